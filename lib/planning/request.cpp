#include "lazyboe/planning/request.h"

#include <algorithm>

#include "lazyboe/planning/registry.h"

namespace lazyboe {

ExecutionOptions execution_options(const PlanningContext& context, const ReturnOptions& output) {
  ExecutionOptions o;
  o.limits = context.command;
  o.shortcut_attempts = output.shortcut_attempts;
  return o;
}

int returned_sample_every(const Simulator& sim, const ReturnOptions& output) {
  return std::max(1, sample_every_ticks(output.sample_interval, sim.robot.control_rate));
}

PlanAnswer answer_request(const PlanningContext& context, const PlanRequest& request,
                          SimulatorWorkspace& ws, RolloutPool* pool) {
  const Deadline clock(kMaxBudgetSeconds);
  PlanAnswer a;
  a.raw = request.output.raw;
  a.result = plan(context, ws, request.planner, request.parameters, request.problem, pool);
  a.planning_seconds = clock.elapsed();
  if (!a.result.success) {
    if (request.problem.termination.cancelled()) a.result.failure = "cancelled";
    a.seconds = a.planning_seconds;
    return a;
  }
  a.trajectory =
      returned_trajectory(context.sim, ws, request.problem, a.result.best_path, a.raw,
                          execution_options(context, request.output),
                          returned_sample_every(context.sim, request.output), a.execution);
  a.seconds = clock.elapsed();
  return a;
}

}  // namespace lazyboe
