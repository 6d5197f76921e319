// lazyboe-build and lazyboe-perturb across MPI ranks (issue 18, item 2): mpirun -np 2 and 3 give
// the file a single process writes; a rank killed mid-run leaves a resumable state that any
// rank count finishes to the same file; a failure on one rank ends the job with one line.
// Skipped (and reported skipped by ctest) when the build found no MPI.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;

#ifdef LAZYBOE_TEST_MPIEXEC
constexpr const char* kMpiexec = LAZYBOE_TEST_MPIEXEC;
#else
constexpr const char* kMpiexec = "";
#endif

#define REQUIRE_MPI()                                                                      \
  if (std::string(kMpiexec).empty()) GTEST_SKIP() << "built without MPI (libopenmpi-dev)"; \
  (void)0

std::string robot() { return source_path("data/robots/panda.json"); }

std::vector<std::string> build_args(const std::string& out) {
  return {"--robot",
          robot(),
          "--env",
          source_path("data/environments/table.json"),
          "--out",
          out,
          "--edges",
          "600",
          "--seed",
          "11",
          "--checkpoint-seconds",
          "0",
          "--quiet"};
}

std::vector<std::string> perturb_args(const std::string& bundle) {
  return {"--bundle", bundle, "--perturbations", "3", "--checkpoint-seconds", "0", "--quiet"};
}

// `ranks` 0: the tool alone (one process, two threads); otherwise under mpirun, one thread each.
std::string command(int ranks, const std::string& tool, std::vector<std::string> args,
                    const std::string& env = "") {
  std::string cmd = env + " " + watchdog(120);
  if (ranks > 0) {
    // As root (CI containers) mpirun needs --allow-run-as-root; two cores: --oversubscribe;
    // a container without ssh: plm_rsh_agent false (every rank is local).
    cmd += quote(kMpiexec) +
           " --allow-run-as-root --oversubscribe --bind-to none --mca plm_rsh_agent false -np " +
           std::to_string(ranks) + " ";
    args.insert(args.end(), {"--threads", "1"});
  } else {
    args.insert(args.end(), {"--threads", "2"});
  }
  cmd += quote(tool_path(tool));
  for (const std::string& a : args) cmd += " " + quote(a);
  return cmd;
}

// The same bytes but for up to `windows` runs of 8 bytes (the wall_seconds attributes).
const std::string& single_build() {
  static const std::string path = [] {
    const std::string out = fresh_dir("single") + "/single.h5";
    const CommandResult r = run(command(0, "lazyboe-build", build_args(out)));
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return out;
  }();
  return path;
}

const std::string& single_perturbed() {
  static const std::string path = [] {
    const std::string out = temp_dir() + "/single/perturbed.h5";
    fs::copy_file(single_build(), out);
    const CommandResult r = run(command(0, "lazyboe-perturb", perturb_args(out)));
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return out;
  }();
  return path;
}

TEST(Mpi, BuildOnTwoAndThreeRanksIsTheSingleProcessFile) {
  REQUIRE_MPI();
  for (int ranks : {2, 3}) {
    SCOPED_TRACE(ranks);
    const std::string out = fresh_dir("build-" + std::to_string(ranks)) + "/mpi.h5";
    const CommandResult r = run(command(ranks, "lazyboe-build", build_args(out)));
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_TRUE(same_bundle_but_timings(out, single_build(), 1));
  }
}

TEST(Mpi, PerturbOnTwoAndThreeRanksIsTheSingleProcessFile) {
  REQUIRE_MPI();
  for (int ranks : {2, 3}) {
    SCOPED_TRACE(ranks);
    const std::string out = fresh_dir("perturb-" + std::to_string(ranks)) + "/mpi.h5";
    fs::copy_file(single_build(), out);
    const CommandResult r = run(command(ranks, "lazyboe-perturb", perturb_args(out)));
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_TRUE(same_bundle_but_timings(out, single_perturbed(), 2));
  }
}

TEST(Mpi, ProgressIsReportedOnceByRankZero) {
  REQUIRE_MPI();
  const std::string out = fresh_dir("progress") + "/mpi.h5";
  std::vector<std::string> args = build_args(out);
  args.pop_back();  // not --quiet
  const CommandResult r = run(command(3, "lazyboe-build", args));
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  size_t summaries = 0;
  for (size_t at = 0; (at = r.err.find("600 edges (complete)", at)) != std::string::npos; ++at)
    ++summaries;
  EXPECT_EQ(summaries, 1u) << r.err;
}

