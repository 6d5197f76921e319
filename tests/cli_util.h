// Helpers shared by the command-line tests: running tools, one-line error checks, comparing
// directories before and after a refused run, bit-exact array comparison.
#pragma once

#include <gtest/gtest.h>
#include <sys/types.h>

#include <chrono>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "test_util.h"

namespace lazyboe::test {

long count_lines(const std::string& s);
std::string quote(const std::string& s);

std::string describe(const CommandResult& r);

bool contains(const std::string& haystack, const std::string& needle);

std::string join(const std::vector<std::string>& v);

// A failure as the tools promise it: a normal non-zero exit (no signal, no abort, no watchdog
// kill), nothing on stdout, and exactly one line on stderr that contains every one of `needles`.
void expect_one_line_error(const CommandResult& r, const std::vector<std::string>& needles);

// Two bundle files of the same work differ only in their `timings` wall_seconds attributes (the
// root's, /perturbation's): each is 8 bytes plus the 4-byte checksum of the HDF5 object header
// holding it, so at most 2 * timings runs of differing bytes, each shorter than 8 bytes
// (schemas/bundle.md, "Same bundle, same bytes").
::testing::AssertionResult same_bundle_but_timings(const std::string& a_path,
                                                   const std::string& b_path, int timings);

// A fresh, empty directory under the test's temp dir.
std::string fresh_dir(const std::string& name);

std::vector<std::string> files_in(const std::string& dir);

// Temporary files of the crash-safe writer ("<path>.tmp.<pid>.<n>").
std::vector<std::string> tmp_files_in(const std::string& dir);

// Every file of a directory with its bytes.
std::map<std::string, std::string> snapshot(const std::string& dir);

void write_bytes(const std::string& path, const std::string& bytes);

std::string garbage_bytes();

// A tool running in the background (for signals), its stdin from /dev/null, stdout and stderr to
// files.
struct Background {
  pid_t pid = -1;
  std::string out_path, err_path;  // <log_prefix>.stdout, .stderr
  std::chrono::steady_clock::time_point started;
};
// Starts build/bin/<tool> with `args`; a failure to start fails the test (pid -1).
Background spawn_tool(const std::string& tool, const std::vector<std::string>& args,
                      const std::string& log_prefix);
// Waits for the process; the exit status, or -signal when it was killed by a signal.
int wait_for(Background& b);
void sleep_seconds(double s);

// Bit-for-bit equality of two arrays, reporting the first difference.
template <typename T>
::testing::AssertionResult same_array(const std::string& name, const std::vector<T>& a,
                                      const std::vector<T>& b) {
  if (a.size() != b.size()) {
    return ::testing::AssertionFailure()
           << name << ": " << a.size() << " vs " << b.size() << " values";
  }
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0) {
      std::ostringstream o;
      o.precision(17);
      o << name << ": first difference at element " << i << " of " << a.size() << ": " << a[i]
        << " vs " << b[i];
      return ::testing::AssertionFailure() << o.str();
    }
  }
  return ::testing::AssertionSuccess();
}

// The edge count and every per-edge array of the two bundles are identical, bit for bit.
void expect_same_edge_arrays(const Bundle& a, const Bundle& b);

// Every per-edge dataset of the two perturbation analyses is identical, bit for bit (the
// transfer statistics too, and whether they are there).
void expect_same_perturbation_arrays(const Perturbation& a, const Perturbation& b);

}  // namespace lazyboe::test
