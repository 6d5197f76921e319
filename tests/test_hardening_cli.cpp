// Hostile input and faults, through the real tools (issue 15): a full disk (a file-size limit,
// `ulimit -f`, which needs no privilege), an output that is one of the inputs, numbers that are
// not numbers or out of range, directories given as files, damaged bundles. Every case must end
// in one line on stderr naming the file and field, a normal non-zero exit, and nothing lost.
//
// One small bundle (300 edges, perturbed) is built once per process and copied.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;

// A tool run under a watchdog (a hang fails the test), optionally with a file-size limit in KiB
// (the shell's ulimit -f) and inside a directory.
CommandResult tool(const std::string& name, const std::vector<std::string>& args,
                   long file_limit_kib = 0, const std::string& dir = "") {
  std::string cmd = dir.empty() ? "" : "cd " + quote(dir) + " && ";
  if (file_limit_kib > 0) cmd += "ulimit -f " + std::to_string(file_limit_kib) + " && ";
  cmd += "timeout -s KILL 120 " + quote(tool_path(name));
  for (const std::string& a : args) cmd += " " + quote(a);
  return run(cmd);
}

// The shared bundle: 300 edges with a perturbation analysis (p = 4).
const std::string& small_bundle() {
  static const std::string path = [] {
    const std::string dir = fresh_dir("shared");
    const std::string p = dir + "/small.h5";
    const CommandResult b = tool("lazyboe-build", {"--edges", "300", "--out", p, "--quiet"});
    EXPECT_EQ(b.exit_code, 0) << describe(b);
    const CommandResult q =
        tool("lazyboe-perturb", {"--bundle", p, "--perturbations", "4", "--quiet"});
    EXPECT_EQ(q.exit_code, 0) << describe(q);
    return p;
  }();
  return path;
}

std::string copy_of_small_bundle(const std::string& dir) {
  const std::string p = dir + "/bundle.h5";
  fs::copy_file(small_bundle(), p);
  return p;
}

// ---- a full disk ----------------------------------------------------------------------------

TEST(FullDisk, BuildPastTheFileSizeLimitFailsInOneLineAndLeavesNothing) {
  const std::string dir = fresh_dir("full-build");
  const std::string out = dir + "/out.h5";
  const CommandResult r =
      tool("lazyboe-build", {"--edges", "300", "--out", out, "--quiet"}, /*file_limit_kib=*/100);
  expect_one_line_error(r, {out + ": cannot write", "File too large"});
  EXPECT_FALSE(contains(r.err, ".tmp.")) << r.err;  // the output is named, not its temporary
  EXPECT_TRUE(files_in(dir).empty()) << join(files_in(dir));
}

TEST(FullDisk, ResumedBuildPastTheLimitKeepsTheLastCheckpoint) {
  const std::string dir = fresh_dir("full-resume");
  const std::string out = dir + "/out.h5";
  ASSERT_EQ(tool("lazyboe-build", {"--edges", "100", "--out", out, "--quiet"}).exit_code, 0);
  const std::string before = read_file(out);
  const long limit = static_cast<long>(before.size() / 1024) + 8;  // room for a few edges
  const CommandResult r =
      tool("lazyboe-build", {"--resume", "--edges", "400", "--out", out, "--quiet"}, limit);
  expect_one_line_error(r, {out + ": cannot write", "File too large"});
  EXPECT_EQ(read_file(out), before);
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"out.h5"});
}

TEST(FullDisk, PerturbPastTheLimitKeepsTheBundle) {
  const std::string dir = fresh_dir("full-perturb");
  const std::string out = dir + "/b.h5";
  ASSERT_EQ(tool("lazyboe-build", {"--edges", "300", "--out", out, "--quiet"}).exit_code, 0);
  const std::string before = read_file(out);
  const long limit = static_cast<long>(before.size() / 1024) + 1;  // the analysis does not fit
  const CommandResult r =
      tool("lazyboe-perturb", {"--bundle", out, "--perturbations", "2", "--quiet"}, limit);
  expect_one_line_error(r, {out + ": cannot write", "File too large"});
  EXPECT_EQ(read_file(out), before);
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"b.h5"});
}

// ---- an output is never an input --------------------------------------------------------

TEST(OutputIsNotAnInput, QueryRefusesToWriteOverItsBundleOrQueries) {
  const std::string dir = fresh_dir("out-query");
  const std::string bundle = copy_of_small_bundle(dir);
  const std::string queries = dir + "/q.jsonl";
  write_bytes(queries, "\n");
  fs::create_symlink(bundle, dir + "/link.h5");
  const auto before = snapshot(dir);
  for (const std::string& out : {bundle, dir + "/link.h5", dir + "/./bundle.h5"}) {
    const CommandResult r =
        tool("lazyboe-query", {"--bundle", bundle, "--queries", queries, "--out", out});
    expect_one_line_error(r, {"--out " + out, "--bundle " + bundle, "never replaces an input"});
  }
  const CommandResult r =
      tool("lazyboe-query", {"--bundle", bundle, "--queries", queries, "--out", queries});
  expect_one_line_error(r, {"--out " + queries, "--queries", "never replaces an input"});
  EXPECT_EQ(snapshot(dir), before);
}

TEST(OutputIsNotAnInput, RobotToolRefusesToWriteOverItsCsv) {
  const std::string dir = fresh_dir("out-robot");
  write_bytes(dir + "/x.csv",
              "q1,q2,q3,q4,q5,q6,q7,dq1,dq2,dq3,dq4,dq5,dq6,dq7,ddq1,ddq2,ddq3,ddq4,ddq5,ddq6,"
              "ddq7\n0,0,0,-1.5,0,1.5,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n");
  write_bytes(dir + "/c.csv", "q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1.5,0,1.5,0\n");
  const auto before = snapshot(dir);
  expect_one_line_error(
      tool("lazyboe-robot", {"torques", "--in", dir + "/x.csv", "--out", dir + "/x.csv"}),
      {"--out", "--in", "never replaces an input"});
  expect_one_line_error(
      tool("lazyboe-robot", {"check", "--in", "c.csv", "--out", "./c.csv"}, 0, dir),
      {"--out ./c.csv", "--in c.csv", "never replaces an input"});
  EXPECT_EQ(snapshot(dir), before);
  // A different output is fine.
  const CommandResult ok =
      tool("lazyboe-robot", {"check", "--in", "c.csv", "--out", "r.csv"}, 0, dir);
  EXPECT_EQ(ok.exit_code, 0) << describe(ok);
}

TEST(OutputIsNotAnInput, BuildRefusesToWriteOverItsEnvironmentEvenWithForce) {
  const std::string dir = fresh_dir("out-build");
  const std::string env = dir + "/env.json";
  fs::copy_file(source_path("data/environments/table.json"), env);
  const auto before = snapshot(dir);
  expect_one_line_error(
      tool("lazyboe-build", {"--edges", "5", "--env", env, "--out", env, "--force", "--quiet"}),
      {"--out " + env, "--env", "never replaces an input"});
  EXPECT_EQ(snapshot(dir), before);
}

}  // namespace
}  // namespace lazyboe::test
