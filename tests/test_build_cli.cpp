// End-to-end tests of the lazyboe-build command-line tool: the real binary builds real bundles,
// which are read back with the library (and, for the layout, with the HDF5 C API directly).
// Covered: the same bundle whatever the thread count; interrupt (SIGINT, SIGKILL) and resume
// giving the same bundle as a straight build; resume refusals; no silent overwrite; one-line
// errors for bad input with nothing written; the file layout of schemas/bundle.md; progress.
//
// Run time matters (the whole file should stay well under a minute on two cores): builds use
// a few hundred edges, except the interruption tests (2500 edges, a few seconds each).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// ------------------------------------------------------------------------------------------
// Running the tool
// ------------------------------------------------------------------------------------------

// The shell command line of lazyboe-build with the given arguments (each shell-quoted). A
// watchdog kills a run that does not end, so a tool that misreads its input fails the test
// instead of hanging it.
std::string build_command(const std::vector<std::string>& args, double timeout_seconds) {
  std::string cmd = watchdog(timeout_seconds) + quote(tool_path("lazyboe-build"));
  for (const std::string& a : args) cmd += " " + quote(a);
  return cmd;
}

CommandResult build_tool(const std::vector<std::string>& args, double timeout_seconds = 60) {
  return run(build_command(args, timeout_seconds));
}

// The same, run inside `dir` (so that anything written by mistake to a relative path lands there).
CommandResult build_tool_in(const std::string& dir, const std::vector<std::string>& args,
                            double timeout_seconds = 60) {
  return run("cd " + quote(dir) + " && " + build_command(args, timeout_seconds));
}

std::string env_file(const std::string& name) { return source_path("data/environments/" + name); }

// ---- A build running in the background, for signals -------------------------------------

Background spawn_build(const std::vector<std::string>& args, const std::string& log_prefix) {
  return spawn_tool("lazyboe-build", args, log_prefix);
}

// Waits until `path` exists (the build's first checkpoint), the process ends, or the timeout.
bool wait_for_file(const Background& b, const std::string& path, double timeout_seconds) {
  const auto until = Clock::now() + std::chrono::duration<double>(timeout_seconds * time_scale());
  while (Clock::now() < until) {
    if (fs::exists(path)) return true;
    int status = 0;
    if (::waitpid(b.pid, &status, WNOHANG) == b.pid) return fs::exists(path);  // ended (reaped)
    sleep_seconds(0.02);
  }
  return fs::exists(path);
}

// ------------------------------------------------------------------------------------------
// Comparing bundles
// ------------------------------------------------------------------------------------------

bool same_double(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every array of the two bundles is identical.
void expect_same_edges(const Bundle& a, const Bundle& b) { expect_same_edge_arrays(a, b); }

// Every deterministic header field is identical: all but wall_seconds and tool_version.
void expect_same_header(const BundleHeader& a, const BundleHeader& b) {
  EXPECT_EQ(a.schema_version, b.schema_version);
  EXPECT_EQ(a.complete, b.complete);
  EXPECT_EQ(a.robot_name, b.robot_name);
  EXPECT_EQ(a.robot_config, b.robot_config);
  EXPECT_EQ(a.robot_hash, b.robot_hash);
  EXPECT_EQ(a.env_name, b.env_name);
  EXPECT_EQ(a.env_file, b.env_file);
  EXPECT_EQ(a.env_hash, b.env_hash);
  EXPECT_EQ(a.dof, b.dof);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.target_edges, b.target_edges);
  EXPECT_TRUE(same_array("region_lower", a.region_lower, b.region_lower));
  EXPECT_TRUE(same_array("region_upper", a.region_upper, b.region_upper));
  EXPECT_TRUE(same_double(a.min_duration, b.min_duration))
      << a.min_duration << " vs " << b.min_duration;
  EXPECT_TRUE(same_double(a.max_duration, b.max_duration))
      << a.max_duration << " vs " << b.max_duration;
  EXPECT_TRUE(same_double(a.knot_interval, b.knot_interval))
      << a.knot_interval << " vs " << b.knot_interval;
  EXPECT_EQ(a.integrator, b.integrator);
  EXPECT_EQ(a.substeps, b.substeps);
  EXPECT_TRUE(same_double(a.velocity_scale, b.velocity_scale))
      << a.velocity_scale << " vs " << b.velocity_scale;
  EXPECT_TRUE(same_double(a.limit_scale, b.limit_scale))
      << a.limit_scale << " vs " << b.limit_scale;
  EXPECT_TRUE(same_double(a.control_rate, b.control_rate))
      << a.control_rate << " vs " << b.control_rate;
  EXPECT_TRUE(same_double(a.sample_interval, b.sample_interval))
      << a.sample_interval << " vs " << b.sample_interval;
  EXPECT_TRUE(same_double(a.design_theta, b.design_theta))
      << a.design_theta << " vs " << b.design_theta;
  EXPECT_EQ(a.attempts, b.attempts);
  EXPECT_EQ(a.valid, b.valid);
  EXPECT_EQ(a.rejected, b.rejected);
  EXPECT_EQ(a.start_resamples, b.start_resamples);
  EXPECT_TRUE(same_double(a.simulated_seconds, b.simulated_seconds))
      << std::to_string(a.simulated_seconds) << " vs " << std::to_string(b.simulated_seconds);
}

