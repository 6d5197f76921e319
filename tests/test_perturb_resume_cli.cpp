// lazyboe-perturb interrupted (SIGINT, SIGKILL in the middle of a run) and resumed to the
// uninterrupted result, through the real binaries (helpers: perturb_cli_util.h).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/bundle/perturbation.h"
#include "perturb_cli_util.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// ------------------------------------------------------------------------------------------
// 4. Interruption and resume
// ------------------------------------------------------------------------------------------

constexpr uint64_t kLongEdges = 400, kLongSeed = 23;
// Not representable in 6 significant digits: the hint must give it back exactly.
constexpr double kLongTheta = 0.3141592653589793;
const char* const kLongThetaText = "0.3141592653589793";

std::vector<std::string> long_args(const std::string& path) {
  return {"--bundle", path, "--perturbations", "16", "--theta", kLongThetaText,
          "--seed",   "5",  "--threads",       "2",  "--quiet"};
}

const Bundle& long_reference() {
  return reference(input_bundle(kLongEdges, kLongSeed),
                   {"--perturbations", "16", "--theta", kLongThetaText, "--seed", "5"});
}

// Splits a command line at spaces (the hint's paths have none here).
std::vector<std::string> words_of(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

TEST(PerturbCli, InterruptedRunResumesToTheUninterruptedResult) {
  const std::string& input = input_bundle(kLongEdges, kLongSeed);
  const Bundle original = read_bundle(input);
  const Bundle& straight = long_reference();
  const std::string dir = fresh_dir("sigint");
  const std::string path = dir + "/run.h5";
  copy_bundle(input, path);
  const ino_t inode = inode_of(path);

  std::vector<std::string> args = long_args(path);
  args.insert(args.end(), {"--checkpoint-seconds", "0.5"});
  Background b = spawn_perturb(args, temp_dir() + "/sigint");
  ASSERT_GT(b.pid, 0);
  // A first checkpoint proves that work was done and the signal handlers are installed; then
  // Ctrl-C at once. (A fixed delay raced the whole run on a fast machine: 200 edges took
  // 0.85 s on two cores, so the run is 400 edges, about twice as long as the first checkpoint
  // at 0.5 s, and the signal does not wait.)
  int early_exit = -1000;
  const bool checkpointed = wait_for_checkpoint(b, path, inode, 60, early_exit);
  if (b.pid > 0) ::kill(b.pid, SIGINT);
  const int code = b.pid > 0 ? wait_for(b) : early_exit;
  ASSERT_TRUE(checkpointed) << "no checkpoint before the run ended (exit " << code
                            << "): make the run longer\n"
                            << read_file(b.err_path);
  const std::string err = read_file(b.err_path);
  EXPECT_EQ(code, 130) << err;
  EXPECT_EQ(read_file(b.out_path), "") << "--quiet printed on stdout";
  EXPECT_EQ(count_lines(err), 1) << "expected a one-line hint on stderr:\n" << err;
  EXPECT_TRUE(contains(err, path)) << err;
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));

  // The hint is a command that continues this very analysis.
  {
    const size_t at = err.find("lazyboe-perturb --bundle");
    ASSERT_NE(at, std::string::npos) << "no command to continue in:\n" << err;
    const std::vector<std::string> words = words_of(err.substr(at));
    std::map<std::string, std::string> options;
    for (size_t i = 1; i + 1 < words.size(); i += 2) options[words[i]] = words[i + 1];
    EXPECT_EQ(options["--bundle"], path) << err;
    EXPECT_EQ(options["--perturbations"], "16") << err;
    EXPECT_EQ(options["--seed"], "5") << err;
    const std::string theta = options["--theta"];
    EXPECT_TRUE(theta.empty() || std::strtod(theta.c_str(), nullptr) == kLongTheta)
        << "the hint's --theta " << theta << " is not the theta of the run (" << kLongThetaText
        << "): its command would be refused as another theta\n"
        << err;
  }

  const Bundle partial = read_bundle(path);
  expect_same_edges(partial, original);
  ASSERT_TRUE(partial.perturbation.present);
  EXPECT_FALSE(partial.perturbation.complete);
  EXPECT_TRUE(same_double(partial.perturbation.theta, kLongTheta));
  EXPECT_EQ(partial.perturbation.perturbations, 16u);
  EXPECT_EQ(partial.perturbation.seed, 5u);
  const size_t finished = check_invariants(partial);
  EXPECT_GT(finished, 0u);
  EXPECT_LT(finished, kLongEdges);
  // The edges done so far already hold their final numbers.
  for (size_t e = 0; e < partial.size(); ++e) {
    if (partial.perturbation.done[e] == 0) continue;
    ASSERT_EQ(partial.perturbation.lazy[e], straight.perturbation.lazy[e]) << "edge " << e;
    ASSERT_EQ(partial.perturbation.collision[e], straight.perturbation.collision[e])
        << "edge " << e;
  }

  // The same command again completes it.
  const CommandResult resumed = perturb_tool(args);
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_EQ(resumed.out, "");
  EXPECT_EQ(resumed.err, "");
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
  const Bundle full = read_bundle(path);
  EXPECT_TRUE(full.perturbation.complete);
  EXPECT_EQ(check_invariants(full), kLongEdges);
  expect_same_perturbation(full.perturbation, straight.perturbation);
  expect_same_edges(full, original);
  EXPECT_GE(full.perturbation.wall_seconds, partial.perturbation.wall_seconds)
      << "work time of the first part lost";
}

