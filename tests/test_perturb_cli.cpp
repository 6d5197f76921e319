// End-to-end tests of the lazyboe-perturb command-line tool: real bundles made by lazyboe-build
// are analysed by the real binary and read back with the library (and, for the layout of the
// /perturbation group, with the HDF5 C API directly).
// Covered: the per-edge numbers and their invariants, the group attributes and the summary;
// the same numbers whatever the thread count; extending p, re-running a complete analysis, the
// refusals of fewer perturbations / another theta / another seed and --replace; SIGINT and
// SIGKILL in the middle of a run (test_perturb_resume_cli.cpp); one-line errors for
// bad input that leave the bundle untouched; robot and environment checked by content; the
// physics in broad strokes.
//
// Run time matters (the whole file should stay well under a minute on two cores; about 900
// rollouts/s with two threads; about 17000 rollouts in all): input bundles of 100-300 edges are
// built once per test binary and copied, and each uninterrupted reference analysis is run once
// and cached.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/bundle/perturbation.h"
#include "perturb_cli_util.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// ------------------------------------------------------------------------------------------
// 1. A basic run
// ------------------------------------------------------------------------------------------

constexpr uint64_t kBasicEdges = 300, kBasicSeed = 21, kBasicP = 8;

struct Hdf5Check {
  bool exists = false;
  bool type_ok = false;
  std::vector<hsize_t> dims;
};

Hdf5Check dataset_check(hid_t file, const char* name, hid_t expected_type) {
  Hdf5Check c;
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0) return c;
  const hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
  if (ds < 0) return c;
  c.exists = true;
  const hid_t space = H5Dget_space(ds);
  const int rank = H5Sget_simple_extent_ndims(space);
  c.dims.resize(std::max(rank, 0));
  if (rank > 0) H5Sget_simple_extent_dims(space, c.dims.data(), nullptr);
  H5Sclose(space);
  const hid_t type = H5Dget_type(ds);
  c.type_ok = H5Tequal(type, expected_type) > 0;
  H5Tclose(type);
  H5Dclose(ds);
  return c;
}

// The attribute's type class, or -1 when it is missing.
int attribute_class(hid_t group, const char* name) {
  if (H5Aexists(group, name) <= 0) return -1;
  const hid_t a = H5Aopen(group, name, H5P_DEFAULT);
  if (a < 0) return -1;
  const hid_t t = H5Aget_type(a);
  const int c = static_cast<int>(H5Tget_class(t));
  H5Tclose(t);
  H5Aclose(a);
  return c;
}

// The run of the basic test (not quiet), made once: the physics test looks at it too.
struct BasicRun {
  std::string path;
  std::vector<std::string> files;  // in its directory afterwards
  CommandResult result;
  Bundle before, after;
};

const BasicRun& basic_run() {
  static BasicRun run;
  static bool done = false;
  if (done) return run;
  done = true;
  const std::string& input = input_bundle(kBasicEdges, kBasicSeed, "table.json");
  run.before = read_bundle(input);
  const std::string dir = fresh_dir("basic");
  run.path = dir + "/b.h5";
  copy_bundle(input, run.path);
  run.result = perturb_tool(
      {"--bundle", run.path, "--perturbations", std::to_string(kBasicP), "--threads", "2"});
  run.files = files_in(dir);
  run.after = read_bundle(run.path);
  return run;
}