void expect_same_bundle(const Bundle& a, const Bundle& b) {
  expect_same_header(a.header, b.header);
  expect_same_edges(a, b);
}

// An uninterrupted build of `edges` edges with `seed` (2 threads), built once per test binary.
const Bundle& straight_build(uint64_t edges, uint64_t seed) {
  static std::map<std::pair<uint64_t, uint64_t>, Bundle> cache;
  const auto key = std::make_pair(edges, seed);
  const auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const std::string dir =
      fresh_dir("straight-" + std::to_string(edges) + "-" + std::to_string(seed));
  const std::string out = dir + "/straight.h5";
  const CommandResult r = build_tool({"--out", out, "--edges", std::to_string(edges), "--seed",
                                      std::to_string(seed), "--threads", "2", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << "straight build: " << describe(r);
  return cache[key] = read_bundle(out);
}

// ------------------------------------------------------------------------------------------
// 1. Determinism
// ------------------------------------------------------------------------------------------

TEST(BuildCli, SameBundleWhateverTheThreadCount) {
  const std::string dir = fresh_dir("threads");
  const std::string one = dir + "/one.h5", two = dir + "/two.h5", other = dir + "/other.h5";
  const CommandResult r1 =
      build_tool({"--out", one, "--edges", "300", "--seed", "5", "--threads", "1", "--quiet"});
  ASSERT_EQ(r1.exit_code, 0) << describe(r1);
  const CommandResult r2 =
      build_tool({"--out", two, "--edges", "300", "--seed", "5", "--threads", "2", "--quiet"});
  ASSERT_EQ(r2.exit_code, 0) << describe(r2);
  const Bundle a = read_bundle(one), b = read_bundle(two);
  EXPECT_TRUE(a.header.complete);
  EXPECT_EQ(a.size(), 300u);
  EXPECT_EQ(a.header.seed, 5u);
  expect_same_bundle(a, b);

  // A different seed gives different edges.
  const CommandResult r3 =
      build_tool({"--out", other, "--edges", "300", "--seed", "6", "--threads", "2", "--quiet"});
  ASSERT_EQ(r3.exit_code, 0) << describe(r3);
  const Bundle c = read_bundle(other);
  EXPECT_EQ(c.size(), 300u);
  EXPECT_FALSE(same_array("q0", a.q0, c.q0)) << "seeds 5 and 6 gave the same start states";
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
}

// ------------------------------------------------------------------------------------------
// 2. Interruption and resume
// ------------------------------------------------------------------------------------------

// Long enough that the build is still running when the tests stop it 0.5 s after its first
// checkpoint (0.2 s): 2500 edges took 0.87 s on an idle 2-core machine and raced the signal.
constexpr uint64_t kLongEdges = 8000;
constexpr uint64_t kLongSeed = 3;

std::vector<std::string> long_build_args(const std::string& out) {
  return {"--out",
          out,
          "--edges",
          std::to_string(kLongEdges),
          "--seed",
          std::to_string(kLongSeed),
          "--threads",
          "2",
          "--checkpoint-seconds",
          "0.2",
          "--quiet"};
}

TEST(BuildCli, InterruptedBuildResumesToTheStraightBuild) {
  const std::string dir = fresh_dir("sigint");
  const std::string out = dir + "/run.h5";
  Background b = spawn_build(long_build_args(out), temp_dir() + "/sigint");
  ASSERT_GT(b.pid, 0);
  // Let it write a first checkpoint and run on a little, then Ctrl-C.
  const bool started = wait_for_file(b, out, 30);
  sleep_seconds(0.5);
  ::kill(b.pid, SIGINT);
  const int code = wait_for(b);
  ASSERT_TRUE(started) << "no checkpoint appeared at " << out;
  const std::string err = read_file(b.err_path);
  EXPECT_EQ(code, 130) << err;
  EXPECT_EQ(count_lines(err), 1) << "expected a one-line hint on stderr:\n" << err;
  EXPECT_TRUE(contains(err, "--resume")) << err;
  EXPECT_TRUE(contains(err, out)) << err;
  EXPECT_EQ(read_file(b.out_path), "");
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));

  const Bundle partial = read_bundle(out);
  EXPECT_FALSE(partial.header.complete);
  EXPECT_GT(partial.size(), 0u);
  EXPECT_LT(partial.size(), kLongEdges);
  EXPECT_EQ(partial.header.target_edges, kLongEdges);
  uint64_t header_edges = 0;
  const BundleHeader header = read_bundle_header(out, &header_edges);
  EXPECT_FALSE(header.complete);
  EXPECT_EQ(header_edges, partial.size());

  const CommandResult inspect = build_tool({"--inspect", out});
  EXPECT_EQ(inspect.exit_code, 0) << describe(inspect);
  EXPECT_TRUE(contains(inspect.out, "INCOMPLETE")) << inspect.out;
  // A few edges in the whole region: most of it uncovered, and the report says what to do.
  EXPECT_TRUE(contains(inspect.out, "outside the bundle's coverage. Build more edges (--edges)"))
      << inspect.out;
  EXPECT_TRUE(contains(
      inspect.out, "edges " + std::to_string(partial.size()) + " of " + std::to_string(kLongEdges)))
      << inspect.out;

  // The settings come from the file.
  const CommandResult resumed = build_tool({"--resume", "--out", out});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_EQ(resumed.out, "");
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
  const Bundle full = read_bundle(out);
  EXPECT_TRUE(full.header.complete);
  EXPECT_EQ(full.size(), kLongEdges);
  // What was there before is kept as it was.
  EXPECT_TRUE(std::equal(partial.q0.begin(), partial.q0.end(), full.q0.begin()));
  expect_same_bundle(full, straight_build(kLongEdges, kLongSeed));
}

