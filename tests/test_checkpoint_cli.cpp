// Incremental checkpoints (issue 18, item 1) through the real tools: lazyboe-build and
// lazyboe-perturb killed (SIGKILL) at every phase of a checkpoint and at timed moments leave a
// file that opens and resumes to the byte-identical result of an uninterrupted run.
//
// The crash phases are reached through the test hook LAZYBOE_TEST_CRASH_AT=<point>:<n>
// (lib/common/journal.h): the tool kills itself with SIGKILL at the n-th pass of <point>.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/journal.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;

constexpr int kEdges = 700;  // about a dozen checkpoints of one 64-attempt round each

std::string command(const std::string& tool, const std::vector<std::string>& args,
                    const std::string& crash_at = "") {
  std::string cmd = crash_at.empty() ? "" : "LAZYBOE_TEST_CRASH_AT=" + quote(crash_at) + " ";
  cmd += watchdog(120) + quote(tool_path(tool));
  for (const std::string& a : args) cmd += " " + quote(a);
  return cmd;
}

CommandResult tool(const std::string& name, const std::vector<std::string>& args,
                   const std::string& crash_at = "") {
  return run(command(name, args, crash_at));
}

std::vector<std::string> build_args(const std::string& out, const std::string& checkpoint) {
  return {"--out",  out,         "--edges", std::to_string(kEdges), "--seed",
          "7",      "--threads", "2",       "--checkpoint-seconds", checkpoint,
          "--quiet"};
}

std::vector<std::string> perturb_args(const std::string& bundle, const std::string& checkpoint) {
  return {"--bundle", bundle,   "--perturbations", "3", "--threads", "2", "--checkpoint-seconds",
          checkpoint, "--quiet"};
}

// The two files are the same bytes but for at most `windows` runs of up to 8 bytes (the
// wall_seconds attributes, which time the run).
// An uninterrupted build without any checkpoint (the reference), once per binary.
const std::string& reference_build() {
  static const std::string path = [] {
    const std::string dir = fresh_dir("reference");
    const std::string out = dir + "/straight.h5";
    const CommandResult r = tool("lazyboe-build", build_args(out, "1e9"));
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return out;
  }();
  return path;
}

// The reference perturbed (no checkpoints).
const std::string& reference_perturbed() {
  static const std::string path = [] {
    const std::string out = temp_dir() + "/reference/perturbed.h5";
    fs::copy_file(reference_build(), out, fs::copy_options::overwrite_existing);
    const CommandResult r = tool("lazyboe-perturb", perturb_args(out, "1e9"));
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return out;
  }();
  return path;
}

// The tool, sent SIGKILL after `seconds` (by timeout itself, so the tool is what dies).
std::string killed_after(double seconds, const std::string& name,
                         const std::vector<std::string>& args) {
  std::string cmd = "timeout -s KILL " + std::to_string(seconds) + " " + quote(tool_path(name));
  for (const std::string& a : args) cmd += " " + quote(a);
  return cmd;
}

bool killed(const CommandResult& r) { return r.exit_code == 128 + SIGKILL; }

TEST(Checkpoints, FinishedFileIsTheSameBytesWithOrWithoutCheckpoints) {
  const std::string dir = fresh_dir("same-bytes");
  const std::string out = dir + "/run.h5";
  const CommandResult r = tool("lazyboe-build", build_args(out, "0"));
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(same_bundle_but_timings(out, reference_build(), 1));
  EXPECT_EQ(files_in(dir),
            (std::vector<std::string>{"run.h5", "run.h5.kd-index", "run.h5.ws-index"}))
      << "the journal is removed";
  const std::string perturbed = dir + "/perturbed.h5";
  fs::copy_file(reference_build(), perturbed);
  const CommandResult p = tool("lazyboe-perturb", perturb_args(perturbed, "0"));
  ASSERT_EQ(p.exit_code, 0) << describe(p);
  EXPECT_TRUE(same_bundle_but_timings(perturbed, reference_perturbed(), 2));
}

// Killed at `crash_at`: the file at --out is absent (only before the first checkpoint) or a
// valid bundle; --resume finishes to the reference bytes and removes the journal.
void crash_and_resume_build(const std::string& crash_at, bool file_expected) {
  SCOPED_TRACE(crash_at);
  const std::string dir = fresh_dir("build-crash-" + crash_at.substr(0, crash_at.find(':')) +
                                    crash_at.substr(crash_at.find(':') + 1));
  const std::string out = dir + "/run.h5";
  const CommandResult r = tool("lazyboe-build", build_args(out, "0"), crash_at);
  ASSERT_TRUE(killed(r)) << "the crash point was not reached: " << describe(r);
  ASSERT_EQ(fs::exists(out), file_expected);
  if (!file_expected) return;
  EXPECT_NO_THROW(read_bundle(out));  // the file at the output path opens, whatever the phase
  const CommandResult inspect = tool("lazyboe-build", {"--inspect", out});
  EXPECT_EQ(inspect.exit_code, 0) << describe(inspect);
  const CommandResult resumed = tool("lazyboe-build", {"--resume", "--out", out, "--quiet"});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(same_bundle_but_timings(out, reference_build(), 1));
  EXPECT_FALSE(fs::exists(build_journal_path(out)));
  EXPECT_TRUE(tmp_files_in(dir).size() <= 1) << join(tmp_files_in(dir));
}

