#include "lazyboe/common/file_checks.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "lazyboe/common/error.h"

namespace lazyboe {

void require_input_file(const std::string& path, const std::string& what) {
  const std::string where = what.empty() ? path : path + " (" + what + ")";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    fail(where, std::string("cannot open: ") + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) fail(where, "is a directory, not a file");
  if (::access(path.c_str(), R_OK) != 0)
    fail(where, std::string("cannot open: ") + std::strerror(errno));
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

void refuse_output_as_input(const NamedPath& out, const std::vector<NamedPath>& inputs) {
  if (out.path.empty() || out.path == "-") return;
  for (const NamedPath& in : inputs) {
    if (in.path.empty() || in.path == "-") continue;
    if (same_file(out.path, in.path))
      fail(out.option + " " + out.path,
           "is the same file as the input " + in.option + " " + in.path +
               ": an output never replaces an input (choose another output path)");
  }
}

std::string resolve_bundled_file(const std::string& path, const std::string& dir,
                                 const std::string& kind) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty() || fs::exists(path, ec)) return path;
  const fs::path given(path);
  // The docs' paths ("data/environments/shelf.json"), run from another folder than the source
  // tree's: the same file of the bundled data (`dir`'s parent is the data folder).
  if (given.is_relative() && !given.empty() && *given.begin() == "data") {
    const fs::path in_data = fs::path(dir).parent_path() / given.lexically_relative("data");
    if (fs::exists(in_data, ec)) return in_data.string();
  }
  if (given.has_parent_path() || given.has_extension()) return path;
  const fs::path bundled = fs::path(dir) / (path + ".json");
  if (fs::exists(bundled, ec)) return bundled.string();
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().extension() == ".json") found.push_back(entry.path().stem().string());
  std::sort(found.begin(), found.end());
  std::string names;
  for (const std::string& name : found) names += (names.empty() ? "" : ", ") + name;
  fail(path, "no such file, nor a bundled " + kind + " of that name (" +
                 (names.empty() ? "none found in " + dir : names) + ")");
}

}  // namespace lazyboe