// After SIGKILL the file at --out is absent, a valid incomplete bundle that resumes to the
// straight build, or (killed while writing the indexes after the build) the straight build
// itself; temporary files of the killed process may remain (of the bundle or of an index beside
// it; nothing else may).
void check_killed_build(const std::string& dir, const std::string& out, pid_t killed_pid,
                        bool must_exist) {
  const std::string name = fs::path(out).filename().string();
  const std::string own_tmp = ".tmp." + std::to_string(killed_pid) + ".";
  auto unexpected_tmp = [&] {
    std::vector<std::string> bad;
    for (const std::string& f : tmp_files_in(dir)) {
      if (f.rfind(name, 0) != 0 || f.find(own_tmp) == std::string::npos) bad.push_back(f);
    }
    return bad;
  };
  EXPECT_TRUE(unexpected_tmp().empty()) << join(unexpected_tmp());
  if (!fs::exists(out)) {
    EXPECT_FALSE(must_exist) << out
                             << " vanished after SIGKILL although a checkpoint had been written";
    return;
  }
  const Bundle partial = read_bundle(out);  // throws (fails the test) if the kill broke it
  if (partial.header.complete) {  // the kill came after the build, while the indexes were written
    expect_same_bundle(partial, straight_build(kLongEdges, kLongSeed));
    return;
  }
  EXPECT_LT(partial.size(), kLongEdges);
  const CommandResult resumed = build_tool({"--resume", "--out", out});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(unexpected_tmp().empty()) << join(unexpected_tmp());
  const Bundle full = read_bundle(out);
  EXPECT_TRUE(full.header.complete);
  expect_same_bundle(full, straight_build(kLongEdges, kLongSeed));
}

TEST(BuildCli, KilledBuildLeavesNothingOrAResumableBundle) {
  {
    SCOPED_TRACE("killed right after start");
    const std::string dir = fresh_dir("sigkill-early");
    const std::string out = dir + "/run.h5";
    Background b = spawn_build(long_build_args(out), temp_dir() + "/sigkill-early");
    ASSERT_GT(b.pid, 0);
    const pid_t pid = b.pid;
    sleep_seconds(0.05);
    ::kill(b.pid, SIGKILL);
    EXPECT_EQ(wait_for(b), -SIGKILL);
    check_killed_build(dir, out, pid, false);
  }
  {
    SCOPED_TRACE("killed in the middle");
    const std::string dir = fresh_dir("sigkill-middle");
    const std::string out = dir + "/run.h5";
    Background b = spawn_build(long_build_args(out), temp_dir() + "/sigkill-middle");
    ASSERT_GT(b.pid, 0);
    const pid_t pid = b.pid;
    const bool started = wait_for_file(b, out, 30);
    sleep_seconds(0.6);  // a few more checkpoints: the kill may well land inside one
    ::kill(b.pid, SIGKILL);
    EXPECT_EQ(wait_for(b), -SIGKILL) << read_file(b.err_path);
    ASSERT_TRUE(started) << "no checkpoint appeared at " << out;
    check_killed_build(dir, out, pid, true);
  }
}

// ------------------------------------------------------------------------------------------
// 3. Resume: refusals, already complete, extending
// ------------------------------------------------------------------------------------------

TEST(BuildCli, ResumeRefusesOtherSettingsAndExtendsToTheStraightBuild) {
  const std::string dir = fresh_dir("resume");
  const std::string full = dir + "/full.h5", part = dir + "/part.h5";
  const CommandResult r =
      build_tool({"--out", full, "--edges", "200", "--seed", "4", "--threads", "2", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);

  // An interrupted build of 400 edges after 200: the same file with complete = 0.
  Bundle partial = read_bundle(full);
  ASSERT_EQ(partial.size(), 200u);
  partial.header.complete = false;
  partial.header.target_edges = 400;
  write_bundle(part, partial);

  const struct {
    std::vector<std::string> args;
    std::vector<std::string> needles;
  } refusals[] = {
      {{"--seed", "5"}, {"--seed"}},
      {{"--env", env_file("shelf.json")}, {"environment", "shelf.json"}},
      {{"--min-duration", "0.2"}, {"--min-duration"}},
  };
  for (const std::string& file : {part, full}) {
    for (const auto& refusal : refusals) {
      SCOPED_TRACE(file + " with " + join(refusal.args));
      const std::string before = read_file(file);
      std::vector<std::string> args = {"--resume", "--out", file};
      args.insert(args.end(), refusal.args.begin(), refusal.args.end());
      const CommandResult refused = build_tool(args);
      std::vector<std::string> needles = refusal.needles;
      needles.push_back(file);
      expect_one_line_error(refused, needles);
      EXPECT_EQ(refused.exit_code, 1);
      EXPECT_TRUE(read_file(file) == before) << file << " changed";
      EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
    }
  }

  // A complete bundle resumed to its own size: nothing to do.
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--edges", "200"}, std::vector<std::string>{}}) {
    SCOPED_TRACE("complete bundle resumed with " + join(extra));
    const std::string before = read_file(full);
    std::vector<std::string> args = {"--resume", "--out", full};
    args.insert(args.end(), extra.begin(), extra.end());
    const CommandResult done = build_tool(args);
    EXPECT_EQ(done.exit_code, 0) << describe(done);
    EXPECT_TRUE(contains(done.err, "already complete")) << describe(done);
    EXPECT_EQ(done.out, "");
    EXPECT_TRUE(read_file(full) == before) << full << " changed";
  }

  // Asking for fewer edges than the file holds is refused.
  {
    const std::string before = read_file(full);
    const CommandResult fewer = build_tool({"--resume", "--out", full, "--edges", "100"});
    expect_one_line_error(fewer, {"--edges", "200"});
    EXPECT_TRUE(read_file(full) == before) << full << " changed";
  }

  // Extending a complete bundle, and finishing the interrupted one, give the straight build.
  const Bundle& straight = straight_build(400, 4);
  const CommandResult extended =
      build_tool({"--resume", "--out", full, "--edges", "400", "--quiet"});
  ASSERT_EQ(extended.exit_code, 0) << describe(extended);
  {
    SCOPED_TRACE("complete 200 extended to 400");
    const Bundle b = read_bundle(full);
    EXPECT_TRUE(b.header.complete);
    EXPECT_EQ(b.header.target_edges, 400u);
    expect_same_bundle(b, straight);
  }
  const CommandResult finished = build_tool({"--resume", "--out", part, "--quiet"});
  ASSERT_EQ(finished.exit_code, 0) << describe(finished);
  {
    SCOPED_TRACE("incomplete 200 of 400 finished");
    expect_same_bundle(read_bundle(part), straight);
  }
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
}