TEST(PerturbCli, BasicRunWritesConsistentProbabilities) {
  const BasicRun& run = basic_run();
  const Bundle& before = run.before;
  const CommandResult& r = run.result;
  const std::string& path = run.path;
  ASSERT_EQ(before.size(), kBasicEdges);
  ASSERT_FALSE(before.perturbation.present);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(run.files, std::vector<std::string>{"b.h5"});

  const Bundle& after = run.after;
  expect_same_edges(after, before);
  const Perturbation& p = after.perturbation;
  ASSERT_TRUE(p.present);
  EXPECT_TRUE(p.complete);
  EXPECT_TRUE(same_double(p.theta, before.header.design_theta))
      << "theta " << p.theta << " is not the bundle's design theta " << before.header.design_theta;
  EXPECT_EQ(p.perturbations, kBasicP);
  EXPECT_EQ(p.seed, 1u) << "the default seed";
  EXPECT_GT(p.simulated_seconds, 0);
  EXPECT_GT(p.wall_seconds, 0);
  EXPECT_EQ(check_invariants(after), kBasicEdges);
  for (size_t e = 0; e < after.size(); ++e) {
    ASSERT_EQ(p.done[e], kBasicP) << "edge " << e;
  }

  // The layout of /perturbation, with the HDF5 C API.
  {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(file, 0) << path;
    const hid_t g = H5Gopen2(file, "/perturbation", H5P_DEFAULT);
    EXPECT_GE(g, 0) << "/perturbation is not a group";
    if (g >= 0) {
      EXPECT_EQ(attribute_class(g, "complete"), H5T_INTEGER);
      EXPECT_EQ(attribute_class(g, "theta"), H5T_FLOAT);
      EXPECT_EQ(attribute_class(g, "perturbations"), H5T_INTEGER);
      EXPECT_EQ(attribute_class(g, "seed"), H5T_INTEGER);
      EXPECT_EQ(attribute_class(g, "distribution"), H5T_STRING);
      EXPECT_EQ(attribute_class(g, "wall_seconds"), H5T_FLOAT);
      EXPECT_EQ(attribute_class(g, "simulated_seconds"), H5T_FLOAT);
      H5Gclose(g);
    }
    const struct {
      const char* name;
      hid_t type;
    } expected[] = {
        {"/perturbation/done", H5T_STD_U64LE},
        {"/perturbation/valid", H5T_STD_U64LE},
        {"/perturbation/lazy", H5T_STD_U64LE},
        {"/perturbation/collision", H5T_STD_U64LE},
        {"/perturbation/max_error", H5T_IEEE_F64LE},
        {"/perturbation/p_lazy_prop", H5T_IEEE_F64LE},
        {"/perturbation/p_collision", H5T_IEEE_F64LE},
        {"/perturbation/transfer_lazy", H5T_STD_U64LE},
        {"/perturbation/transfer_max_error", H5T_IEEE_F64LE},
        {"/perturbation/p_lazy_prop_transfer", H5T_IEEE_F64LE},
    };
    for (const auto& e : expected) {
      SCOPED_TRACE(e.name);
      const Hdf5Check c = dataset_check(file, e.name, e.type);
      ASSERT_TRUE(c.exists);
      EXPECT_TRUE(c.type_ok) << "element type";
      EXPECT_EQ(c.dims, std::vector<hsize_t>{kBasicEdges});
    }
    H5Fclose(file);
  }

  // The summary on stdout: both histograms (10 bins each) and the share of usable edges.
  EXPECT_TRUE(contains(r.out, "P_lazy_prop")) << r.out;
  EXPECT_TRUE(contains(r.out, "P_collision")) << r.out;
  EXPECT_TRUE(contains(r.out, "usable for lazy propagation")) << r.out;
  EXPECT_TRUE(contains(r.out, "P_lazy_prop under transfer")) << r.out;
  EXPECT_TRUE(contains(r.out, "max transfer residual")) << r.out;
  std::istringstream lines(r.out);
  std::string line;
  int bins = 0, last_bins = 0;
  while (std::getline(lines, line)) {
    const size_t first = line.find_first_not_of(' ');
    if (first != std::string::npos && line[first] == '[') ++bins;
    if (contains(line, "1.000]")) ++last_bins;
  }
  EXPECT_EQ(bins, 20) << "expected two 10-bin histograms:\n" << r.out;
  EXPECT_EQ(last_bins, 2) << "expected two histograms ending at 1:\n" << r.out;
  EXPECT_FALSE(contains(r.err, "error")) << r.err;
}

// ------------------------------------------------------------------------------------------
// 2. Determinism
// ------------------------------------------------------------------------------------------

constexpr uint64_t kSmallEdges = 120, kSmallSeed = 22;

