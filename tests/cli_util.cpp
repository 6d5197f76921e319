#include "cli_util.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <thread>

namespace lazyboe::test {

namespace fs = std::filesystem;

long count_lines(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string describe(const CommandResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\n--- stdout:\n" + r.out + "--- stderr:\n" +
         r.err;
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// A failure as the tools promise it: a normal non-zero exit (no signal, no abort, no watchdog
// kill), nothing on stdout, and exactly one line on stderr that contains every one of `needles`.
void expect_one_line_error(const CommandResult& r, const std::vector<std::string>& needles) {
  std::string problems;
  if (r.exit_code == 0) problems += "  exit status 0 (expected failure)\n";
  if (r.exit_code < 0 || r.exit_code >= 124)
    problems += "  exit status looks like a signal, crash or timeout\n";
  if (count_lines(r.err) != 1 || r.err.empty() || r.err.back() != '\n') {
    problems +=
        "  expected exactly one line on stderr, got " + std::to_string(count_lines(r.err)) + "\n";
  }
  if (!r.out.empty()) problems += "  stdout is not empty\n";
  for (const std::string& n : needles) {
    if (!contains(r.err, n)) problems += "  stderr does not mention '" + n + "'\n";
  }
  EXPECT_TRUE(problems.empty()) << problems << describe(r);
}

// A fresh, empty directory under the test's temp dir.
std::string fresh_dir(const std::string& name) {
  const std::string dir = temp_dir() + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> files_in(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// Temporary files of the crash-safe writer ("<path>.tmp.<pid>.<n>").
std::vector<std::string> tmp_files_in(const std::string& dir) {
  std::vector<std::string> out;
  for (const std::string& f : files_in(dir)) {
    if (contains(f, ".tmp.")) out.push_back(f);
  }
  return out;
}

// Every file of a directory with its bytes.
std::map<std::string, std::string> snapshot(const std::string& dir) {
  std::map<std::string, std::string> out;
  for (const std::string& f : files_in(dir)) out[f] = read_file(dir + "/" + f);
  return out;
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr) << path;
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
}

std::string garbage_bytes() {
  std::string s;
  uint32_t x = 12345;
  for (int i = 0; i < 4096; ++i) {
    x = x * 1664525u + 1013904223u;
    s += static_cast<char>(x >> 24);
  }
  return s;
}

void expect_same_edge_arrays(const Bundle& a, const Bundle& b) {
  EXPECT_EQ(a.size(), b.size());
  EXPECT_TRUE(same_array("q0", a.q0, b.q0));
  EXPECT_TRUE(same_array("qf", a.qf, b.qf));
  EXPECT_TRUE(same_array("duration", a.duration, b.duration));
  EXPECT_TRUE(same_array("command_duration", a.command_duration, b.command_duration));
  EXPECT_TRUE(same_array("attempt", a.attempt, b.attempt));
  EXPECT_TRUE(same_array("knot_offset", a.knot_offset, b.knot_offset));
  EXPECT_TRUE(same_array("knots", a.knots, b.knots));
  EXPECT_TRUE(same_array("sample_offset", a.sample_offset, b.sample_offset));
  EXPECT_TRUE(same_array("sample_q", a.sample_q, b.sample_q));
  EXPECT_TRUE(same_array("sample_dq", a.sample_dq, b.sample_dq));
}

void expect_same_perturbation_arrays(const Perturbation& a, const Perturbation& b) {
  EXPECT_TRUE(same_array("perturbation/done", a.done, b.done));
  EXPECT_TRUE(same_array("perturbation/valid", a.valid, b.valid));
  EXPECT_TRUE(same_array("perturbation/lazy", a.lazy, b.lazy));
  EXPECT_TRUE(same_array("perturbation/collision", a.collision, b.collision));
  EXPECT_TRUE(same_array("perturbation/max_error", a.max_error, b.max_error));
  EXPECT_TRUE(same_array("perturbation/p_lazy_prop", a.p_lazy_prop, b.p_lazy_prop));
  EXPECT_TRUE(same_array("perturbation/p_collision", a.p_collision, b.p_collision));
  EXPECT_EQ(a.has_transfer, b.has_transfer);
  EXPECT_TRUE(same_array("perturbation/transfer_lazy", a.transfer_lazy, b.transfer_lazy));
  EXPECT_TRUE(
      same_array("perturbation/transfer_max_error", a.transfer_max_error, b.transfer_max_error));
  EXPECT_TRUE(same_array("perturbation/p_lazy_prop_transfer", a.p_lazy_prop_transfer,
                         b.p_lazy_prop_transfer));
}

::testing::AssertionResult same_bundle_but_timings(const std::string& a_path,
                                                   const std::string& b_path, int timings) {
  const std::string a = read_file(a_path), b = read_file(b_path);
  if (a.size() != b.size())
    return ::testing::AssertionFailure()
           << a_path << ": " << a.size() << " bytes, " << b_path << ": " << b.size();
  std::vector<std::pair<size_t, size_t>> runs;  // differing bytes closer than 8 apart: one run
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i] == b[i]) continue;
    if (!runs.empty() && i - runs.back().second < 8)
      runs.back().second = i;
    else
      runs.emplace_back(i, i);
  }
  if (runs.size() > static_cast<size_t>(2 * timings))
    return ::testing::AssertionFailure() << runs.size() << " runs of differing bytes, more than "
                                         << 2 * timings << "; one at byte " << runs.back().first;
  for (const auto& [first, last] : runs)
    if (last - first >= 8)
      return ::testing::AssertionFailure() << "bytes differ from " << first << " to " << last;
  return ::testing::AssertionSuccess();
}

Background spawn_tool(const std::string& tool_name, const std::vector<std::string>& args,
                      const std::string& log_prefix) {
  Background b;
  b.out_path = log_prefix + ".stdout";
  b.err_path = log_prefix + ".stderr";
  const std::string tool = tool_path(tool_name);
  std::vector<std::string> all = {tool};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, b.out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, 2, b.err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  b.started = std::chrono::steady_clock::now();
  const int rc = posix_spawn(&b.pid, tool.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    ADD_FAILURE() << "posix_spawn " << tool << ": " << std::strerror(rc);
    b.pid = -1;
  }
  return b;
}

int wait_for(Background& b) {
  if (b.pid < 0) return -1000;
  int status = 0;
  while (::waitpid(b.pid, &status, 0) < 0 && errno == EINTR) {
  }
  b.pid = -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return -WTERMSIG(status);
  return -1000;
}

void sleep_seconds(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

}  // namespace lazyboe::test
