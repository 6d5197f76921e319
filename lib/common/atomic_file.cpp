#include "lazyboe/common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
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

// "<path>.tmp.<pid>.<n>": n counts the writers of this process, so two writers of one path
// (two threads, two sessions) never share a temporary.
std::atomic<uint64_t> writers{0};

std::string temporary_name(const std::string& path, uint64_t writer) {
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(writer);
}

}  // namespace

std::string next_temporary_name(const std::string& path) {
  return temporary_name(path, writers.load());
}

AtomicFile::AtomicFile(const std::string& path, Writer writer)
    : path_(path), temp_path_(temporary_name(path, writers++)) {
  // Said now, not after all the work when the rename fails.
  std::error_code error;  // an unreadable path is refused by the open or the rename, clearly
  if (std::filesystem::is_directory(path_, error))
    fail(path_, "cannot write: is a directory, not a file");
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

void AtomicFile::write_all(const void* data, size_t bytes) {
  const int fd = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail(path_, "cannot write: " + last_error());
  const char* p = static_cast<const char*>(data);
  size_t left = bytes;
  while (left > 0) {
    const ssize_t n = ::write(fd, p, std::min<size_t>(left, size_t{1} << 30));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string reason = n < 0 ? last_error() : "nothing written";
      ::close(fd);
      ::unlink(temp_path_.c_str());
      fail(path_, "cannot write: " + reason + " (" + std::to_string(bytes) + " bytes to write, " +
                      std::to_string(bytes - left) + " written)");
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::close(fd) != 0) {
    const std::string reason = last_error();
    ::unlink(temp_path_.c_str());
    fail(path_, "cannot write: " + reason);
  }
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
