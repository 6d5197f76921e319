// One request, one pipeline (OMPL's SimpleSetup: solve, then the solution path): what a front
// end asks for (a planner with its parameter values, a problem, and what to return) and the one
// call that answers it: plan, then post-process the path into an executable trajectory (or,
// raw, realize the planner's edge chain as it is), with the execution limits taken from the
// planning context. lazyboe-query, lazyboe-bench, the Python module and the installed example
// all answer through answer_request, so they give the same answer to the same request.
#pragma once

#include <string>

#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/planner.h"

namespace lazyboe {

// What to return for a solved problem.
struct ReturnOptions {
  bool raw = false;  // the planner's edge chain as it is, a stop at rest after every step
  // Trajectory sample spacing, s, rounded to whole control ticks (at least one: a spacing at
  // or below the control period samples every tick, with ddq and the command).
  double sample_interval = 0.01;
  int shortcut_attempts = ExecutionOptions{}.shortcut_attempts;  // 0: no shortcutting
};

struct PlanRequest {
  std::string planner = "lazyboe";  // a name in the planner registry
  ParameterValues parameters;       // values of parameters the planner declares
  PlanningProblem problem;
  ReturnOptions output;
};

struct PlanAnswer {
  PlanResult result;         // the planner's own answer: cost, edges, counters
  Trajectory trajectory;     // when result.success: the executable one, or the raw chain
  ExecutionStats execution;  // the post-processing's figures (untouched when raw)
  bool raw = false;          // trajectory is the raw chain
  // Wall time, s: of planning (the solve with its setup and the problem's checks), and of the
  // whole request (planning, then the returned trajectory: with stop_at_first, the time to an
  // executable trajectory).
  double planning_seconds = 0, seconds = 0;
};

// The post-processing options of `output` in `context`: the context's command limits.
ExecutionOptions execution_options(const PlanningContext& context, const ReturnOptions& output);

// Control ticks between returned samples for `output` (at least 1).
int returned_sample_every(const Simulator& sim, const ReturnOptions& output);

// make_planner, setup, validate_problem, solve, then the returned trajectory. Throws Error for a
// bad request (unknown planner or parameter, a value out of range, an invalid problem) and when
// the returned path fails its re-validation (a planner bug: never reported as a solution).
PlanAnswer answer_request(const PlanningContext& context, const PlanRequest& request,
                          SimulatorWorkspace& ws, RolloutPool* pool = nullptr);

}  // namespace lazyboe
