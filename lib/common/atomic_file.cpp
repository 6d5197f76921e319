#include "lazyboe/common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

std::string last_error() { return std::strerror(errno); }

// fsync by path: an std::ofstream does not expose its descriptor, and fsync applies to the
// file, whichever descriptor names it.
void fsync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDWR);
  if (fd < 0) fail(path, "cannot open to sync: " + last_error());
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) fail(path, "cannot sync to disk: " + std::string(std::strerror(err)));
}

}  // namespace

AtomicFile::AtomicFile(const std::string& path, Writer writer)
    : path_(path), temp_path_(path + ".tmp." + std::to_string(::getpid())) {
  if (writer == Writer::External) return;
  errno = 0;
  out_.open(temp_path_, std::ios::out | std::ios::trunc);
  if (!out_) fail(path_, "cannot write: " + (errno ? last_error() : "cannot create " + temp_path_));
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (out_.is_open()) out_.close();
  ::unlink(temp_path_.c_str());
}

void AtomicFile::commit() {
  try {
    if (out_.is_open()) {
      out_.flush();
      out_.close();
      if (!out_) fail(path_, "cannot write: " + last_error());
    }
    fsync_path(temp_path_, false);
    if (std::rename(temp_path_.c_str(), path_.c_str()) != 0)
      fail(path_, "cannot rename " + temp_path_ + " into place: " + last_error());
  } catch (const Error&) {
    ::unlink(temp_path_.c_str());
    throw;
  }
  committed_ = true;
  const std::string dir = std::filesystem::path(path_).parent_path().string();
  try {
    fsync_path(dir.empty() ? "." : dir, true);
  } catch (const Error&) {
  }
}

}  // namespace lazyboe
