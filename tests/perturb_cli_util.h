// Helpers of the lazyboe-perturb command-line tests (test_perturb_cli, test_perturb_resume_cli):
// running the tools, waiting for a checkpoint, comparing bundles and analyses, and the input
// bundles and reference analyses, made once per test binary.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle.h"
#include "test_util.h"

namespace lazyboe::test {

// The shell command line of a tool with the given arguments (each shell-quoted), under a
// watchdog that kills a run that does not end (a hang fails the test instead of stalling it).
std::string tool_command(const std::string& tool, const std::vector<std::string>& args,
                         double timeout_seconds);
CommandResult perturb_tool(const std::vector<std::string>& args, double timeout_seconds = 120);
// The same, run inside `dir` (anything written by mistake to a relative path lands there).
CommandResult perturb_tool_in(const std::string& dir, const std::vector<std::string>& args,
                              double timeout_seconds = 20);
CommandResult build_tool(const std::vector<std::string>& args, double timeout_seconds = 120);
std::string env_file(const std::string& name);

Background spawn_perturb(const std::vector<std::string>& args, const std::string& log_prefix);
// The file's identity: a checkpoint renames a new file over it, which changes the inode.
ino_t inode_of(const std::string& path);
// Waits until the bundle at `path` has been replaced by a checkpoint (its inode changes) while
// the process still runs. False when the process ended first (it is then reaped: b.pid = -1,
// `exit_code` set) or after the timeout.
bool wait_for_checkpoint(Background& b, const std::string& path, ino_t before,
                         double timeout_seconds, int& exit_code);

bool same_double(double a, double b);
// Every edge dataset of the two bundles is identical, and so is the header (all but
// wall_seconds and tool_version).
void expect_same_edges(const Bundle& a, const Bundle& b);
// The two analyses hold the same numbers (with `work`, the bookkeeping attributes too).
void expect_same_perturbation(const Perturbation& a, const Perturbation& b, bool work = false);
// The per-edge invariants of an analysis, finished or not. Returns the number of edges done.
size_t check_invariants(const Bundle& b);

// A complete bundle of `edges` edges on `env`, built once; never modified (tests copy it).
const std::string& input_bundle(uint64_t edges, uint64_t seed,
                                const std::string& env = "table.json");
// A copy of an input bundle at `path` (writable).
void copy_bundle(const std::string& from, const std::string& path);
// An uninterrupted analysis of a copy of `input` with `args` (2 threads, quiet), run once.
const Bundle& reference(const std::string& input, const std::vector<std::string>& args);

}  // namespace lazyboe::test