// ------------------------------------------------------------------------------------------
// 4. No silent overwrite
// ------------------------------------------------------------------------------------------

TEST(BuildCli, ExistingOutputIsOnlyReplacedWithForce) {
  const std::string dir = fresh_dir("overwrite");
  const std::string out = dir + "/b.h5";
  const CommandResult first = build_tool({"--out", out, "--edges", "60", "--seed", "1", "--quiet"});
  ASSERT_EQ(first.exit_code, 0) << describe(first);
  const std::string before = read_file(out);

  const CommandResult again = build_tool({"--out", out, "--edges", "60", "--seed", "2", "--quiet"});
  expect_one_line_error(again, {out, "--force"});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_TRUE(read_file(out) == before) << "overwritten without --force";

  const CommandResult forced =
      build_tool({"--out", out, "--edges", "60", "--seed", "2", "--quiet", "--force"});
  ASSERT_EQ(forced.exit_code, 0) << describe(forced);
  EXPECT_FALSE(read_file(out) == before) << "--force did not replace the file";
  const Bundle b = read_bundle(out);
  EXPECT_EQ(b.header.seed, 2u);
  EXPECT_TRUE(b.header.complete);
  EXPECT_EQ(b.size(), 60u);
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"b.h5", "b.h5.kd-index", "b.h5.ws-index"}));
}

// ------------------------------------------------------------------------------------------
// 5. Bad input
// ------------------------------------------------------------------------------------------

struct BadCase {
  std::string name;
  std::vector<std::string> args;  // "@OUT" stands for <case dir>/out.h5, "@DIR/x" for a file in it
  std::vector<std::string> needles;   // "@OUT"/"@DIR" expanded likewise
  bool command_line_mistake = false;  // reported by CLI11: exit status >= 2; else exactly 1
  std::function<void(const std::string& dir)> setup;  // files placed in the case dir first

  BadCase(std::string name, std::vector<std::string> args, std::vector<std::string> needles,
          bool command_line_mistake = false, std::function<void(const std::string&)> setup = {})
      : name(std::move(name)),
        args(std::move(args)),
        needles(std::move(needles)),
        command_line_mistake(command_line_mistake),
        setup(std::move(setup)) {}
};

std::string expand(const std::string& s, const std::string& dir) {
  if (s.rfind("@OUT", 0) == 0) return dir + "/out.h5" + s.substr(4);
  if (s.rfind("@DIR", 0) == 0) return dir + s.substr(4);
  return s;
}

// Out of the workspace of the default region: a box covering the space in front of the robot.
const char* kBlockedEnv = R"({
  "schema_version": 1,
  "name": "blocked",
  "description": "a box filling the robot's workspace",
  "objects": [
    {"name": "block", "type": "box", "size": [1.2, 2.0, 0.8], "position": [0.5, 0, 0.6], "rpy": [0, 0, 0]}
  ]
})";

void expect_bad_input(const BadCase& c, const std::string& dir_name) {
  SCOPED_TRACE(c.name);
  const std::string dir = fresh_dir(dir_name);
  if (c.setup) c.setup(dir);
  const auto before = snapshot(dir);
  std::vector<std::string> args, needles;
  for (const std::string& a : c.args) args.push_back(expand(a, dir));
  for (const std::string& n : c.needles) needles.push_back(expand(n, dir));
  const CommandResult r = build_tool_in(dir, args, 3);
  expect_one_line_error(r, needles);
  if (c.command_line_mistake) {
    EXPECT_GE(r.exit_code, 2) << describe(r);
  } else {
    EXPECT_EQ(r.exit_code, 1) << describe(r);
  }
  const auto after = snapshot(dir);
  std::vector<std::string> names_before, names_after;
  for (const auto& [name, bytes] : before) names_before.push_back(name);
  for (const auto& [name, bytes] : after) names_after.push_back(name);
  EXPECT_EQ(names_after, names_before) << "files written or removed";
  EXPECT_TRUE(after == before) << "a file was changed";
}

