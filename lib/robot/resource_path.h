// The files a URDF names (collision meshes): ROS's `package://NAME/...` URIs resolved through a
// package path, `file://` URIs, and paths relative to the URDF's folder.
#pragma once

#include <string>
#include <vector>

namespace lazyboe {

// The folders searched for `package://NAME/...`: `configured` (the robot config's package_path)
// first, then ROS_PACKAGE_PATH's entries when it is set.
std::vector<std::string> package_search_path(const std::vector<std::string>& configured);

// "a:b:c" -> {"a", "b", "c"} (empty entries dropped).
std::vector<std::string> split_path_list(const std::string& list);

// The file `uri` names: for package://NAME/rest, DIR/NAME/rest for the first DIR of `search`
// that holds a folder NAME (or is itself named NAME, or holds one folder with NAME inside);
// file:///abs -> /abs; anything else relative to `urdf_path`'s folder. Throws Error(`where`:
// ...) for a package on none of the folders (listing them) and for a URI scheme it cannot read
// (http://...). Whether the file exists is the reader's check.
std::string resolve_urdf_resource(const std::string& uri, const std::string& urdf_path,
                                  const std::vector<std::string>& search, const std::string& where);

}  // namespace lazyboe
