// An append-only journal of checksummed records, for incremental crash-safe checkpoints.
//
// File: the 8 bytes "LZBJRNL1", then records, each [u64 payload length][u64 FNV-1a 64 of the
// length's 8 bytes and the payload][payload] (little-endian). A record is appended with one
// write() and made durable with fdatasync() before append() returns. A process killed at any
// moment leaves a prefix of whole records, possibly followed by a torn record (short, or
// whose checksum does not match): readers stop at the first such record and ignore the rest,
// and a writer that reopens the journal cuts it off before appending.
//
// One writer at a time: the writer holds an exclusive flock() on the file, so a second process
// appending to the same journal is refused with one line instead of interleaving records.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace lazyboe {

struct JournalContents {
  bool exists = false;
  bool valid_start = false;          // begins with the magic bytes
  std::vector<std::string> records;  // the whole records, in order
  uint64_t valid_bytes = 0;          // length of the prefix of whole records
  uint64_t ignored_bytes = 0;        // a torn or damaged tail after them
};

// Reads every whole record (a missing file: exists false). Throws Error only when the file
// exists but cannot be read.
JournalContents read_journal(const std::string& path);

class JournalWriter {
 public:
  JournalWriter() = default;
  ~JournalWriter();
  JournalWriter(JournalWriter&& other) noexcept;
  JournalWriter& operator=(JournalWriter&& other) noexcept;
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;

  // Creates the journal afresh (replacing any file there) with `first` as its first record,
  // durable (and the directory entry too) on return.
  static JournalWriter create(const std::string& path, const std::string& first);
  // Reopens an existing journal to append after its first `valid_bytes` bytes (cutting off a
  // torn tail), as read_journal found them.
  static JournalWriter reopen(const std::string& path, uint64_t valid_bytes);

  // Appends one record, durable on return. Throws Error("<path>: cannot write: ...") on a full
  // disk or any other failure; the journal then still holds every earlier record.
  void append(const std::string& payload);
  // Closes and deletes the journal (after the final file is in place).
  void remove();
  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  uint64_t bytes() const { return size_; }

 private:
  void close();
  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

// Test hook for crash tests: when the environment variable LAZYBOE_TEST_CRASH_AT is
// "<point>:<n>", the n-th call (from 1) of crash_point("<point>") kills the process with
// SIGKILL, as kill -9 would. Costs one comparison when the variable is unset.
void crash_point(const char* point);
// The same, for journal appends: "journal-torn:<n>" writes half of the n-th record and dies.
bool crash_requested(const char* point);

}  // namespace lazyboe
