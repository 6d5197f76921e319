#include "lazyboe/common/file_checks.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

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

}  // namespace lazyboe
