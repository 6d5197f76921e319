// A benchmark study: every planner on every problem, repeated with different seeds, each run
// with the same wall-clock budget; the record of each run is what the paper reports (success,
// time to first solution, final cost, number of solutions) plus the planner's counters.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "lazyboe/bench/problems.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/request.h"

namespace lazyboe {

// A named setting of a planner's parameters that studies run as a planner of its own: the
// paper's SST pruning-to-selection ratios (sst-0.5x, sst-1x, sst-2x) and LazyBoE with each of its
// lazy models (lazyboe, lazyboe-transfer). A study's concern, not the planner's.
struct StudyVariant {
  std::string name;
  ParameterValues values;
};
// A planner's study variants; empty: studies run the planner itself.
const std::vector<StudyVariant>& study_variants(const std::string& planner);

// How many of `problems` one direct command solves in the context's world
// (solved_by_direct_command with the context's command limits).
int direct_solutions(const PlanningContext& context, const std::vector<BenchProblem>& problems);

struct PlannerSpec {
  std::string name;            // as in runs.csv: lazyboe, boe, rrt, sst-0.5x, ..., ompl-sst
  std::string planner;         // its name in the planner registry
  ParameterValues parameters;  // a study variant's values (e.g. sst-2x: pruning_ratio 2)
  bool available = true;
  std::string unavailable_reason;
};

// The study's planners, from the planner registry: "all" (every registered planner, or its
// study variants where it has them: SST's sst-0.5x, sst-1x, sst-2x, the paper's pruning-to-
// selection ratios; lazyboe and lazyboe-transfer, its two lazy models) or a comma-separated
// list of names, where a planner's name means its variant of that name if it has one
// (lazyboe), else all its variants (sst). Planners not built in (OMPL's without OMPL) are
// kept, marked unavailable. Throws Error("--planners", ...) for an unknown name or one named
// twice.
std::vector<PlannerSpec> planner_specs(const std::string& list);

// Marks unavailable, with the reason, the planners that cannot run on this context (their
// setup refuses it: lazyboe-transfer on a bundle without transfer statistics).
void check_planner_specs(const PlanningContext& context, std::vector<PlannerSpec>& specs);

// Sets direct = false on every spec whose planner declares it (lazyboe-bench --no-direct).
void search_only(std::vector<PlannerSpec>& specs);

struct RunRecord {
  std::string planner;
  int problem = 0;  // index into the study's problems
  int repeat = 0;
  uint64_t seed = 0;
  bool success = false;
  double time_to_first_solution = std::numeric_limits<double>::quiet_NaN();  // s
  double best_cost = std::numeric_limits<double>::quiet_NaN();  // arc length, rad (re-simulated)
  int n_solutions = 0;
  PlannerCounters counters;
  double budget = 0;
  std::string failure;  // why there is no solution, or the error
  // The returned trajectory's execution (execution.h; the raw chain's with post-processing
  // off) and the raw chain's, for comparison; NaN / -1 without a solution.
  double duration = std::numeric_limits<double>::quiet_NaN();    // s
  int stops = -1;                                                // excluding start and end
  double arc_length = std::numeric_limits<double>::quiet_NaN();  // rad
  double raw_duration = std::numeric_limits<double>::quiet_NaN();
  int raw_stops = -1;
  // Wall time of the post-processing (after the planner's clock has stopped; not part of the
  // budget): time to first solution + post_seconds is the time to an executable trajectory.
  double post_seconds = 0;
  int junctions = -1, blends_kept = -1, shortcuts = -1;
  std::string found_by;  // PlanResult::found_by ("direct", "bundle", "growth", "connection", "approach", ...)
};

// The seed of a (problem, repeat) run: the same for every planner, different across repeats.
uint64_t run_seed(uint64_t study_seed, int problem, int repeat);

// Trajectory sampling of a study's runs: only the returned trajectory's figures are kept, not
// its samples (1000 control ticks at the Panda's 1 kHz).
constexpr double kStudySampleInterval = 1.0;  // s

// One run, answered as every front end answers a request (answer_request, request.h). The
// best path is re-simulated from the exact start with every check (realize_path, or
// make_executable's raw pass); its cost is the reported cost (the planner's path, as the paper
// reports it), and a path that fails the check is reported as a failed run with the reason (it
// would be a planner bug). Unless `output.raw`, the path is also post-processed (after the
// planner's clock has stopped) and the record gets the executed trajectory's figures.
RunRecord run_planner(const PlanningContext& context, SimulatorWorkspace& ws,
                      const PlannerSpec& planner, const BenchProblem& problem, int problem_index,
                      int repeat, uint64_t seed, double budget, const ReturnOptions& output);

struct StudyTask {
  int planner = 0;  // index into the specs
  int problem = 0;
  int repeat = 0;
};

struct StudyControl {
  int jobs = 1;                          // runs in parallel (one workspace each)
  std::function<bool()> stop_requested;  // polled before each run starts
  // Called for each finished run, one at a time (under a lock), in completion order.
  std::function<void(const RunRecord&, size_t finished, size_t total)> on_run;
  // What run_planner returns: post-processed (raw = false) by default.
  ReturnOptions output{false, kStudySampleInterval, ExecutionOptions{}.shortcut_attempts};
};

// Runs `tasks`; returns the records of the runs that finished, in task order. Runs in progress
// when a stop is requested finish (within their budget); no new run starts.
std::vector<RunRecord> run_study(const PlanningContext& context,
                                 const std::vector<PlannerSpec>& planners,
                                 const std::vector<BenchProblem>& problems,
                                 const std::vector<StudyTask>& tasks, double budget,
                                 uint64_t study_seed, const StudyControl& control);

}  // namespace lazyboe
