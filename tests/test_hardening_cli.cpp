// Hostile input and faults, through the real tools (issue 15): a full disk (a file-size limit,
// `ulimit -f`, which needs no privilege), an output that is one of the inputs, numbers that are
// not numbers or out of range, directories given as files, damaged bundles. Every case must end
// in one line on stderr naming the file and field, a normal non-zero exit, and nothing lost.
//
// One small bundle (300 edges, perturbed) is built once per process and copied.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bench/report.h"
#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"
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
  cmd += watchdog(120) + quote(tool_path(name));
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

// The final write is what these tests fill the disk with: no checkpoint journal in between, or
// a slow (sanitizer) build writes one first and, rightly, keeps it for the resume.
const char* const kNoCheckpoint[2] = {"--checkpoint-seconds", "1000000"};

TEST(FullDisk, BuildPastTheFileSizeLimitFailsInOneLineAndLeavesNothing) {
  const std::string dir = fresh_dir("full-build");
  const std::string out = dir + "/out.h5";
  const CommandResult r =
      tool("lazyboe-build",
           {"--edges", "300", "--out", out, "--quiet", kNoCheckpoint[0], kNoCheckpoint[1]},
           /*file_limit_kib=*/100);
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
  const CommandResult r = tool(
      "lazyboe-build",
      {"--resume", "--edges", "400", "--out", out, "--quiet", kNoCheckpoint[0], kNoCheckpoint[1]},
      limit);
  expect_one_line_error(r, {out + ": cannot write", "File too large"});
  EXPECT_EQ(read_file(out), before);
  EXPECT_EQ(files_in(dir),
            (std::vector<std::string>{"out.h5", "out.h5.kd-index", "out.h5.ws-index"}));
}

TEST(FullDisk, PerturbPastTheLimitKeepsTheBundle) {
  const std::string dir = fresh_dir("full-perturb");
  const std::string out = dir + "/b.h5";
  ASSERT_EQ(tool("lazyboe-build", {"--edges", "300", "--out", out, "--quiet"}).exit_code, 0);
  const std::string before = read_file(out);
  const long limit = static_cast<long>(before.size() / 1024) + 1;  // the analysis does not fit
  const CommandResult r =
      tool("lazyboe-perturb",
           {"--bundle", out, "--perturbations", "2", "--quiet", kNoCheckpoint[0], kNoCheckpoint[1]},
           limit);
  expect_one_line_error(r, {out + ": cannot write", "File too large"});
  EXPECT_EQ(read_file(out), before);
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"b.h5", "b.h5.kd-index", "b.h5.ws-index"}));
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

// ---- numbers are parsed strictly and range-checked --------------------------------------

// A copy of the bundled Panda (config and URDF) in `dir`, with `edit` applied to the URDF text
// (first occurrence of `from` replaced by `to`); returns the config path.
std::string panda_with(const std::string& dir, const std::string& file, const std::string& from,
                       const std::string& to) {
  fs::copy_file(source_path("data/robots/panda.json"), dir + "/panda.json");
  fs::copy_file(source_path("data/robots/panda.urdf"), dir + "/panda.urdf");
  std::string text = read_file(dir + "/" + file);
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  write_bytes(dir + "/" + file, text);
  return dir + "/panda.json";
}

struct TextCase {
  std::string file, from, to;
  std::vector<std::string> needles;
};