TEST(PerturbCli, KilledRunLeavesAValidResumableBundle) {
  const std::string& input = input_bundle(kLongEdges, kLongSeed);
  const Bundle original = read_bundle(input);
  const std::string dir = fresh_dir("sigkill");
  const std::string path = dir + "/run.h5";
  copy_bundle(input, path);
  const ino_t inode = inode_of(path);

  std::vector<std::string> args = long_args(path);
  args.insert(args.end(), {"--checkpoint-seconds", "0.2"});
  Background b = spawn_perturb(args, temp_dir() + "/sigkill");
  ASSERT_GT(b.pid, 0);
  const pid_t pid = b.pid;
  int early_exit = -1000;
  const bool checkpointed = wait_for_checkpoint(b, path, inode, 60, early_exit);
  if (b.pid > 0) {
    sleep_seconds(0.5);  // a few more checkpoints: the kill may well land inside one
    ::kill(b.pid, SIGKILL);
  }
  const int code = b.pid > 0 ? wait_for(b) : early_exit;
  ASSERT_TRUE(checkpointed) << "no checkpoint before the run ended (exit " << code << ")\n"
                            << read_file(b.err_path);
  ASSERT_EQ(code, -SIGKILL) << "the run ended before the kill: make it longer\n"
                            << read_file(b.err_path);

  // Only the killed process's own temporary file may remain.
  const std::string own_tmp = "run.h5.tmp." + std::to_string(pid) + ".";
  for (const std::string& f : tmp_files_in(dir)) EXPECT_EQ(f.rfind(own_tmp, 0), 0u) << f;

  // The bundle is the one given (opens, same edges); the work so far is in its checkpoint
  // journal, which applied to it gives a partial analysis.
  Bundle partial = read_bundle(path);  // throws (fails the test) if the kill broke it
  expect_same_edges(partial, original);
  EXPECT_EQ(partial.perturbation.present, original.perturbation.present);
  ASSERT_TRUE(std::filesystem::exists(perturb_journal_path(path)));
  PerturbSettings settings;
  settings.perturbations = 16;
  settings.theta = kLongTheta;
  settings.seed = 5;
  prepare_perturbation(partial, settings, false, path);
  {
    PerturbCheckpoints journal(path);
    ASSERT_TRUE(journal.resume(partial, settings).applied);
  }
  EXPECT_FALSE(partial.perturbation.complete);
  const size_t finished = check_invariants(partial);
  EXPECT_GT(finished, 0u);
  EXPECT_LT(finished, kLongEdges);

  const CommandResult resumed = perturb_tool(args);  // the same command again
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  const Bundle full = read_bundle(path);
  EXPECT_TRUE(full.perturbation.complete);
  expect_same_perturbation(full.perturbation, long_reference().perturbation);
  expect_same_edges(full, original);
}

}  // namespace
}  // namespace lazyboe::test