TEST(Checkpoints, BuildKilledAtEveryCheckpointPhaseResumesToTheSameBytes) {
  crash_and_resume_build("base-written:1", true);      // first checkpoint: base file in place
  crash_and_resume_build("journal-torn:1", true);      // half of the first record written
  crash_and_resume_build("journal-torn:3", true);      // half of a later one
  crash_and_resume_build("journal-unsynced:2", true);  // written, not yet fsynced
  crash_and_resume_build("journal-synced:4", true);    // between checkpoints
  crash_and_resume_build("final-written:1", true);     // final file renamed, journal not removed
}

TEST(Checkpoints, BuildKilledAtTimedMomentsResumesToTheSameBytes) {
  for (const double seconds : {0.25, 0.6, 1.0}) {
    SCOPED_TRACE(seconds);
    const std::string dir = fresh_dir("build-kill-" + std::to_string(int(seconds * 100)));
    const std::string out = dir + "/run.h5";
    const CommandResult r = run(killed_after(seconds, "lazyboe-build", build_args(out, "0")));
    if (!fs::exists(out)) continue;  // killed before the first checkpoint: nothing to resume
    EXPECT_NO_THROW(read_bundle(out));
    const CommandResult resumed = tool("lazyboe-build", {"--resume", "--out", out, "--quiet"});
    ASSERT_EQ(resumed.exit_code, 0) << describe(resumed) << "\nkilled run: " << describe(r);
    EXPECT_TRUE(same_bundle_but_timings(out, reference_build(), 1));
    EXPECT_FALSE(fs::exists(build_journal_path(out)));
  }
}

TEST(Checkpoints, ResumeAfterAKillExtendsTheBuildAndTheBaseStaysComplete) {
  // A complete bundle extended with --resume --edges: killed in its journal, the file is still
  // the complete smaller bundle (usable by every tool); resuming again reaches the target.
  const std::string dir = fresh_dir("extend");
  const std::string out = dir + "/run.h5";
  std::vector<std::string> small = build_args(out, "0");
  small[3] = "300";
  ASSERT_EQ(tool("lazyboe-build", small).exit_code, 0);
  const CommandResult r = tool("lazyboe-build",
                               {"--resume", "--out", out, "--edges", std::to_string(kEdges),
                                "--checkpoint-seconds", "0", "--quiet"},
                               "journal-synced:3");
  ASSERT_TRUE(killed(r)) << describe(r);
  const Bundle base = read_bundle(out);
  EXPECT_TRUE(base.header.complete);
  EXPECT_EQ(base.size(), 300u);
  EXPECT_TRUE(fs::exists(build_journal_path(out)));
  const CommandResult resumed = tool("lazyboe-build", {"--resume", "--out", out});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(contains(resumed.err, "checkpoints from its journal applied")) << resumed.err;
  const Bundle full = read_bundle(out);
  EXPECT_EQ(full.size(), static_cast<size_t>(kEdges));
  expect_same_edge_arrays(full, read_bundle(reference_build()));
}

TEST(Checkpoints, AJournalOfAnotherBundleIsIgnoredAndRemoved) {
  const std::string dir = fresh_dir("stale");
  const std::string out = dir + "/run.h5";
  const CommandResult r = tool("lazyboe-build", build_args(out, "0"), "journal-synced:3");
  ASSERT_TRUE(killed(r)) << describe(r);
  const std::string journal = read_file(build_journal_path(out));
  // Another bundle at the same path (a fresh build with --force, run to its end elsewhere).
  fs::copy_file(reference_build(), out, fs::copy_options::overwrite_existing);
  write_bytes(build_journal_path(out), journal);
  const CommandResult resumed = tool("lazyboe-build", {"--resume", "--out", out});
  EXPECT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(contains(resumed.err, "ignored and removed")) << resumed.err;
  EXPECT_FALSE(fs::exists(build_journal_path(out)));
  EXPECT_TRUE(same_bundle_but_timings(out, reference_build(), 1)) << "the file is untouched";
}

