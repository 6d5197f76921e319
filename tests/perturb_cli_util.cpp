// Helpers of the lazyboe-perturb command-line tests (test_perturb_cli, test_perturb_resume_cli).
#include "perturb_cli_util.h"

#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"

namespace lazyboe::test {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// ------------------------------------------------------------------------------------------
// Running the tools
// ------------------------------------------------------------------------------------------

// The shell command line of a tool with the given arguments (each shell-quoted), under a
// watchdog that kills a run that does not end (a hang fails the test instead of stalling it).
std::string tool_command(const std::string& tool, const std::vector<std::string>& args,
                         double timeout_seconds) {
  std::string cmd = watchdog(timeout_seconds) + quote(tool_path(tool));
  for (const std::string& a : args) cmd += " " + quote(a);
  return cmd;
}

CommandResult perturb_tool(const std::vector<std::string>& args, double timeout_seconds) {
  return run(tool_command("lazyboe-perturb", args, timeout_seconds));
}

// The same, run inside `dir` (anything written by mistake to a relative path lands there).
CommandResult perturb_tool_in(const std::string& dir, const std::vector<std::string>& args,
                              double timeout_seconds) {
  return run("cd " + quote(dir) + " && " + tool_command("lazyboe-perturb", args, timeout_seconds));
}

CommandResult build_tool(const std::vector<std::string>& args, double timeout_seconds) {
  return run(tool_command("lazyboe-build", args, timeout_seconds));
}

std::string env_file(const std::string& name) { return source_path("data/environments/" + name); }

// ---- A run in the background, for signals -------------------------------------------------

Background spawn_perturb(const std::vector<std::string>& args, const std::string& log_prefix) {
  return spawn_tool("lazyboe-perturb", args, log_prefix);
}

// The file's identity: a checkpoint renames a new file over it, which changes the inode.
ino_t inode_of(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? st.st_ino : 0;
}

// Waits until the bundle at `path` has been replaced by a checkpoint (its inode changes) while
// the process still runs. False when the process ended first (it is then reaped: b.pid = -1,
// `exit_code` set) or after the timeout.
bool wait_for_checkpoint(Background& b, const std::string& path, ino_t before,
                         double timeout_seconds, int& exit_code) {
  const auto until = Clock::now() + std::chrono::duration<double>(timeout_seconds * time_scale());
  while (Clock::now() < until) {
    int status = 0;
    if (::waitpid(b.pid, &status, WNOHANG) == b.pid) {
      b.pid = -1;
      exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
      return false;
    }
    // A checkpoint: the journal beside the bundle (incremental checkpoints), or a rewritten
    // bundle (the last save).
    const ino_t now = inode_of(path);
    if ((now != 0 && now != before) || std::filesystem::exists(perturb_journal_path(path)))
      return true;
    sleep_seconds(0.01);
  }
  return false;
}

// ------------------------------------------------------------------------------------------
// Comparing bundles
// ------------------------------------------------------------------------------------------

bool same_double(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every edge dataset of the two bundles is identical, and so is the header (all but
// wall_seconds and tool_version).
void expect_same_edges(const Bundle& a, const Bundle& b) {
  expect_same_edge_arrays(a, b);
  const BundleHeader &x = a.header, &y = b.header;
  EXPECT_EQ(x.complete, y.complete);
  EXPECT_EQ(x.robot_config, y.robot_config);
  EXPECT_EQ(x.robot_hash, y.robot_hash);
  EXPECT_EQ(x.env_file, y.env_file);
  EXPECT_EQ(x.env_hash, y.env_hash);
  EXPECT_EQ(x.seed, y.seed);
  EXPECT_EQ(x.target_edges, y.target_edges);
  EXPECT_EQ(x.attempts, y.attempts);
  EXPECT_EQ(x.valid, y.valid);
  EXPECT_EQ(x.rejected, y.rejected);
  EXPECT_TRUE(same_double(x.design_theta, y.design_theta));
  EXPECT_TRUE(same_double(x.simulated_seconds, y.simulated_seconds));
  EXPECT_TRUE(same_double(x.wall_seconds, y.wall_seconds))
      << "the build's wall_seconds was changed";
}

// The two analyses hold the same numbers: settings and every per-edge dataset bit for bit.
// simulated_seconds is a sum whose order depends on how the work was split: close, not equal.
// With `work` also the bookkeeping attributes must be identical (an untouched analysis).
void expect_same_perturbation(const Perturbation& a, const Perturbation& b, bool work) {
  EXPECT_EQ(a.present, b.present);
  EXPECT_EQ(a.complete, b.complete);
  EXPECT_TRUE(same_double(a.theta, b.theta)) << a.theta << " vs " << b.theta;
  EXPECT_EQ(a.perturbations, b.perturbations);
  EXPECT_EQ(a.seed, b.seed);
  expect_same_perturbation_arrays(a, b);
  EXPECT_NEAR(a.simulated_seconds, b.simulated_seconds,
              1e-9 * std::max(1.0, std::abs(b.simulated_seconds)));
  if (work) {
    EXPECT_TRUE(same_double(a.simulated_seconds, b.simulated_seconds));
    EXPECT_TRUE(same_double(a.wall_seconds, b.wall_seconds))
        << a.wall_seconds << " vs " << b.wall_seconds;
  }
}

// The per-edge invariants of an analysis, finished or not. Returns the number of edges done.
size_t check_invariants(const Bundle& b) {
  const Perturbation& p = b.perturbation;
  const size_t N = b.size();
  EXPECT_TRUE(p.present);
  EXPECT_EQ(p.done.size(), N);
  EXPECT_EQ(p.valid.size(), N);
  EXPECT_EQ(p.lazy.size(), N);
  EXPECT_EQ(p.collision.size(), N);
  EXPECT_EQ(p.max_error.size(), N);
  EXPECT_EQ(p.p_lazy_prop.size(), N);
  EXPECT_EQ(p.p_collision.size(), N);
  EXPECT_TRUE(p.has_transfer);
  EXPECT_EQ(p.transfer_lazy.size(), N);
  EXPECT_EQ(p.transfer_max_error.size(), N);
  EXPECT_EQ(p.p_lazy_prop_transfer.size(), N);
  if (p.done.size() != N || p.valid.size() != N || p.lazy.size() != N || p.collision.size() != N ||
      p.max_error.size() != N || p.p_lazy_prop.size() != N || p.p_collision.size() != N ||
      p.transfer_lazy.size() != N || p.transfer_max_error.size() != N ||
      p.p_lazy_prop_transfer.size() != N) {
    return 0;
  }
  size_t finished = 0;
  int reported = 0;  // stop after a few failing edges
  for (size_t e = 0; e < N && reported < 5; ++e) {
    std::ostringstream where;
    where.precision(17);
    where << "edge " << e << ": done " << p.done[e] << ", valid " << p.valid[e] << ", lazy "
          << p.lazy[e] << ", collision " << p.collision[e] << ", max_error " << p.max_error[e]
          << ", p_lazy_prop " << p.p_lazy_prop[e] << ", p_collision " << p.p_collision[e];
    std::string problems;
    // An edge is processed whole: 0 or p done.
    if (p.done[e] != 0 && p.done[e] != p.perturbations) problems += " done is neither 0 nor p;";
    finished += p.done[e] == p.perturbations;
    if (p.valid[e] + p.collision[e] > p.done[e]) problems += " valid + collision > done;";
    if (p.lazy[e] > p.valid[e]) problems += " lazy > valid;";
    if (!(p.p_lazy_prop[e] >= 0 && p.p_lazy_prop[e] <= 1))
      problems += " p_lazy_prop outside [0, 1];";
    if (!(p.p_collision[e] >= 0 && p.p_collision[e] <= 1))
      problems += " p_collision outside [0, 1];";
    const double lazy_prop = p.valid[e] ? static_cast<double>(p.lazy[e]) / p.valid[e] : 0.0;
    if (!same_double(p.p_lazy_prop[e], lazy_prop)) problems += " p_lazy_prop != lazy / valid;";
    const double collision = p.done[e] ? static_cast<double>(p.collision[e]) / p.done[e] : 0.0;
    if (!same_double(p.p_collision[e], collision)) problems += " p_collision != collision / done;";
    if (p.valid[e] == 0) {
      if (!std::isnan(p.max_error[e])) problems += " max_error is not NaN with no valid rollout;";
    } else if (!(p.max_error[e] >= 0)) {
      problems += " max_error is not >= 0 (or is NaN) with valid rollouts;";
    }
    if (p.transfer_lazy[e] > p.valid[e]) problems += " transfer_lazy > valid;";
    const double transfer_prop =
        p.valid[e] ? static_cast<double>(p.transfer_lazy[e]) / p.valid[e] : 0.0;
    if (!same_double(p.p_lazy_prop_transfer[e], transfer_prop))
      problems += " p_lazy_prop_transfer != transfer_lazy / valid;";
    if (p.valid[e] == 0) {
      if (!std::isnan(p.transfer_max_error[e]))
        problems += " transfer_max_error is not NaN with no valid rollout;";
    } else if (!(p.transfer_max_error[e] >= 0)) {
      problems += " transfer_max_error is not >= 0 (or is NaN) with valid rollouts;";
    }
    if (!problems.empty()) {
      ADD_FAILURE() << where.str() << ":" << problems;
      ++reported;
    }
  }
  return finished;
}

// ------------------------------------------------------------------------------------------
// Inputs and references, made once per test binary
// ------------------------------------------------------------------------------------------

// A complete bundle of `edges` edges on `env`, built once; never modified (tests copy it).
const std::string& input_bundle(uint64_t edges, uint64_t seed, const std::string& env) {
  static std::map<std::string, std::string> cache;
  const std::string key = std::to_string(edges) + "-" + std::to_string(seed) + "-" + env;
  const auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const std::string dir = fresh_dir("input-" + key);
  const std::string out = dir + "/input.h5";
  const CommandResult r =
      build_tool({"--out", out, "--edges", std::to_string(edges), "--seed", std::to_string(seed),
                  "--env", env_file(env), "--threads", "2", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << "input build: " << describe(r);
  return cache[key] = out;
}

// A copy of an input bundle at `path` (writable).
void copy_bundle(const std::string& from, const std::string& path) {
  fs::copy_file(from, path, fs::copy_options::overwrite_existing);
}

// An uninterrupted analysis of a copy of `input` with `args` (2 threads, quiet), run once.
const Bundle& reference(const std::string& input, const std::vector<std::string>& args) {
  static std::map<std::string, Bundle> cache;
  static int counter = 0;
  const std::string key = input + " " + join(args);
  const auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const std::string dir = fresh_dir("reference-" + std::to_string(counter++));
  const std::string path = dir + "/reference.h5";
  copy_bundle(input, path);
  std::vector<std::string> all = {"--bundle", path, "--threads", "2", "--quiet"};
  all.insert(all.end(), args.begin(), args.end());
  const CommandResult r = perturb_tool(all);
  EXPECT_EQ(r.exit_code, 0) << "reference run " << key << ": " << describe(r);
  return cache[key] = read_bundle(path);
}

}  // namespace lazyboe::test
