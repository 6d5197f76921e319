// AtomicFile: commit replaces the file; a writer that throws or never commits leaves the old
// file and no temporary file; a directory that cannot be written gives one clear Error.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed afterwards.
class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("lazyboe_atomic_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
    return names;
  }
  fs::path dir_;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST_F(AtomicFileTest, TemporaryNameIsPathDotTmpDotPidDotWriter) {
  AtomicFile file(path("out.txt"));
  EXPECT_EQ(file.path(), path("out.txt"));
  const std::string prefix = path("out.txt") + ".tmp." + std::to_string(::getpid()) + ".";
  EXPECT_EQ(file.temp_path().rfind(prefix, 0), 0u) << file.temp_path();
  EXPECT_TRUE(fs::exists(file.temp_path()));
}

TEST_F(AtomicFileTest, TwoWritersOfOnePathHaveTheirOwnTemporaries) {
  AtomicFile first(path("out.txt")), second(path("out.txt"));
  EXPECT_NE(first.temp_path(), second.temp_path());
  first.stream() << "first\n";
  second.stream() << "second\n";
  first.commit();
  EXPECT_EQ(read_text(path("out.txt")), "first\n");
  second.commit();  // its content is its own, not the first's
  EXPECT_EQ(read_text(path("out.txt")), "second\n");
}

TEST_F(AtomicFileTest, CommitReplacesTheFile) {
  write_text(path("out.txt"), "old\n");
  {
    AtomicFile file(path("out.txt"));
    file.stream() << "line 1\n" << std::flush;
    EXPECT_EQ(read_text(path("out.txt")), "old\n");  // not visible before commit
    file.stream() << "line 2\n";
    file.commit();
  }
  EXPECT_EQ(read_text(path("out.txt")), "line 1\nline 2\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"out.txt"});
}

TEST_F(AtomicFileTest, CommitCreatesAMissingFile) {
  AtomicFile file(path("new.txt"));
  file.stream() << "x";
  file.commit();
  EXPECT_EQ(read_text(path("new.txt")), "x");
  EXPECT_EQ(entries(), std::vector<std::string>{"new.txt"});
}

TEST_F(AtomicFileTest, UncommittedWriterLeavesTheOldFileAndNoTemporary) {
  write_text(path("out.txt"), "old\n");
  {
    AtomicFile file(path("out.txt"));
    file.stream() << "partial";
  }
  EXPECT_EQ(read_text(path("out.txt")), "old\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"out.txt"});
}

TEST_F(AtomicFileTest, ThrowingWriterLeavesTheOldFileAndNoTemporary) {
  write_text(path("out.txt"), "old\n");
  EXPECT_THROW(
      {
        AtomicFile file(path("out.txt"));
        file.stream() << "partial" << std::flush;
        throw std::runtime_error("writer failed");
      },
      std::runtime_error);
  EXPECT_EQ(read_text(path("out.txt")), "old\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"out.txt"});
}

// A writer that opens the temporary file itself (as HDF5 does).
TEST_F(AtomicFileTest, ExternalWriterCommitsAndCleansUp) {
  {
    AtomicFile file(path("ext.bin"), AtomicFile::Writer::External);
    EXPECT_FALSE(fs::exists(file.temp_path()));
    write_text(file.temp_path(), "data");
    file.commit();
  }
  EXPECT_EQ(read_text(path("ext.bin")), "data");
  {
    AtomicFile file(path("ext.bin"), AtomicFile::Writer::External);
    write_text(file.temp_path(), "partial");
  }
  EXPECT_EQ(read_text(path("ext.bin")), "data");
  EXPECT_EQ(entries(), std::vector<std::string>{"ext.bin"});
}

TEST_F(AtomicFileTest, ExternalWriterThatWroteNothingCannotCommit) {
  AtomicFile file(path("ext.bin"), AtomicFile::Writer::External);
  const std::string e = error_of([&] { file.commit(); });
  EXPECT_EQ(e.rfind(file.temp_path() + ": cannot open to sync: ", 0), 0u) << e;
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFileTest, MissingDirectoryIsOneClearError) {
  const std::string target = path("no/such/dir/out.txt");
  EXPECT_EQ(error_of([&] { AtomicFile file(target); }),
            target + ": cannot write: No such file or directory");
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFileTest, DirectoryThatIsAFileIsOneClearError) {
  write_text(path("plain"), "");
  const std::string target = path("plain/out.txt");
  EXPECT_EQ(error_of([&] { AtomicFile file(target); }), target + ": cannot write: Not a directory");
}

TEST_F(AtomicFileTest, ReadOnlyDirectoryIsOneClearError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into read-only directories";
  write_text(path("out.txt"), "old\n");
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
  const std::string target = path("out.txt");
  EXPECT_EQ(error_of([&] { AtomicFile file(target); }),
            target + ": cannot write: Permission denied");
  fs::permissions(dir_, fs::perms::owner_all);
  EXPECT_EQ(read_text(target), "old\n");
}

}  // namespace
}  // namespace lazyboe