TEST(StrictNumbers, UrdfValuesAreReadStrictlyNamingTheLinkOrJoint) {
  const std::vector<TextCase> cases = {
      {"panda.urdf",
       R"(<mass value="0.629769"/>)",
       R"(<mass value="abc"/>)",
       {"panda.urdf:27: link 'panda_link0' <mass value>", "'abc'", "[0, 100000] kg"}},
      {"panda.urdf",
       R"(<mass value="0.629769"/>)",
       R"(<mass value="4.97abc"/>)",
       {"link 'panda_link0' <mass value>", "'4.97abc'"}},
      {"panda.urdf",
       R"(ixx=")",
       R"(ixx="0.7x" ixx_was=")",
       {"link 'panda_link0' <inertia ixx>", "'0.7x'"}},
      {"panda.urdf",
       R"(<mass value="0.629769"/>)",
       R"(<mass value="1e308"/>)",
       {"link 'panda_link0' <mass value>", "1e+308", "outside", "[0, 100000] kg"}},
      {"panda.urdf",
       R"(effort=")",
       R"(effort="nan" was=")",
       {"joint 'panda_joint1' <limit effort>", "'nan'"}},
      {"panda.urdf",
       R"(<joint name="panda_joint1" type="revolute">)",
       R"(<joint name="panda_joint1" type="spherical">)",
       {"joint 'panda_joint1'", "unknown joint type 'spherical'"}},
      {"panda.urdf", R"(<limit )", R"(<limits )", {"joint 'panda_joint1'", "missing <limit>"}},
      {"panda.urdf",
       R"(<origin xyz="-0.041018 -0.00014 0.049974")",
       R"(<origin xyz="-0.041018 -0.00014")",
       {"link 'panda_link0' <origin xyz>", "expected 3 numbers"}},
      {"panda.json",
       R"("control_rate": )",
       R"("control_rate": 1e400, "x": )",
       {"panda.json:", "number out of range ('1e400')"}},
      {"panda.json",
       R"("margin": 0.)",
       R"("margin": 5.)",
       {"panda.json: collision.margin", "[0, 1] m"}},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    SCOPED_TRACE(cases[k].to);
    const std::string dir = fresh_dir("urdf-" + std::to_string(k));
    const std::string config = panda_with(dir, cases[k].file, cases[k].from, cases[k].to);
    expect_one_line_error(tool("lazyboe-robot", {"info", "--robot", config}), cases[k].needles);
  }
}

TEST(StrictNumbers, EnvironmentSizesAreRangeChecked) {
  const std::string dir = fresh_dir("env-range");
  std::string env = read_file(source_path("data/environments/table.json"));
  env.replace(env.find("[0.6, 1.2, 0.04]"), 16, "[1e308, 1.2, 0.04]");
  write_bytes(dir + "/env.json", env);
  write_bytes(dir + "/q.csv", "q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1.5,0,1.5,0\n");
  expect_one_line_error(
      tool("lazyboe-robot", {"check", "--env", "env.json", "--in", "q.csv", "--out", "r.csv"}, 0,
           dir),
      {"env.json: objects[1].size", "1e+308", "(0, 100] m"});
}

TEST(StrictNumbers, CsvCellsAndCommandLineNumbersAreDecimalOnly) {
  const std::string dir = fresh_dir("csv-hex");
  write_bytes(dir + "/q.csv", "q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1.5,0,1.5,0\n0x10,0,0,-1.5,0,1.5,0\n");
  expect_one_line_error(tool("lazyboe-robot", {"check", "--in", "q.csv", "--out", "r.csv"}, 0, dir),
                        {"q.csv:3: column 'q1'", "'0x10'"});
  EXPECT_FALSE(fs::exists(dir + "/r.csv"));
  expect_one_line_error(tool("lazyboe-robot", {"fk", "--q", "0x1,0,0,-1.5,0,1.5,0"}),
                        {"--q", "'0x1'"});
  for (const char* budget : {"nan", "inf", "0x10", "1e7", "-1", "5s"}) {
    const CommandResult r = tool(
        "lazyboe-bench", {"--bundle", small_bundle(), "--out", dir + "/study", "--budget", budget});
    EXPECT_GE(r.exit_code, 2) << describe(r);
    expect_one_line_error(r, {"--budget", "(0, 1000000] s"});
  }
  EXPECT_FALSE(fs::exists(dir + "/study"));
  // Integers too: CLI11 alone would read 0x10 as 16 and wrap -1 around to 2^64 - 1.
  const CommandResult hex = tool("lazyboe-robot", {"allowed-pairs", "--samples", "0x10"});
  EXPECT_GE(hex.exit_code, 2) << describe(hex);
  expect_one_line_error(hex, {"--samples", "whole number"});
  const CommandResult negative =
      tool("lazyboe-bench", {"--bundle", small_bundle(), "--out", dir + "/study", "--seed", "-1",
                             "--problems", "1", "--planners", "boe", "--budget", "0.1"});
  EXPECT_GE(negative.exit_code, 2) << describe(negative);
  expect_one_line_error(negative, {"--seed", "whole number >= 0"});
  EXPECT_FALSE(fs::exists(dir + "/study"));
}

