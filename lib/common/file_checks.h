// Checks on the files a tool is given: an input must be a readable regular file (a directory
// is named as one, not misread as an empty or invalid file), and an output must never be one of
// the inputs (compared by the file they are, after symlinks, not by spelling).
#pragma once

#include <string>
#include <vector>

namespace lazyboe {

// Throws Error("<path>: cannot open: No such file or directory"), "<path>: is a directory, not
// a file" and the like; `what` ("URDF file", "queries") is added to the message when given.
void require_input_file(const std::string& path, const std::string& what = "");

// Whether two paths name the same existing file (same device and inode: symlinks, hard links
// and different spellings included). False when either does not exist.
bool same_file(const std::string& a, const std::string& b);

// An input named by the option it came from.
struct NamedPath {
  std::string option;  // "--bundle"
  std::string path;
};

// Throws Error("<out_option> <out>: is also the input <option> (...): an output never replaces
// an input") when `out` is the same file as one of `inputs`. "-" (standard output or input) and
// empty paths are skipped.
void refuse_output_as_input(const NamedPath& out, const std::vector<NamedPath>& inputs);

// `path` as given when it exists, or is a path or a file name (it has a folder or an
// extension: never silently another file); a bare name ("shelf") names the bundled
// `dir`/<name>.json; a relative path under "data/" that is not there names the same file of the
// bundled data (`dir`'s parent), so that the docs' paths work from any folder. Throws Error naming
// `path`, what it is not (`kind`: "scene", "robot") and the bundled names, when there is none of
// that name.
std::string resolve_bundled_file(const std::string& path, const std::string& dir,
                                 const std::string& kind);

}  // namespace lazyboe