TEST(PerturbCli, SameNumbersWhateverTheThreadCount) {
  const std::string& input = input_bundle(kSmallEdges, kSmallSeed);
  const std::string dir = fresh_dir("threads");
  const std::string one = dir + "/one.h5";
  copy_bundle(input, one);
  const CommandResult r = perturb_tool(
      {"--bundle", one, "--perturbations", "4", "--seed", "3", "--threads", "1", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "");
  const Bundle a = read_bundle(one);
  const Bundle& b = reference(input, {"--perturbations", "4", "--seed", "3"});  // 2 threads
  EXPECT_TRUE(a.perturbation.complete);
  EXPECT_EQ(check_invariants(a), kSmallEdges);
  expect_same_perturbation(a.perturbation, b.perturbation);
  EXPECT_TRUE(same_double(a.perturbation.simulated_seconds, b.perturbation.simulated_seconds))
      << "same split, same sum expected";
  expect_same_edges(a, b);
}

// ------------------------------------------------------------------------------------------
// 3. Extending, re-running, refusing, replacing
// ------------------------------------------------------------------------------------------

TEST(PerturbCli, ExtendRerunRefuseAndReplace) {
  const std::string& input = input_bundle(kSmallEdges, kSmallSeed);
  const Bundle original = read_bundle(input);
  const std::string dir = fresh_dir("extend");
  const std::string path = dir + "/b.h5";
  copy_bundle(input, path);

  // p = 4, then p = 8 with the same seed and theta: equal to a fresh p = 8 run.
  {
    const CommandResult r4 = perturb_tool(
        {"--bundle", path, "--perturbations", "4", "--seed", "3", "--threads", "2", "--quiet"});
    ASSERT_EQ(r4.exit_code, 0) << describe(r4);
    const Bundle b4 = read_bundle(path);
    EXPECT_EQ(b4.perturbation.perturbations, 4u);
    expect_same_perturbation(
        b4.perturbation, reference(input, {"--perturbations", "4", "--seed", "3"}).perturbation);
    const CommandResult r8 = perturb_tool(
        {"--bundle", path, "--perturbations", "8", "--seed", "3", "--threads", "2", "--quiet"});
    ASSERT_EQ(r8.exit_code, 0) << describe(r8);
    const Bundle b8 = read_bundle(path);
    EXPECT_TRUE(b8.perturbation.complete);
    EXPECT_EQ(check_invariants(b8), kSmallEdges);
    expect_same_perturbation(
        b8.perturbation, reference(input, {"--perturbations", "8", "--seed", "3"}).perturbation);
    expect_same_edges(b8, original);
  }

  // The same settings again on a complete analysis: says so, changes nothing.
  {
    const Bundle before = read_bundle(path);
    const CommandResult again =
        perturb_tool({"--bundle", path, "--perturbations", "8", "--seed", "3", "--threads", "2"});
    ASSERT_EQ(again.exit_code, 0) << describe(again);
    EXPECT_TRUE(contains(again.err, "already")) << describe(again);
    EXPECT_TRUE(contains(again.err, path)) << describe(again);
    const Bundle after = read_bundle(path);
    expect_same_perturbation(after.perturbation, before.perturbation, /*work=*/true);
    expect_same_edges(after, original);
    EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
  }

  // Refusals: one line naming the file and how to get past it, the file's bytes unchanged.
  const struct {
    const char* name;
    std::vector<std::string> args;
    std::vector<std::string> needles;
  } refusals[] = {
      {"fewer perturbations", {"--perturbations", "4", "--seed", "3"}, {"--replace"}},
      {"another theta",
       {"--perturbations", "8", "--seed", "3", "--theta", "0.3"},
       {"--replace", "theta"}},
      {"another seed", {"--perturbations", "8", "--seed", "4"}, {"--replace", "--seed"}},
      {"another seed and more perturbations",
       {"--perturbations", "12", "--seed", "4"},
       {"--replace", "--seed"}},
  };
  for (const auto& refusal : refusals) {
    SCOPED_TRACE(refusal.name);
    const auto before = snapshot(dir);
    std::vector<std::string> args = {"--bundle", path, "--threads", "2"};
    args.insert(args.end(), refusal.args.begin(), refusal.args.end());
    const CommandResult r = perturb_tool(args, 20);
    std::vector<std::string> needles = refusal.needles;
    needles.push_back(path);
    expect_one_line_error(r, needles);
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_TRUE(snapshot(dir) == before) << "the directory changed: " << join(files_in(dir));
  }

  // --replace: equal to a fresh run with the new settings.
  {
    const CommandResult r =
        perturb_tool({"--bundle", path, "--replace", "--theta", "0.3", "--perturbations", "4",
                      "--seed", "3", "--threads", "2", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    const Bundle b = read_bundle(path);
    EXPECT_TRUE(same_double(b.perturbation.theta, 0.3));
    expect_same_perturbation(
        b.perturbation,
        reference(input, {"--theta", "0.3", "--perturbations", "4", "--seed", "3"}).perturbation);
    expect_same_edges(b, original);
  }
  {
    // Back to the design theta (not given: the default) with another seed.
    const CommandResult r = perturb_tool({"--bundle", path, "--replace", "--perturbations", "4",
                                          "--seed", "4", "--threads", "2", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    const Bundle b = read_bundle(path);
    EXPECT_TRUE(same_double(b.perturbation.theta, original.header.design_theta));
    expect_same_perturbation(
        b.perturbation, reference(input, {"--perturbations", "4", "--seed", "4"}).perturbation);
    expect_same_edges(b, original);
    // A different seed gives different perturbations (the counts of some edge differ).
    const Perturbation& s3 = reference(input, {"--perturbations", "4", "--seed", "3"}).perturbation;
    EXPECT_FALSE(same_array("max_error", b.perturbation.max_error, s3.max_error))
        << "seeds 3 and 4 gave the same errors";
  }
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
}

// An analysis written before the transfer statistics (the same file without their three
// datasets, as an older lazyboe-perturb wrote it) opens everywhere without them;
// lazyboe-perturb keeps it (saying what it lacks), refuses to extend it in place, and redoes it
// with --replace to the numbers of a straight run.
TEST(PerturbCli, AnalysisWithoutTransferStatisticsOpensAndIsKeptOrReplaced) {
  const std::string& input = input_bundle(kSmallEdges, kSmallSeed);
  const Bundle original = read_bundle(input);
  const std::string dir = fresh_dir("old-analysis");
  const std::string path = dir + "/b.h5";
  const std::vector<std::string> settings = {"--perturbations", "4", "--seed", "3"};
  const Bundle& straight = reference(input, settings);
  auto make_old = [&] {
    Bundle old = straight;
    old.perturbation.has_transfer = false;
    old.perturbation.transfer_lazy.clear();
    old.perturbation.transfer_max_error.clear();
    old.perturbation.p_lazy_prop_transfer.clear();
    write_bundle(path, old);
  };
  make_old();
  {
    const Bundle b = read_bundle(path);
    ASSERT_TRUE(b.perturbation.present);
    ASSERT_FALSE(b.perturbation.has_transfer);
    const BundleView view = BundleView::open(path);
    EXPECT_TRUE(view.has_perturbation());
    EXPECT_FALSE(view.has_transfer());
    EXPECT_TRUE(view.warnings().empty());
  }
  {
    const CommandResult inspect = build_tool({"--inspect", path});
    ASSERT_EQ(inspect.exit_code, 0) << describe(inspect);
    EXPECT_TRUE(contains(inspect.out, "P_lazy_prop")) << inspect.out;
    EXPECT_TRUE(contains(inspect.out, "transfer statistics: none")) << inspect.out;
  }
  {
    // lazyboe's query on it: a start and goal of one edge.
    const int n = original.dof();
    auto vec = [&](const std::vector<double>& q) {
      std::string s = "[";
      for (int i = 0; i < n; ++i) s += (i ? "," : "") + std::to_string(q[i]);
      return s + "]";
    };
    const std::vector<double> q0(original.q0.begin(), original.q0.begin() + n);
    const std::vector<double> qf(original.qf.begin(), original.qf.begin() + n);
    const std::string queries = dir + "/q.jsonl";
    write_bytes(queries, "{\"id\":\"old\",\"start\":" + vec(q0) + ",\"goal\":{\"q\":" + vec(qf) +
                             ",\"tolerance\":0.3},\"planner\":\"lazyboe\",\"budget\":1,"
                             "\"seed\":1,\"stop_at_first\":true}\n");
    const CommandResult q = run(
        tool_command("lazyboe-query", {"--bundle", path, "--queries", queries, "--out", "-"}, 60));
    EXPECT_EQ(q.exit_code, 0) << describe(q);
    EXPECT_TRUE(contains(q.out, "\"old\"")) << describe(q);
  }
  // Continuing it with its own settings: nothing to do; it is kept, and the note says what it
  // lacks, once.
  {
    make_old();
    const CommandResult r =
        perturb_tool({"--bundle", path, "--perturbations", "4", "--seed", "3", "--threads", "2"});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    size_t notes = 0;
    for (size_t at = r.err.find("no transfer statistics"); at != std::string::npos;
         at = r.err.find("no transfer statistics", at + 1))
      ++notes;
    EXPECT_EQ(notes, 1u) << r.err;
    EXPECT_TRUE(contains(r.err, "--replace")) << r.err;
    const Bundle b = read_bundle(path);
    EXPECT_TRUE(b.perturbation.complete);
    EXPECT_FALSE(b.perturbation.has_transfer);
    expect_same_edges(b, original);
  }
  // Extending it in place is refused (it would be redone, checkpointing an incomplete analysis
  // over the complete one); --replace redoes it, to a straight run's numbers.
  {
    make_old();
    const auto before = snapshot(dir);
    const CommandResult more =
        perturb_tool({"--bundle", path, "--perturbations", "8", "--seed", "3", "--threads", "2"});
    expect_one_line_error(more, {"--replace", path, "transfer statistics"});
    EXPECT_TRUE(snapshot(dir) == before);
    const CommandResult r = perturb_tool(
        {"--bundle", path, "--perturbations", "8", "--seed", "3", "--threads", "2", "--replace"});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    const Bundle b = read_bundle(path);
    EXPECT_TRUE(b.perturbation.complete);
    EXPECT_TRUE(b.perturbation.has_transfer);
    EXPECT_EQ(check_invariants(b), kSmallEdges);
    expect_same_perturbation(
        b.perturbation, reference(input, {"--perturbations", "8", "--seed", "3"}).perturbation);
    expect_same_edges(b, original);
  }
  // Fewer perturbations than it holds, or other settings, are refused as for any analysis.
  make_old();
  const auto before = snapshot(dir);
  const CommandResult fewer =
      perturb_tool({"--bundle", path, "--perturbations", "2", "--seed", "3", "--threads", "2"});
  expect_one_line_error(fewer, {"--replace", path});
  EXPECT_TRUE(snapshot(dir) == before);
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
}

// ------------------------------------------------------------------------------------------
// 5. Refusals
// ------------------------------------------------------------------------------------------

enum class Exit { One, CommandLine, Either };  // 1; >= 2 (CLI11); either of them

struct BadCase {
  std::string name;
  std::vector<std::string> args;     // @BUNDLE: the copied bundle; @DIR: the case's directory
  std::vector<std::string> needles;  // all must appear in the one line on stderr
  Exit exit = Exit::One;
  std::function<void(const std::string& dir)> setup = nullptr;
};

std::string expand(const std::string& s, const std::string& dir) {
  if (s.rfind("@BUNDLE", 0) == 0) return dir + "/b.h5" + s.substr(7);
  if (s.rfind("@DIR", 0) == 0) return dir + s.substr(4);
  return s;
}

void expect_refused(const BadCase& c, const std::string& input, const std::string& dir_name) {
  SCOPED_TRACE(c.name);
  const std::string dir = fresh_dir(dir_name);
  copy_bundle(input, dir + "/b.h5");
  if (c.setup) c.setup(dir);
  const auto before = snapshot(dir);
  std::vector<std::string> args, needles;
  for (const std::string& a : c.args) args.push_back(expand(a, dir));
  for (const std::string& n : c.needles) needles.push_back(expand(n, dir));
  const CommandResult r = perturb_tool_in(dir, args);
  expect_one_line_error(r, needles);
  switch (c.exit) {
    case Exit::One:
      EXPECT_EQ(r.exit_code, 1) << describe(r);
      break;
    case Exit::CommandLine:
      EXPECT_GE(r.exit_code, 2) << describe(r);
      break;
    case Exit::Either:
      EXPECT_GE(r.exit_code, 1) << describe(r);
      break;
  }
  const auto after = snapshot(dir);
  std::vector<std::string> names_before, names_after;
  for (const auto& [name, bytes] : before) names_before.push_back(name);
  for (const auto& [name, bytes] : after) names_after.push_back(name);
  EXPECT_EQ(names_after, names_before) << "files written or removed";
  EXPECT_TRUE(after == before) << "a file was changed";
}

// A copy of the Panda's config and URDF in `dir`; `edit` may change the URDF text.
void copy_robot(const std::string& dir, const std::function<void(std::string&)>& edit = nullptr) {
  fs::copy_file(source_path("data/robots/panda.json"), dir + "/panda.json",
                fs::copy_options::overwrite_existing);
  std::string urdf = read_file(source_path("data/robots/panda.urdf"));
  if (edit) edit(urdf);
  write_bytes(dir + "/panda.urdf", urdf);
}

// One mass of the URDF, changed: 0.629769 -> 0.639769 kg (still a perfectly valid robot).
void change_a_mass(std::string& urdf) {
  const std::string from = "<mass value=\"0.629769\"/>", to = "<mass value=\"0.639769\"/>";
  const size_t at = urdf.find(from);
  ASSERT_NE(at, std::string::npos) << "test setup: the URDF has no mass 0.629769 any more";
  urdf.replace(at, from.size(), to);
}

constexpr uint64_t kTinyEdges = 100, kTinySeed = 24;

TEST(PerturbCli, BadInputIsOneLineAndChangesNothing) {
  const std::string& input = input_bundle(kTinyEdges, kTinySeed);
  const std::vector<BadCase> cases = {
      {"missing --bundle", {"--perturbations", "4"}, {"--bundle"}, Exit::CommandLine},
      {"missing file", {"--bundle", "@DIR/missing.h5"}, {"@DIR/missing.h5"}},
      {"not an HDF5 file",
       {"--bundle", "@DIR/garbage.h5"},
       {"@DIR/garbage.h5"},
       Exit::One,
       [](const std::string& dir) { write_bytes(dir + "/garbage.h5", garbage_bytes()); }},
      {"empty file",
       {"--bundle", "@DIR/empty.h5"},
       {"@DIR/empty.h5"},
       Exit::One,
       [](const std::string& dir) { write_bytes(dir + "/empty.h5", ""); }},
      {"incomplete bundle",
       {"--bundle", "@DIR/incomplete.h5"},
       {"@DIR/incomplete.h5", "lazyboe-build --resume"},
       Exit::One,
       [&input](const std::string& dir) {
         Bundle b = read_bundle(input);
         b.header.complete = false;
         b.header.target_edges = 2 * b.size();
         write_bundle(dir + "/incomplete.h5", b);
       }},
      {"another robot (one mass changed)",
       {"--bundle", "@BUNDLE", "--robot", "@DIR/panda.json"},
       {"@DIR/panda.json", "not the robot"},
       Exit::One,
       [](const std::string& dir) { copy_robot(dir, change_a_mass); }},
      {"another environment",
       {"--bundle", "@BUNDLE", "--env", env_file("shelf.json")},
       {"shelf.json", "not the environment"}},
      {"missing robot file",
       {"--bundle", "@BUNDLE", "--robot", "@DIR/nope.json"},
       {"@DIR/nope.json"}},
      {"missing environment file",
       {"--bundle", "@BUNDLE", "--env", "@DIR/nope.json"},
       {"@DIR/nope.json"}},
      {"perturbations 0",
       {"--bundle", "@BUNDLE", "--perturbations", "0"},
       {"--perturbations"},
       Exit::CommandLine},
      {"perturbations -1",
       {"--bundle", "@BUNDLE", "--perturbations", "-1"},
       {"--perturbations"},
       Exit::CommandLine},
      {"perturbations abc",
       {"--bundle", "@BUNDLE", "--perturbations", "abc"},
       {"--perturbations"},
       Exit::CommandLine},
      {"perturbations too many",
       {"--bundle", "@BUNDLE", "--perturbations", "16777216"},
       {"--perturbations"},
       Exit::Either},
      {"theta -1", {"--bundle", "@BUNDLE", "--theta", "-1"}, {"--theta"}, Exit::Either},
      {"theta 0", {"--bundle", "@BUNDLE", "--theta", "0"}, {"--theta"}, Exit::Either},
      {"theta nan", {"--bundle", "@BUNDLE", "--theta", "nan"}, {"--theta"}, Exit::Either},
      {"theta abc", {"--bundle", "@BUNDLE", "--theta", "abc"}, {"--theta"}, Exit::CommandLine},
      {"seed -3", {"--bundle", "@BUNDLE", "--seed", "-3"}, {"--seed"}, Exit::CommandLine},
      {"threads x", {"--bundle", "@BUNDLE", "--threads", "x"}, {"--threads"}, Exit::CommandLine},
      {"checkpoint -1",
       {"--bundle", "@BUNDLE", "--checkpoint-seconds", "-1"},
       {"--checkpoint-seconds"},
       Exit::CommandLine},
      {"unknown option", {"--bundle", "@BUNDLE", "--bogus"}, {"--bogus"}, Exit::CommandLine},
  };
  for (size_t k = 0; k < cases.size(); ++k)
    expect_refused(cases[k], input, "bad-" + std::to_string(k));
}

// The robot and environment are checked by content, not by path: identical copies elsewhere
// are accepted, a copy with one number changed is not (above).
TEST(PerturbCli, RobotAndEnvironmentAreCheckedByContent) {
  const std::string& input = input_bundle(kTinyEdges, kTinySeed);
  const std::string dir = fresh_dir("copies");
  const std::string path = dir + "/b.h5";
  copy_bundle(input, path);
  copy_robot(dir);
  fs::copy_file(env_file("table.json"), dir + "/table.json");
  const CommandResult r =
      perturb_tool({"--bundle", path, "--robot", dir + "/panda.json", "--env", dir + "/table.json",
                    "--perturbations", "1", "--threads", "2", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const Bundle b = read_bundle(path);
  EXPECT_TRUE(b.perturbation.complete);
  EXPECT_EQ(check_invariants(b), kTinyEdges);
  expect_same_perturbation(b.perturbation, reference(input, {"--perturbations", "1"}).perturbation);
  expect_same_edges(b, read_bundle(input));
}

// ------------------------------------------------------------------------------------------
// 6. Physics, in broad strokes (the library tests are finer)
// ------------------------------------------------------------------------------------------

TEST(PerturbCli, ProbabilitiesArePlausibleOnTheTable) {
  const BasicRun& run = basic_run();
  ASSERT_EQ(run.result.exit_code, 0) << describe(run.result);
  const Bundle& b = run.after;
  EXPECT_EQ(b.header.env_hash, run.before.header.env_hash);
  EXPECT_TRUE(contains(b.header.env_file, "table.json")) << b.header.env_file;
  const Perturbation& p = b.perturbation;
  ASSERT_TRUE(p.complete);
  ASSERT_EQ(p.p_collision.size(), kBasicEdges);
  const double n = static_cast<double>(kBasicEdges);
  const double mean_collision =
      std::accumulate(p.p_collision.begin(), p.p_collision.end(), 0.0) / n;
  const double mean_lazy = std::accumulate(p.p_lazy_prop.begin(), p.p_lazy_prop.end(), 0.0) / n;
  EXPECT_GT(mean_collision, 0) << "no perturbation of any edge collides with the table";
  EXPECT_LT(mean_collision, 0.5);
  // Half of the perturbations have |d| < theta/2; an end that moves with the start keeps that.
  EXPECT_GT(mean_lazy, 0.3);
  EXPECT_LT(mean_lazy, 0.7);
  uint64_t valid = 0, lazy = 0, collision = 0, done = 0;
  for (size_t e = 0; e < b.size(); ++e) {
    valid += p.valid[e];
    lazy += p.lazy[e];
    collision += p.collision[e];
    done += p.done[e];
  }
  EXPECT_EQ(done, kBasicEdges * kBasicP);
  EXPECT_GT(valid, done / 2) << "most perturbations should re-simulate validly";
  EXPECT_GT(lazy, 0u);
  EXPECT_LT(lazy, valid);
  EXPECT_GT(collision, 0u);
  std::printf(
      "[ info     ] mean P_collision %.3f, mean P_lazy_prop %.3f, rollouts valid %.1f%%, collided "
      "%.1f%%\n",
      mean_collision, mean_lazy, 100.0 * valid / done, 100.0 * collision / done);
}

}  // namespace
}  // namespace lazyboe::test