TEST(BuildCli, BadInputIsOneLineAndWritesNothing) {
  const std::string outside = "-3:3,-0.3:0.7,-0.6:0.6,-2.6:-1.4,-0.6:0.6,1.3:2.5,0:1.6";
  const std::vector<BadCase> cases = {
      {"edges 0", {"--out", "@OUT", "--edges", "0"}, {"--edges", "> 0"}, true},
      {"seed -3", {"--out", "@OUT", "--seed", "-3"}, {"--seed", ">= 0"}, true},
      {"checkpoint -1",
       {"--out", "@OUT", "--checkpoint-seconds", "-1"},
       {"--checkpoint-seconds"},
       true},
      {"durations reversed",
       {"--out", "@OUT", "--min-duration", "0.8", "--max-duration", "0.5"},
       {"--max-duration"}},
      {"region outside the limits",
       {"--out", "@OUT", "--region", outside},
       {"--region", "joint 1", "2.897"}},
      {"region with 2 pairs", {"--out", "@OUT", "--region", "-1:1,-0.3:0.7"}, {"--region", "7"}},
      {"region with 8 pairs",
       {"--out", "@OUT", "--region", "-1:1,-0.3:0.7,-0.6:0.6,-2.6:-1.4,-0.6:0.6,1.3:2.5,0:1.6,0:1"},
       {"--region", "7"}},
      {"region garbage", {"--out", "@OUT", "--region", "garbage"}, {"--region", "garbage"}},
      {"region pair reversed",
       {"--out", "@OUT", "--region", "1:-1,-0.3:0.7,-0.6:0.6,-2.6:-1.4,-0.6:0.6,1.3:2.5,0:1.6"},
       {"--region", "joint 1"}},
      {"region file without upper",
       {"--out", "@OUT", "--region", "@DIR/region.json"},
       {"@DIR/region.json", "upper"},
       false,
       [](const std::string& dir) {
         write_bytes(dir + "/region.json", R"({"lower": [-1, -0.3, -0.6, -2.6, -0.6, 1.3, 0]})");
       }},
      {"region file with 6 values",
       {"--out", "@OUT", "--region", "@DIR/region.json"},
       {"@DIR/region.json", "lower"},
       false,
       [](const std::string& dir) {
         write_bytes(dir + "/region.json", R"({"lower": [-1, -0.3, -0.6, -2.6, -0.6, 1.3],
                                               "upper": [1, 0.7, 0.6, -1.4, 0.6, 2.5, 1.6]})");
       }},
      {"start region entirely in collision",
       {"--out", "@OUT", "--env", "@DIR/blocked.json"},
       {"--region", "collision"},
       false,
       [](const std::string& dir) { write_bytes(dir + "/blocked.json", kBlockedEnv); }},
      {"integrator foo", {"--out", "@OUT", "--integrator", "foo"}, {"--integrator", "foo"}},
      {"velocity scale 0", {"--out", "@OUT", "--velocity-scale", "0"}, {"--velocity-scale"}, true},
      {"velocity scale nan",
       {"--out", "@OUT", "--velocity-scale", "nan"},
       {"--velocity-scale"},
       true},
      {"theta in hex", {"--out", "@OUT", "--theta", "0x1"}, {"--theta", "0x1"}, true},
      {"missing --out", {"--edges", "10"}, {"--out"}},
      {"resume a missing file", {"--resume", "--out", "@OUT"}, {"@OUT"}},
      {"resume with force", {"--resume", "--force", "--out", "@OUT"}, {"--resume", "--force"}},
      {"resume a corrupt bundle",
       {"--resume", "--out", "@OUT"},
       {"@OUT"},
       false,
       [](const std::string& dir) { write_bytes(dir + "/out.h5", garbage_bytes()); }},
      {"inspect a corrupt bundle",
       {"--inspect", "@OUT"},
       {"@OUT"},
       false,
       [](const std::string& dir) { write_bytes(dir + "/out.h5", garbage_bytes()); }},
      {"inspect a missing file", {"--inspect", "@OUT"}, {"@OUT"}},
      {"edges not a number", {"--out", "@OUT", "--edges", "abc"}, {"--edges"}, true},
      {"unknown option", {"--out", "@OUT", "--bogus"}, {"--bogus"}, true},
  };
  for (size_t k = 0; k < cases.size(); ++k) expect_bad_input(cases[k], "bad-" + std::to_string(k));
}

// An unsigned option must not wrap a negative number around to 2^64 - 1 (and then build
// forever): the watchdog ends such a run after a few seconds, which fails the test.
TEST(BuildCli, NegativeEdgesIsRefused) {
  expect_bad_input(
      {"edges negative", {"--out", "@OUT", "--edges", "-1", "--quiet"}, {"--edges"}, true},
      "bad-negative-edges");
}