TEST(StrictNumbers, QueryBudgetBeyondTheClockIsAnErrorLine) {
  const std::string dir = fresh_dir("budget");
  write_bytes(
      dir + "/q.jsonl",
      R"({"id": "a", "planner": "boe", "budget": 9.3e9, "start": [0, 0, 0, -1.5, 0, 1.5, 0], "goal": {"q": [0.3, 0, 0, -1.5, 0, 1.5, 0]}})"
      "\n"
      R"({"id": "b", "planner": "boe", "budget": 1, "budget": 2, "start": [0, 0, 0, -1.5, 0, 1.5, 0], "goal": {"q": [0.3, 0, 0, -1.5, 0, 1.5, 0]}})"
      "\n");
  const CommandResult r =
      tool("lazyboe-query", {"--bundle", small_bundle(), "--queries", dir + "/q.jsonl", "--quiet"});
  // Every query had an error: exit status 1 (the error results are written all the same).
  ASSERT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "every query had an error (2 of 2")) << r.err;
  std::istringstream lines(r.out);
  std::string a, b;
  std::getline(lines, a);
  std::getline(lines, b);
  EXPECT_TRUE(contains(a, "line 1: budget") && contains(a, "(0, 1000000] s")) << a;
  EXPECT_TRUE(contains(b, "line 2") && contains(b, "duplicate key 'budget'")) << b;
}

// ---- a directory is not a file ------------------------------------------------------------

TEST(DirectoryAsFile, EveryToolNamesItAsADirectory) {
  const std::string dir = fresh_dir("dir-as-file");
  fs::create_directory(dir + "/d");
  const std::string d = dir + "/d";
  write_bytes(dir + "/q.jsonl", "\n");
  expect_one_line_error(tool("lazyboe-query", {"--bundle", small_bundle(), "--queries", d, "--out",
                                               dir + "/r.jsonl", "--quiet"}),
                        {d, "is a directory"});
  EXPECT_FALSE(fs::exists(dir + "/r.jsonl"));
  expect_one_line_error(tool("lazyboe-robot", {"info", "--robot", d}), {d, "is a directory"});
  expect_one_line_error(
      tool("lazyboe-robot", {"check", "--env", d, "--in", d, "--out", dir + "/x"}),
      {d, "is a directory"});
  expect_one_line_error(tool("lazyboe-robot", {"check", "--in", d, "--out", dir + "/x"}),
                        {d, "is a directory"});
  expect_one_line_error(tool("lazyboe-build", {"--inspect", d}), {d, "is a directory"});
  // As an output: said at once, not after the work when the rename fails.
  expect_one_line_error(tool("lazyboe-build", {"--edges", "3", "--out", d, "--force", "--quiet"}),
                        {d, "cannot write: is a directory"});
  expect_one_line_error(tool("lazyboe-query", {"--bundle", small_bundle(), "--queries",
                                               dir + "/q.jsonl", "--out", d, "--quiet"}),
                        {d, "cannot write: is a directory"});
  const std::string cfg =
      panda_with(dir, "panda.json", R"("urdf": "panda.urdf")", R"("urdf": "d")");
  expect_one_line_error(tool("lazyboe-robot", {"info", "--robot", cfg}),
                        {dir + "/d", "URDF file", "is a directory"});
}

// The tool-wide options of lazyboe-robot go anywhere on the line.
TEST(RobotTool, ToolWideOptionsAfterTheSubcommand) {
  const CommandResult r =
      tool("lazyboe-robot", {"info", "--json", "--robot", source_path("data/robots/panda.json")});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "\"name\": \"panda\"")) << r.out;
}

// ---- one bundle validation, run by every tool on open ------------------------------------

