// A file written all at once or not at all: the content goes to "<path>.tmp.<pid>.<n>" in the same
// directory, and commit() renames it over `path`. Until then `path` keeps its old content (or
// stays absent); a writer that throws or returns early leaves no temporary file behind (only a
// killed process may).
#pragma once

#include <fstream>
#include <ostream>
#include <string>

namespace lazyboe {

// The temporary name the next AtomicFile made in this process will write `path` under (while no
// other thread makes one): for tests that put something in its way.
std::string next_temporary_name(const std::string& path);

class AtomicFile {
 public:
  // Stream: the content is written to stream(). External: a writer opens temp_path() itself
  // (HDF5) and has closed it before commit().
  enum class Writer { Stream, External };

  // Throws Error("<path>: cannot write: <reason>") when the temporary file cannot be created.
  explicit AtomicFile(const std::string& path, Writer writer = Writer::Stream);
  ~AtomicFile();  // removes the temporary file unless committed
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Writer::Stream only. Flushing it (e.g. after each line) makes the lines so far durable in
  // the temporary file, not visible at `path`.
  std::ostream& stream() { return out_; }
  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

  // Writer::External: writes `bytes` bytes as the whole temporary file. A short write (a full
  // disk, a file-size limit) throws Error("<path>: cannot write: <reason>") and removes it.
  void write_all(const void* data, size_t bytes);

  // Flushes, fsyncs and renames the temporary file over `path`, then fsyncs the directory
  // (best effort: the new file is in place already). On failure removes the temporary file,
  // leaves `path` untouched and throws Error naming `path`.
  void commit();

 private:
  std::string path_, temp_path_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace lazyboe