TEST(BuildCli, RegionFromAJsonFile) {
  const std::string dir = fresh_dir("region-file");
  const std::string region = dir + "/region.json", out = dir + "/b.h5";
  write_bytes(region, R"({"description": "a smaller box",
                          "lower": [-0.5, -0.2, -0.4, -2.4, -0.4, 1.5, 0.2],
                          "upper": [0.5, 0.6, 0.4, -1.6, 0.4, 2.3, 1.4]})");
  const CommandResult r =
      build_tool({"--out", out, "--edges", "40", "--region", region, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const Bundle b = read_bundle(out);
  EXPECT_EQ(b.header.region_lower, (std::vector<double>{-0.5, -0.2, -0.4, -2.4, -0.4, 1.5, 0.2}));
  EXPECT_EQ(b.header.region_upper, (std::vector<double>{0.5, 0.6, 0.4, -1.6, 0.4, 2.3, 1.4}));
  const int n = b.dof();
  for (size_t e = 0; e < b.size(); ++e) {
    for (int i = 0; i < n; ++i) {
      EXPECT_GE(b.q0[e * n + i], b.header.region_lower[i]);
      EXPECT_LE(b.q0[e * n + i], b.header.region_upper[i]);
    }
  }
}

// ------------------------------------------------------------------------------------------
// 6. The file layout (schemas/bundle.md)
// ------------------------------------------------------------------------------------------

struct DatasetInfo {
  bool exists = false;
  std::vector<hsize_t> dims;
  bool type_ok = false;
  bool contiguous = false;
  int filters = -1;
};

DatasetInfo dataset_info(hid_t file, const char* name, hid_t expected_type) {
  DatasetInfo info;
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0) return info;
  const hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
  if (ds < 0) return info;
  info.exists = true;
  const hid_t space = H5Dget_space(ds);
  const int rank = H5Sget_simple_extent_ndims(space);
  info.dims.resize(std::max(rank, 0));
  if (rank > 0) H5Sget_simple_extent_dims(space, info.dims.data(), nullptr);
  H5Sclose(space);
  const hid_t type = H5Dget_type(ds);
  info.type_ok = H5Tequal(type, expected_type) > 0;
  H5Tclose(type);
  const hid_t dcpl = H5Dget_create_plist(ds);
  info.contiguous = H5Pget_layout(dcpl) == H5D_CONTIGUOUS;
  info.filters = H5Pget_nfilters(dcpl);
  H5Pclose(dcpl);
  H5Dclose(ds);
  return info;
}

std::string dims_text(const std::vector<hsize_t>& dims) {
  std::string s;
  for (hsize_t d : dims) s += (s.empty() ? "" : " x ") + std::to_string(d);
  return s.empty() ? "(scalar)" : s;
}