// Overwrites element `index` of a contiguous dataset of doubles or uint64 in place (the bytes
// HDF5 reports for it), as a damaged or hand-edited file would have it.
template <typename T>
void poke(const std::string& path, const std::string& dataset, uint64_t index, T value) {
  const DatasetLocation loc = dataset_location(path, dataset);
  ASSERT_TRUE(loc.contiguous && loc.bytes >= (index + 1) * sizeof(T)) << dataset;
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(loc.file_offset + index * sizeof(T)));
  f.write(reinterpret_cast<const char*>(&value), sizeof(T));
  ASSERT_TRUE(f.good());
}

struct Damage {
  std::string name;
  std::function<void(const std::string&)> apply;
  std::vector<std::string> needles;
};

TEST(BundleValidation, EveryToolRefusesTheSameDamageNamingTheDataset) {
  const double nan = std::nan("");
  const std::vector<Damage> damages = {
      {"nan in q0",
       [&](const std::string& p) { poke<double>(p, "/edges/q0", 17, nan); },
       {"/edges/q0", "edge 2 joint 4", "nan"}},
      {"1e308 in q0",
       [](const std::string& p) { poke<double>(p, "/edges/q0", 3, 1e308); },
       {"/edges/q0", "edge 0 joint 4", "1e+308"}},
      {"nan in p_lazy_prop",
       [&](const std::string& p) { poke<double>(p, "/perturbation/p_lazy_prop", 5, nan); },
       {"/perturbation/p_lazy_prop", "edge 5", "[0, 1]"}},
      {"probability 2",
       [](const std::string& p) { poke<double>(p, "/perturbation/p_collision", 9, 2.0); },
       {"/perturbation/p_collision", "edge 9"}},
      {"sample_offset out of range",
       [](const std::string& p) { poke<uint64_t>(p, "/edges/sample_offset", 300, 1u << 30); },
       {"/edges/sample_offset", "last value"}},
      {"negative duration",
       [](const std::string& p) { poke<double>(p, "/edges/duration", 0, -1.0); },
       {"/edges/duration", "edge 0"}},
  };
  const std::string dir = fresh_dir("damage");
  write_bytes(dir + "/q.jsonl", "\n");
  for (size_t k = 0; k < damages.size(); ++k) {
    SCOPED_TRACE(damages[k].name);
    const std::string p = dir + "/b" + std::to_string(k) + ".h5";
    fs::copy_file(small_bundle(), p);
    damages[k].apply(p);
    const std::string before = read_file(p);
    std::vector<std::string> needles = damages[k].needles;
    needles.insert(needles.begin(), p);
    expect_one_line_error(tool("lazyboe-build", {"--inspect", p}), needles);
    expect_one_line_error(tool("lazyboe-perturb", {"--bundle", p, "--quiet"}), needles);
    expect_one_line_error(
        tool("lazyboe-query", {"--bundle", p, "--queries", dir + "/q.jsonl", "--quiet"}), needles);
    expect_one_line_error(tool("lazyboe-query", {"--bundle", p, "--queries", dir + "/q.jsonl",
                                                 "--no-mmap", "--quiet"}),
                          needles);
    expect_one_line_error(
        tool("lazyboe-bench",
             {"--bundle", p, "--out", dir + "/study" + std::to_string(k), "--problems", "1",
              "--budget", "0.1", "--planners", "boe", "--quiet", "--no-figures"}),
        needles);
    EXPECT_EQ(read_file(p), before);
  }
}

// ---- messages -----------------------------------------------------------------------------

TEST(Messages, UnwritableOutputNamesTheOutputWithoutHdf5Text) {
  const std::string dir = fresh_dir("unwritable");
  const std::string out = dir + "/missing-dir/b.h5";
  const CommandResult r = tool("lazyboe-build", {"--edges", "5", "--out", out, "--quiet"});
  expect_one_line_error(r, {out + ": cannot write: No such file or directory"});
  EXPECT_FALSE(contains(r.err, "HDF5")) << r.err;
  EXPECT_FALSE(contains(r.err, ".tmp.")) << r.err;
}