// Ranks other than 0 die (SIGKILL) in their `round`-th round; the job ends; another rank count
// (and thread count) resumes it to the single-process file.
TEST(Mpi, RankKilledMidBuildResumesWithAnotherRankCountToTheSameFile) {
  REQUIRE_MPI();
  const std::string out = fresh_dir("killed-build") + "/mpi.h5";
  const CommandResult r =
      run(command(3, "lazyboe-build", build_args(out), "LAZYBOE_TEST_CRASH_AT=rank-round:2"));
  ASSERT_NE(r.exit_code, 0) << "the job did not end when a rank died: " << describe(r);
  ASSERT_TRUE(fs::exists(out)) << describe(r);
  for (int ranks : {2, 0}) {  // resumed on 2 ranks, killed again, finished by one process
    std::vector<std::string> resume = {"--resume", "--out", out, "--quiet"};
    const CommandResult again = run(
        command(ranks, "lazyboe-build", resume, ranks ? "LAZYBOE_TEST_CRASH_AT=rank-round:3" : ""));
    if (ranks) {
      EXPECT_NE(again.exit_code, 0) << describe(again);
    } else {
      ASSERT_EQ(again.exit_code, 0) << describe(again);
    }
  }
  EXPECT_TRUE(same_bundle_but_timings(out, single_build(), 1));
  EXPECT_FALSE(fs::exists(build_journal_path(out)));
}

TEST(Mpi, RankKilledMidPerturbResumesWithAnotherRankCountToTheSameFile) {
  REQUIRE_MPI();
  const std::string out = fresh_dir("killed-perturb") + "/mpi.h5";
  fs::copy_file(single_build(), out);
  const CommandResult r =
      run(command(3, "lazyboe-perturb", perturb_args(out), "LAZYBOE_TEST_CRASH_AT=rank-round:5"));
  ASSERT_NE(r.exit_code, 0) << describe(r);
  ASSERT_TRUE(fs::exists(perturb_journal_path(out)));
  const CommandResult again = run(command(2, "lazyboe-perturb", perturb_args(out)));
  ASSERT_EQ(again.exit_code, 0) << describe(again);
  EXPECT_TRUE(same_bundle_but_timings(out, single_perturbed(), 2));
}

// Ctrl-C on mpirun kills the ranks; SIGUSR1, which mpirun forwards, stops the job as Ctrl-C
// stops one process: rank 0 saves the whole bundle so far (a prefix of the straight build's
// edges), the other ranks end, the exit status is 130.
TEST(Mpi, SigusrOnMpirunStopsTheJobWithAFinalSave) {
  REQUIRE_MPI();
  const std::string out = fresh_dir("usr1") + "/mpi.h5";
  std::vector<std::string> args = build_args(out);
  args[7] = "1000000";  // --edges: far more than the job can make before the signal
  const std::string cmd = "(" + command(2, "lazyboe-build", args) + " & job=$!; while [ ! -e " +
                          quote(out) + " ]; do sleep 0.1; done; pkill -USR1 -P $job; wait $job; " +
                          "echo exit $?)";
  const CommandResult r = run(cmd);
  EXPECT_TRUE(contains(r.out, "exit 130")) << describe(r);
  EXPECT_TRUE(contains(r.err, "lazyboe-build: interrupted; " + out + " holds ")) << r.err;
  EXPECT_FALSE(fs::exists(build_journal_path(out))) << "no final save";
  const Bundle stopped = read_bundle(out), straight = read_bundle(single_build());
  EXPECT_FALSE(stopped.header.complete);
  ASSERT_GT(stopped.size(), 0u);
  const size_t n = std::min(stopped.size(), straight.size()) * 7;
  EXPECT_TRUE(std::equal(stopped.q0.begin(), stopped.q0.begin() + n, straight.q0.begin()));
}

// A rank that cannot open the environment (a relative path, another working directory: the
// file is not on that node) ends the whole job with one line naming the rank and the file.
TEST(Mpi, AFailureOnOneRankEndsTheJobWithOneLine) {
  REQUIRE_MPI();
  const std::string here = fresh_dir("fail-here"), there = fresh_dir("fail-there");
  fs::copy_file(source_path("data/environments/table.json"), here + "/table.json");
  auto args = [&](const std::string& out) {
    std::string a = quote(tool_path("lazyboe-build")) + " --robot " + quote(robot()) +
                    " --env table.json --edges 300 --threads 1 --quiet --out " + quote(out);
    return a;
  };
  const std::string cmd =
      "cd " + quote(here) + " && " + watchdog(60) + quote(kMpiexec) +
      " --allow-run-as-root --oversubscribe --bind-to none --mca plm_rsh_agent false -np 1 " +
      args(here + "/run.h5") + " : -np 1 -wdir " + quote(there) + " " + args(here + "/run.h5");
  const CommandResult r = run(cmd);
  EXPECT_NE(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.exit_code, 128 + SIGKILL) << "the watchdog had to end a hanging job";
  EXPECT_TRUE(contains(r.err, "lazyboe-build: error: rank 1: table.json: ")) << r.err;
}

}  // namespace
}  // namespace lazyboe::test