TEST(BuildCli, FreshBundleFollowsTheSchema) {
  const std::string dir = fresh_dir("schema");
  const std::string out = dir + "/b.h5";
  const CommandResult r = build_tool({"--out", out, "--edges", "150", "--seed", "7", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"b.h5", "b.h5.kd-index", "b.h5.ws-index"}));

  const Bundle b = read_bundle(out);
  const BundleHeader& h = b.header;
  const size_t N = b.size();
  const int n = b.dof();
  ASSERT_EQ(N, 150u);
  ASSERT_EQ(n, 7);
  ASSERT_EQ(b.knot_offset.size(), N + 1);
  ASSERT_EQ(b.sample_offset.size(), N + 1);
  const uint64_t K = b.knot_offset.back(), S = b.sample_offset.back();
  EXPECT_TRUE(h.complete);
  EXPECT_EQ(h.schema_version, 1);
  EXPECT_EQ(h.target_edges, 150u);
  EXPECT_EQ(h.valid, N);
  uint64_t rejected = 0;
  for (const auto& [reason, count] : h.rejected) rejected += count;
  EXPECT_EQ(h.attempts, h.valid + rejected);

  // Shapes, element types and storage, read with the HDF5 C API.
  {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t file = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(file, 0) << out;
    const hsize_t d = static_cast<hsize_t>(n);
    const struct {
      const char* name;
      std::vector<hsize_t> dims;
      hid_t type;
    } expected[] = {
        {"/edges/q0", {N, d}, H5T_IEEE_F64LE},
        {"/edges/qf", {N, d}, H5T_IEEE_F64LE},
        {"/edges/duration", {N}, H5T_IEEE_F64LE},
        {"/edges/command_duration", {N}, H5T_IEEE_F64LE},
        {"/edges/attempt", {N}, H5T_STD_U64LE},
        {"/edges/knot_offset", {N + 1}, H5T_STD_U64LE},
        {"/edges/sample_offset", {N + 1}, H5T_STD_U64LE},
        {"/controls/knots", {K, d}, H5T_IEEE_F64LE},
        {"/trajectory/q", {S, d}, H5T_IEEE_F32LE},
        {"/trajectory/dq", {S, d}, H5T_IEEE_F32LE},
    };
    for (const auto& e : expected) {
      SCOPED_TRACE(e.name);
      const DatasetInfo info = dataset_info(file, e.name, e.type);
      ASSERT_TRUE(info.exists);
      EXPECT_EQ(dims_text(info.dims), dims_text(e.dims));
      EXPECT_TRUE(info.type_ok) << "element type";
      EXPECT_TRUE(info.contiguous) << "layout";
      EXPECT_EQ(info.filters, 0);
    }
    H5Fclose(file);
  }

  // Contents.
  EXPECT_EQ(b.knot_offset[0], 0u);
  EXPECT_EQ(b.sample_offset[0], 0u);
  const int every = static_cast<int>(std::lround(h.sample_interval * h.control_rate));
  ASSERT_GT(every, 0);
  for (size_t e = 0; e < N; ++e) {
    SCOPED_TRACE("edge " + std::to_string(e));
    if (e > 0) {
      EXPECT_GT(b.attempt[e], b.attempt[e - 1]) << "attempts not strictly increasing";
    }
    EXPECT_LT(b.attempt[e], h.attempts);
    for (int i = 0; i < n; ++i) {
      EXPECT_GE(b.q0[e * n + i], h.region_lower[i]) << "q0 outside the region, joint " << i + 1;
      EXPECT_LE(b.q0[e * n + i], h.region_upper[i]) << "q0 outside the region, joint " << i + 1;
    }
    EXPECT_GE(b.command_duration[e], h.min_duration);
    EXPECT_LE(b.command_duration[e], h.max_duration);
    EXPECT_GE(b.duration[e], b.command_duration[e]);

    // The velocity command starts and ends at rest.
    const uint64_t k0 = b.knot_offset[e], k1 = b.knot_offset[e + 1];
    ASSERT_GE(k1, k0 + 2) << "fewer than two knots";
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(b.knots[k0 * n + i], 0.0) << "first knot, joint " << i + 1;
      EXPECT_EQ(b.knots[(k1 - 1) * n + i], 0.0) << "last knot, joint " << i + 1;
    }

    // Trajectory samples: from q0 at rest every sample_interval, and the end state qf.
    const uint64_t s0 = b.sample_offset[e], s1 = b.sample_offset[e + 1];
    ASSERT_GE(s1, s0 + 2) << "fewer than two samples";
    const long ticks = std::lround(b.duration[e] * h.control_rate);
    const uint64_t expected_samples = ticks / every + 1 + (ticks % every != 0);
    EXPECT_EQ(s1 - s0, expected_samples) << "duration " << b.duration[e];
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(b.sample_q[s0 * n + i], static_cast<float>(b.q0[e * n + i]))
          << "first sample, joint " << i + 1;
      EXPECT_EQ(b.sample_dq[s0 * n + i], 0.0f) << "first sample velocity, joint " << i + 1;
      EXPECT_EQ(b.sample_q[(s1 - 1) * n + i], static_cast<float>(b.qf[e * n + i]))
          << "last sample, joint " << i + 1;
      // At rest: below the simulator's settle velocity (1e-3 rad/s).
      EXPECT_LE(std::abs(b.sample_dq[(s1 - 1) * n + i]), 1e-3f)
          << "last sample velocity, joint " << i + 1;
    }
  }

  const CommandResult inspect = build_tool({"--inspect", out});
  ASSERT_EQ(inspect.exit_code, 0) << describe(inspect);
  EXPECT_EQ(inspect.err, "");
  EXPECT_TRUE(contains(inspect.out, "complete")) << inspect.out;
  EXPECT_FALSE(contains(inspect.out, "INCOMPLETE")) << inspect.out;
  EXPECT_TRUE(contains(inspect.out, "edges 150 of 150")) << inspect.out;
  EXPECT_TRUE(contains(inspect.out, "edge starts within theta")) << inspect.out;
}

// ------------------------------------------------------------------------------------------
// 7. Progress output
// ------------------------------------------------------------------------------------------

TEST(BuildCli, ProgressIsPlainLinesWithASummary) {
  const std::string dir = fresh_dir("progress");
  const std::string out = dir + "/b.h5";
  const CommandResult r =
      build_tool({"--out", out, "--edges", "300", "--seed", "5", "--threads", "2"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(contains(r.err, "\r")) << "carriage return on stderr that is not a terminal:\n"
                                      << r.err;
  EXPECT_FALSE(contains(r.err, "\x1b")) << "escape sequence on stderr that is not a terminal:\n"
                                        << r.err;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.back(), '\n');
  EXPECT_TRUE(contains(r.err, "300/300")) << r.err;

  const Bundle b = read_bundle(out);
  const BundleHeader& h = b.header;
  EXPECT_TRUE(contains(r.err, "300 edges (complete)")) << r.err;
  EXPECT_TRUE(contains(
      r.err, "attempts " + std::to_string(h.attempts) + ", valid " + std::to_string(h.valid)))
      << r.err;
  ASSERT_FALSE(h.rejected.empty())
      << "test setup: no rejection in this build, the summary check means nothing";
  std::istringstream lines(r.err);
  std::string line;
  std::map<std::string, std::string> reported;  // reason -> count as printed
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string first, reason, count;
    if (words >> first >> reason >> count && first == "rejected") reported[reason] = count;
  }
  for (const auto& [reason, count] : h.rejected) {
    EXPECT_EQ(reported[reason], std::to_string(count)) << "rejected " << reason << "\n" << r.err;
  }
}

// The progress line names the leading rejection reason as the build goes.
TEST(BuildCli, ProgressNamesTheTopRejection) {
  const std::string dir = fresh_dir("progress-top");
  const CommandResult r = build_tool({"--out", dir + "/b.h5", "--edges", "300", "--seed", "5"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "300/300 (100.0%) valid ")) << r.err;
  EXPECT_TRUE(contains(r.err, ", top rejection ")) << r.err;
}

