#include "lazyboe/common/journal.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>

#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"

namespace lazyboe {
namespace {

constexpr char kMagic[8] = {'L', 'Z', 'B', 'J', 'R', 'N', 'L', '1'};
constexpr size_t kRecordHeader = 16;

std::string last_error() { return std::strerror(errno); }

uint64_t record_checksum(uint64_t length, const char* payload) {
  Fnv1a64 h;
  h.update(&length, sizeof length);
  h.update(payload, length);
  return h.value();
}

std::string framed(const std::string& payload) {
  std::string r(kRecordHeader, '\0');
  const uint64_t length = payload.size();
  const uint64_t sum = record_checksum(length, payload.data());
  std::memcpy(&r[0], &length, 8);
  std::memcpy(&r[8], &sum, 8);
  r += payload;
  return r;
}

void write_fully(int fd, const char* p, size_t n, const std::string& path) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) fail(path, "cannot write: " + (w < 0 ? last_error() : "nothing written"));
    p += w;
    n -= static_cast<size_t>(w);
  }
}

void sync_fd(int fd, const std::string& path) {
  if (::fdatasync(fd) != 0) fail(path, "cannot sync to disk: " + last_error());
}

void sync_directory_of(const std::string& path) {
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;  // best effort, as AtomicFile
  ::fsync(fd);
  ::close(fd);
}

int open_locked(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC, 0644);
  if (fd < 0) fail(path, "cannot write: " + last_error());
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    if (err == EWOULDBLOCK)
      fail(path, "another process is writing this checkpoint journal (it is locked)");
    fail(path, "cannot lock: " + std::string(std::strerror(err)));
  }
  return fd;
}

// ---- the crash hook ----

struct CrashSetting {
  std::string point;
  long at = 0;
  long calls = 0;
};

CrashSetting& crash_setting() {
  static CrashSetting s = [] {
    CrashSetting c;
    const char* v = std::getenv("LAZYBOE_TEST_CRASH_AT");
    if (!v) return c;
    const std::string text = v;
    const size_t colon = text.rfind(':');
    if (colon == std::string::npos) return c;
    c.point = text.substr(0, colon);
    c.at = std::atol(text.c_str() + colon + 1);
    return c;
  }();
  return s;
}

}  // namespace

bool crash_requested(const char* point) {
  CrashSetting& s = crash_setting();
  if (s.at <= 0 || s.point != point) return false;
  return ++s.calls == s.at;
}

void crash_point(const char* point) {
  if (crash_requested(point)) ::raise(SIGKILL);
}

JournalContents read_journal(const std::string& path) {
  JournalContents c;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return c;
  c.exists = true;
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot read: " + last_error());
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) {
    c.ignored_bytes = bytes.size();
    return c;
  }
  c.valid_start = true;
  size_t pos = sizeof kMagic;
  while (bytes.size() - pos >= kRecordHeader) {
    uint64_t length = 0, sum = 0;
    std::memcpy(&length, bytes.data() + pos, 8);
    std::memcpy(&sum, bytes.data() + pos + 8, 8);
    if (length > bytes.size() - pos - kRecordHeader) break;
    const char* payload = bytes.data() + pos + kRecordHeader;
    if (record_checksum(length, payload) != sum) break;
    c.records.emplace_back(payload, length);
    pos += kRecordHeader + length;
  }
  c.valid_bytes = pos;
  c.ignored_bytes = bytes.size() - pos;
  return c;
}

JournalWriter::~JournalWriter() { close(); }

JournalWriter::JournalWriter(JournalWriter&& o) noexcept
    : path_(std::move(o.path_)), fd_(std::exchange(o.fd_, -1)), size_(o.size_) {}

JournalWriter& JournalWriter::operator=(JournalWriter&& o) noexcept {
  if (this != &o) {
    close();
    path_ = std::move(o.path_);
    fd_ = std::exchange(o.fd_, -1);
    size_ = o.size_;
  }
  return *this;
}

void JournalWriter::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

JournalWriter JournalWriter::create(const std::string& path, const std::string& first) {
  JournalWriter w;
  w.path_ = path;
  // Not O_TRUNC before the lock: truncating another writer's journal is what the lock prevents.
  w.fd_ = open_locked(path, O_WRONLY | O_CREAT);
  if (::ftruncate(w.fd_, 0) != 0) fail(path, "cannot write: " + last_error());
  std::string head(kMagic, sizeof kMagic);
  head += framed(first);
  write_fully(w.fd_, head.data(), head.size(), path);
  sync_fd(w.fd_, path);
  sync_directory_of(path);
  w.size_ = head.size();
  return w;
}

JournalWriter JournalWriter::reopen(const std::string& path, uint64_t valid_bytes) {
  JournalWriter w;
  w.path_ = path;
  w.fd_ = open_locked(path, O_WRONLY);
  if (::ftruncate(w.fd_, static_cast<off_t>(valid_bytes)) != 0 ||
      ::lseek(w.fd_, static_cast<off_t>(valid_bytes), SEEK_SET) < 0)
    fail(path, "cannot write: " + last_error());
  sync_fd(w.fd_, path);
  w.size_ = valid_bytes;
  return w;
}

void JournalWriter::append(const std::string& payload) {
  if (fd_ < 0) fail(path_, "the checkpoint journal is not open");
  const std::string record = framed(payload);
  if (crash_requested("journal-torn")) {
    write_fully(fd_, record.data(), record.size() / 2, path_);
    ::fdatasync(fd_);
    ::raise(SIGKILL);
  }
  try {
    write_fully(fd_, record.data(), record.size(), path_);
    crash_point("journal-unsynced");
    sync_fd(fd_, path_);
  } catch (const Error&) {
    // A partial record would be ignored by readers anyway; cut it off so the next one follows
    // the last whole record.
    if (::ftruncate(fd_, static_cast<off_t>(size_)) == 0)
      ::lseek(fd_, static_cast<off_t>(size_), SEEK_SET);
    throw;
  }
  size_ += record.size();
  crash_point("journal-synced");
}

void JournalWriter::remove() {
  close();
  if (!path_.empty()) ::unlink(path_.c_str());
  sync_directory_of(path_);
}

}  // namespace lazyboe