TEST(Messages, MovedRobotConfigSaysWhereThePathCameFrom) {
  const std::string dir = fresh_dir("moved");
  fs::create_directory(dir + "/robot");
  fs::copy_file(source_path("data/robots/panda.json"), dir + "/robot/panda.json");
  fs::copy_file(source_path("data/robots/panda.urdf"), dir + "/robot/panda.urdf");
  ASSERT_EQ(
      tool("lazyboe-build",
           {"--edges", "5", "--robot", "robot/panda.json", "--out", "b.h5", "--quiet"}, 0, dir)
          .exit_code,
      0);
  fs::rename(dir + "/robot", dir + "/moved");
  write_bytes(dir + "/q.jsonl", "\n");
  expect_one_line_error(tool("lazyboe-query", {"--bundle", "b.h5", "--queries", "q.jsonl"}, 0, dir),
                        {"robot/panda.json", "recorded in the bundle", "--robot"});
  const CommandResult ok =
      tool("lazyboe-query",
           {"--bundle", "b.h5", "--queries", "q.jsonl", "--robot", "moved/panda.json", "--quiet"},
           0, dir);
  EXPECT_EQ(ok.exit_code, 0) << describe(ok);
}

// ---- interruption ---------------------------------------------------------------------------

// SIGTERM in the middle of `check` (100000 rows take seconds) leaves neither the output nor its
// temporary file.
TEST(Interruption, RobotCheckStoppedBySigtermLeavesNothing) {
  const std::string dir = fresh_dir("check-term");
  std::string csv = "q1,q2,q3,q4,q5,q6,q7\n";
  for (int k = 0; k < 100000; ++k)
    csv += std::to_string(-1.0 + 2.0 * (k % 1000) / 1000) + ",0.1,0,-1.5,0,1.5," +
           std::to_string(0.001 * (k % 97)) + "\n";
  write_bytes(dir + "/q.csv", csv);
  // The signal is sent once the tool's handler is installed (SIGTERM's bit, 0x4000, in the
  // SigCgt mask of /proc/PID/status): under the sanitizers the start-up alone can take seconds,
  // and a signal before it would end the process by the default action (exit 143).
  const CommandResult r = run(
      "cd " + quote(dir) + " && (" + quote(tool_path("lazyboe-robot")) +
      " check --in q.csv --out r.csv & pid=$!; "
      "until m=$(sed -n 's/^SigCgt:[[:space:]]*//p' /proc/$pid/status 2>/dev/null) && "
      "[ -n \"$m\" ] && [ $((0x$m & 0x4000)) -ne 0 ]; do kill -0 $pid || break; sleep 0.01; done; "
      "sleep 0.5; kill -TERM $pid; wait $pid)");
  EXPECT_EQ(r.exit_code, 130) << describe(r);
  EXPECT_TRUE(contains(r.err, "interrupted")) << r.err;
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"q.csv"});
}

// ---- checksums --------------------------------------------------------------------------

TEST(Checksums, VerifyFindsAChangedSampleThatNoRangeCheckCatches) {
  const std::string dir = fresh_dir("verify");
  const std::string p = copy_of_small_bundle(dir);
  const CommandResult ok = tool("lazyboe-build", {"--verify", p});
  EXPECT_EQ(ok.exit_code, 0) << describe(ok);
  EXPECT_TRUE(contains(ok.out, p + ": verified (all 20 datasets verify")) << ok.out;
  EXPECT_TRUE(
      contains(tool("lazyboe-build", {"--inspect", p}).out, "checksums: all 20 datasets verify"));

  poke<float>(p, "/trajectory/q", 100,
              0.125f);  // plausible, finite, in range: only a checksum sees it
  expect_one_line_error(tool("lazyboe-build", {"--verify", p}),
                        {p, "/trajectory/q: checksum mismatch", "damaged"});
  const CommandResult inspect = tool("lazyboe-build", {"--inspect", p});
  EXPECT_EQ(inspect.exit_code, 0) << describe(inspect);
  EXPECT_TRUE(contains(inspect.out, "checksums: MISMATCH in /trajectory/q")) << inspect.out;
}

