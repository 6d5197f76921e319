#include "lazyboe/common/data_dir.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

namespace lazyboe {
namespace {

// An installed copy of the data beside the binary this code was linked into: <prefix>/share/
// lazyboe above <prefix>/bin/<tool> or <prefix>/lib/python3.X/dist-packages/lazyboe/<module>.
std::string installed_beside_binary() {
  std::vector<std::filesystem::path> binaries;
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&installed_beside_binary), &info) && info.dli_fname)
    binaries.emplace_back(info.dli_fname);
  binaries.emplace_back("/proc/self/exe");  // dli_fname of the main program may be argv[0]
  for (const std::filesystem::path& binary : binaries) {
    std::error_code error;
    const std::filesystem::path dir = std::filesystem::canonical(binary, error).parent_path();
    if (error) continue;
    std::filesystem::path prefix;  // of the two installed layouts, else none
    const std::string packages = dir.parent_path().filename().string();
    if (dir.filename() == "bin") {
      prefix = dir.parent_path();
    } else if (dir.filename() == "lazyboe" &&
               (packages == "dist-packages" || packages == "site-packages")) {
      prefix = dir.parent_path().parent_path().parent_path().parent_path();
    }
    const std::filesystem::path data = prefix / "share" / "lazyboe";
    if (!prefix.empty() && std::filesystem::is_regular_file(data / "robots" / "panda.json", error))
      return data;
  }
  return "";
}

std::string find_data_dir() {
  if (std::string beside = installed_beside_binary(); !beside.empty()) return beside;
  std::error_code error;
  if (std::filesystem::is_directory(LAZYBOE_DATA_DIR, error)) return LAZYBOE_DATA_DIR;
  return LAZYBOE_INSTALLED_DATA_DIR;
}

}  // namespace

std::string data_dir() {
  if (const char* env = std::getenv("LAZYBOE_DATA_DIR"); env && *env) return env;
  static const std::string found = find_data_dir();
  return found;
}

}  // namespace lazyboe