// The Panda with every torque-rate limit set to `rate` N m/s, as dir/slow.json.
std::string panda_with_torque_rate(const std::string& dir, const std::string& rate) {
  std::ifstream in(source_path("data/robots/panda.json"));
  const std::string config((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string slow = std::regex_replace(config, std::regex(R"("max_torque_rate": [0-9.]+)"),
                                              "\"max_torque_rate\": " + rate);
  EXPECT_NE(slow, config);
  write_bytes(dir + "/slow.json", slow);
  std::filesystem::copy_file(source_path("data/robots/panda.urdf"), dir + "/panda.urdf");
  return dir + "/slow.json";
}

// A robot whose every motion is rejected (here torque-rate limits of 1 N m/s) stops after the
// first 2000 attempts with the leading reasons and what to change, not after hours; the
// partial bundle stays valid.
TEST(BuildCli, AHopelessBuildStopsEarlyWithTheReason) {
  const std::string dir = fresh_dir("hopeless");
  panda_with_torque_rate(dir, "1");
  const std::string out = dir + "/b.h5";
  const CommandResult r =
      build_tool({"--robot", dir + "/slow.json", "--out", out, "--edges", "100", "--quiet"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  expect_one_line_error(
      r, {out, "stopped after the first 2000 attempts: 0 of 2000 attempts valid",
          "most rejected: torque_rate_limit 100.0%", "max_torque_rate", "--keep-going"});
  const Bundle b = read_bundle(out);
  EXPECT_FALSE(b.header.complete);
  EXPECT_EQ(b.header.attempts, 2000u);
}

// A build that is slow rather than hopeless (12 N m/s: about 0.5% of the attempts valid on
// this seed) stops at the check too, and `--keep-going` builds it to the end: complete, every
// edge there, past the 2000 attempts where the check would have stopped it.
TEST(BuildCli, KeepGoingBuildsPastTheEarlyStop) {
  const std::string dir = fresh_dir("keep-going");
  const std::string robot = panda_with_torque_rate(dir, "12");
  const std::string out = dir + "/b.h5";
  const std::vector<std::string> args = {
      "--robot", robot, "--env", env_file("empty.json"), "--out", out, "--edges", "15", "--quiet"};
  const CommandResult stopped = build_tool(args);
  EXPECT_EQ(stopped.exit_code, 1) << describe(stopped);
  EXPECT_TRUE(contains(stopped.err, "stopped after the first 2000 attempts")) << stopped.err;
  std::vector<std::string> keep_going = args;
  keep_going.push_back("--keep-going");
  keep_going.push_back("--force");
  const CommandResult r = build_tool(keep_going);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const Bundle b = read_bundle(out);
  EXPECT_TRUE(b.header.complete);
  EXPECT_EQ(b.size(), 15u);
  EXPECT_GT(b.header.attempts, 2000u);
  EXPECT_LT(b.header.valid * 50, b.header.attempts);  // under 2% valid: the check's case
}

TEST(BuildCli, QuietPrintsNothing) {
  const std::string dir = fresh_dir("quiet");
  const CommandResult r = build_tool({"--out", dir + "/b.h5", "--edges", "60", "--quiet"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"b.h5", "b.h5.kd-index", "b.h5.ws-index"}));
}

// ------------------------------------------------------------------------------------------
// 8. The k-d tree index beside the bundle
// ------------------------------------------------------------------------------------------

// Every finished build writes it, planning maps it, and --index writes the same file again for
// a bundle that has none.
TEST(BuildCli, AFinishedBuildWritesTheKdTreeIndexThatPlanningMaps) {
  const std::string dir = fresh_dir("kd-index");
  const std::string out = dir + "/b.h5", index = out + ".kd-index";
  const CommandResult built = build_tool({"--out", out, "--edges", "300", "--threads", "2"});
  ASSERT_EQ(built.exit_code, 0) << describe(built);
  EXPECT_TRUE(contains(built.err, "k-d tree index written to " + index)) << built.err;
  const std::string written = read_file(index);

  const std::string queries = write_temp_file("no-queries.jsonl", "");
  const std::string query = watchdog(60) + quote(tool_path("lazyboe-query")) + " --bundle " +
                            quote(out) + " --queries " + quote(queries) + " --out " +
                            quote(dir + "/results.jsonl");
  CommandResult r = run(query);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "k-d trees mapped from " + index)) << r.err;

  fs::remove(index);
  r = run(query);
  EXPECT_TRUE(contains(r.err, "k-d trees built at load (no index file)")) << r.err;
  r = build_tool({"--index", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(read_file(index) == written) << "--index wrote another file than the build";
  fs::remove(index);  // a finished bundle "resumed" gets the index it lacks
  r = build_tool({"--resume", "--out", out, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(fs::exists(index) && read_file(index) == written);

  const CommandResult missing = build_tool({"--index", dir + "/none.h5"});
  expect_one_line_error(missing, {dir + "/none.h5", "cannot open"});
  EXPECT_FALSE(fs::exists(dir + "/none.h5.kd-index"));

  // An index that cannot be written does not fail the build it goes with.
  const std::string other = dir + "/other.h5";
  fs::create_directory(other + ".kd-index");
  r = build_tool({"--out", other, "--edges", "60"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "warning: " + other + ".kd-index: cannot write: is a directory"))
      << r.err;
  EXPECT_TRUE(read_bundle(other).header.complete);
}

}  // namespace
}  // namespace lazyboe::test