// The same build twice gives the same bytes except the wall_seconds attribute (the one
// timing in an unperturbed bundle): schemas/bundle.md states exactly this.
TEST(Checksums, RepeatedBuildDiffersOnlyInWallSeconds) {
  const std::string dir = fresh_dir("twice");
  for (const char* name : {"a.h5", "b.h5"})
    ASSERT_EQ(
        tool("lazyboe-build", {"--edges", "30", "--out", dir + "/" + name, "--quiet"}).exit_code,
        0);
  EXPECT_TRUE(same_bundle_but_timings(dir + "/a.h5", dir + "/b.h5", 1));
}

// The runs file `lazyboe-bench --resume` reads: numbers strictly too.
TEST(StrictNumbers, ResumedRunsFileRefusesHexAndNan) {
  const std::string dir = fresh_dir("runs");
  std::string header;
  for (const std::string& c : runs_csv_header()) header += (header.empty() ? "" : ",") + c;
  for (const char* bad : {"0x10", "nan", "inf", "-1"}) {
    SCOPED_TRACE(bad);
    const std::string path = dir + "/runs.csv";
    // A valid row as the writer makes it, with the time to first solution replaced.
    RunRecord r;
    r.planner = "boe";
    r.success = true;
    r.time_to_first_solution = 0.25;
    r.best_cost = 1.5;
    r.budget = 5;
    std::string row = runs_csv_row(r, "p1");
    const size_t column = static_cast<size_t>(
        std::find(runs_csv_header().begin(), runs_csv_header().end(), "time_to_first_solution") -
        runs_csv_header().begin());
    size_t from = 0;
    for (size_t c = 0; c < column; ++c) from = row.find(',', from) + 1;
    row.replace(from, row.find(',', from) - from, bad);
    write_bytes(path, header + "\n" + row + "\n");
    std::string message;
    try {
      read_runs_csv(path, {"p1"});
    } catch (const Error& e) {
      message = e.what();
    }
    EXPECT_TRUE(contains(message, path + ": line 2") &&
                contains(message, "time_to_first_solution") && contains(message, bad))
        << message;
  }
}

// ---- the shared parsers, directly -------------------------------------------------------

TEST(StrictParsers, DecimalNumbersOnly) {
  double v = -7;
  for (const char* good : {"0", "-1", "+2.5", "1.", ".5", "1e3", "1E-3", "-0.0", "1e-400"}) {
    EXPECT_TRUE(parse_decimal(good, v)) << good;
  }
  EXPECT_TRUE(parse_decimal("2.5e1", v));
  EXPECT_EQ(v, 25.0);
  for (const char* bad : {"", " 1", "1 ", "0x10", "inf", "-inf", "nan", "1e400", "1e", "e5", ".",
                          "1.2.3", "4.97abc", "--1", "1,5"}) {
    EXPECT_FALSE(parse_decimal(bad, v)) << bad;
  }
  EXPECT_EQ(RealRange({0, 1, true}).text(), "(0, 1]");
  EXPECT_EQ(RealRange({-100, 100}).text(), "[-100, 100]");
}

TEST(StrictParsers, DuplicateKeysAreRefusedWithTheirPath) {
  const auto message = [](const std::string& text) {
    try {
      parse_json_text(text, "f.json", true);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(message(R"({"a": 1, "a": 2})"),
            "f.json: duplicate key 'a' (each key may appear once in an object)");
  EXPECT_EQ(message(R"({"objects": [{"x": 1}, {"y": [1, {"z": 1, "z": 2}]}]})"),
            "f.json: objects[1].y[1]: duplicate key 'z' (each key may appear once in an object)");
  EXPECT_EQ(message(R"({"a": {"b": 1}, "c": {"b": 1}})"), "(no error)");  // other objects
  EXPECT_EQ(message("{\n  \"a\": 1e400\n}"), "f.json:2:12: number out of range ('1e400')");
  EXPECT_EQ(message("{\n  \"a\": \n}"), "f.json:3:1: invalid JSON");
}

}  // namespace
}  // namespace lazyboe::test
