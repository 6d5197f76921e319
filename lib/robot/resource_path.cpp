#include "lazyboe/robot/resource_path.h"

#include <cstdlib>
#include <filesystem>

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;

bool is_folder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

// The package's folder under `dir`, or empty: dir/NAME, dir itself when it is NAME, or
// dir/*/NAME (a workspace's src folder holding repositories of packages).
fs::path package_folder(const fs::path& dir, const std::string& name) {
  if (is_folder(dir / name)) return dir / name;
  if (dir.filename() == name && is_folder(dir)) return dir;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (is_folder(it->path() / name)) return it->path() / name;
  }
  return {};
}

std::string joined(const std::vector<std::string>& dirs) {
  std::string text;
  for (const std::string& d : dirs) text += (text.empty() ? "" : ", ") + d;
  return text.empty() ? "no folder given" : text;
}

}  // namespace

std::vector<std::string> split_path_list(const std::string& list) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t end = std::min(list.find(':', start), list.size());
    if (end > start) parts.push_back(list.substr(start, end - start));
    start = end + 1;
  }
  return parts;
}

std::vector<std::string> package_search_path(const std::vector<std::string>& configured) {
  std::vector<std::string> search = configured;
  if (const char* ros = std::getenv("ROS_PACKAGE_PATH"); ros && *ros) {
    for (const std::string& dir : split_path_list(ros)) search.push_back(dir);
  }
  return search;
}

std::string resolve_urdf_resource(const std::string& uri, const std::string& urdf_path,
                                  const std::vector<std::string>& search,
                                  const std::string& where) {
  const std::string package_scheme = "package://", file_scheme = "file://";
  if (uri.rfind(package_scheme, 0) == 0) {
    const std::string rest = uri.substr(package_scheme.size());
    const size_t slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    if (name.empty() || slash == std::string::npos) fail(where, "'" + uri + "' names no file");
    for (const std::string& dir : search) {
      const fs::path folder = package_folder(dir, name);
      if (!folder.empty()) return (folder / rest.substr(slash + 1)).lexically_normal().string();
    }
    fail(where, "package '" + name + "' of '" + uri + "' is in none of the package folders (" +
                    joined(search) +
                    "): add the folder that holds it to the robot config's package_path or "
                    "to ROS_PACKAGE_PATH");
  }
  if (uri.rfind(file_scheme, 0) == 0) return uri.substr(file_scheme.size());
  if (uri.find("://") != std::string::npos) {
    fail(where, "'" + uri + "': only package://, file:// and plain paths are read");
  }
  const fs::path path(uri);
  if (path.is_absolute()) return uri;
  return (fs::path(urdf_path).parent_path() / path).lexically_normal().string();
}

}  // namespace lazyboe