void crash_and_resume_perturb(const std::string& crash_at) {
  SCOPED_TRACE(crash_at);
  const std::string dir = fresh_dir("perturb-crash-" + crash_at.substr(0, crash_at.find(':')) +
                                    crash_at.substr(crash_at.find(':') + 1));
  const std::string bundle = dir + "/run.h5";
  fs::copy_file(reference_build(), bundle);
  const CommandResult r = tool("lazyboe-perturb", perturb_args(bundle, "0"), crash_at);
  ASSERT_TRUE(killed(r)) << "the crash point was not reached: " << describe(r);
  EXPECT_NO_THROW(read_bundle(bundle));
  const CommandResult again = tool("lazyboe-perturb", perturb_args(bundle, "0"));
  ASSERT_EQ(again.exit_code, 0) << describe(again);
  EXPECT_TRUE(same_bundle_but_timings(bundle, reference_perturbed(), 2));
  EXPECT_FALSE(fs::exists(perturb_journal_path(bundle)));
}

TEST(Checkpoints, PerturbKilledAtEveryCheckpointPhaseResumesToTheSameBytes) {
  crash_and_resume_perturb("journal-torn:1");
  crash_and_resume_perturb("journal-torn:4");
  crash_and_resume_perturb("journal-unsynced:3");
  crash_and_resume_perturb("journal-synced:5");
  crash_and_resume_perturb("final-written:1");
}

TEST(Checkpoints, PerturbKilledAtTimedMomentsResumesToTheSameBytes) {
  for (const double seconds : {0.3, 0.8}) {
    SCOPED_TRACE(seconds);
    const std::string dir = fresh_dir("perturb-kill-" + std::to_string(int(seconds * 100)));
    const std::string bundle = dir + "/run.h5";
    fs::copy_file(reference_build(), bundle);
    run(killed_after(seconds, "lazyboe-perturb", perturb_args(bundle, "0")));
    EXPECT_NO_THROW(read_bundle(bundle));
    const CommandResult again = tool("lazyboe-perturb", perturb_args(bundle, "0"));
    ASSERT_EQ(again.exit_code, 0) << describe(again);
    EXPECT_TRUE(same_bundle_but_timings(bundle, reference_perturbed(), 2));
  }
}

// Past a file-size limit (as a full disk) inside a journal append: one line naming the journal;
// the base and the whole records stay, and --resume (without the limit) finishes the build.
TEST(Checkpoints, FullDiskInAJournalAppendKeepsEveryEarlierCheckpoint) {
  const std::string dir = fresh_dir("full");
  const std::string out = dir + "/run.h5";
  std::vector<std::string> args = build_args(out, "0");
  const CommandResult r = run("ulimit -f 300 && " + command("lazyboe-build", args));
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  expect_one_line_error(r, {build_journal_path(out), "cannot write"});
  EXPECT_NO_THROW(read_bundle(out));
  EXPECT_GE(read_journal(build_journal_path(out)).records.size(), 2u);
  const CommandResult resumed = tool("lazyboe-build", {"--resume", "--out", out, "--quiet"});
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(same_bundle_but_timings(out, reference_build(), 1));
}

// ---- the journal itself ----

TEST(Journal, TornOrDamagedTailIsIgnoredAndCutOffOnReopen) {
  const std::string path = fresh_dir("journal") + "/j";
  {
    JournalWriter w = JournalWriter::create(path, "base");
    w.append("one");
    w.append("two");
  }
  std::string bytes = read_file(path);
  write_bytes(path, bytes + bytes.substr(8, 10));  // a torn third record
  JournalContents c = read_journal(path);
  ASSERT_TRUE(c.valid_start);
  EXPECT_EQ(c.records, (std::vector<std::string>{"base", "one", "two"}));
  EXPECT_EQ(c.ignored_bytes, 10u);
  {
    JournalWriter w = JournalWriter::reopen(path, c.valid_bytes);
    w.append("three");
  }
  c = read_journal(path);
  EXPECT_EQ(c.records, (std::vector<std::string>{"base", "one", "two", "three"}));
  EXPECT_EQ(c.ignored_bytes, 0u);
  bytes = read_file(path);
  bytes[bytes.size() - 2] ^= 1;  // a flipped bit in the last record: it is dropped
  write_bytes(path, bytes);
  c = read_journal(path);
  EXPECT_EQ(c.records.size(), 3u);
}

TEST(Journal, ASecondWriterIsRefused) {
  const std::string path = fresh_dir("journal-lock") + "/j";
  JournalWriter w = JournalWriter::create(path, "base");
  try {
    JournalWriter::reopen(path, w.bytes());
    FAIL() << "a second writer was let in";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "another process is writing")) << e.what();
  }
}

}  // namespace
}  // namespace lazyboe::test
