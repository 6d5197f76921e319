// A planner defined outside the library and registered at run time (register_planner), as an
// OMPL user subclasses base::Planner: it tries the one straight joint-space command from the
// start to a joint goal, within the context's command limits, and returns it when it simulates
// valid and ends in the goal region. It shares the context's simulator, and so every check.
#pragma once

#include <memory>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/registry.h"

namespace straight {

class StraightPlanner : public lazyboe::Planner {
 public:
  void setup(const lazyboe::PlanningContext& context) override { context_ = &context; }

  lazyboe::PlanResult solve(const lazyboe::PlanningProblem& problem,
                            lazyboe::SimulatorWorkspace& ws,
                            lazyboe::RolloutPool* /*pool*/) override {
    const lazyboe::Simulator& sim = context_->sim;
    lazyboe::PlanResult result;
    if (problem.goal.kind != lazyboe::Goal::Kind::Joint)
      lazyboe::fail("straight", "needs a joint-space goal");
    std::vector<double> times, knots;
    const lazyboe::Deadline clock(problem.termination.budget);
    if (!lazyboe::direct_command(sim.robot, context_->command, problem.goal.q - problem.start,
                                 sim.dt, times, knots)) {
      result.failure = "the start is the goal";
      return result;
    }
    const int dof = sim.robot.dof;
    const lazyboe::CommandProfile command{knots.data(), static_cast<int>(times.size()), dof,
                                          times.back()};
    const lazyboe::RolloutResult r = lazyboe::simulate(sim, ws, problem.start, command);
    result.counters.nodes = 2;
    result.counters.simulations = 1;
    result.counters.collision_checks = r.collision_checks;
    if (!r.valid() || !problem.goal.contains(sim.robot, ws.robot, r.qf)) {
      result.failure = std::string("the straight command ") +
                       (r.valid() ? "ends outside the goal" : "is not valid (") +
                       (r.valid() ? "" : std::string(lazyboe::rollout_status_name(r.status)) + ")");
      return result;
    }
    result.success = true;
    result.time_to_first_solution = clock.elapsed();
    result.n_solutions = 1;
    result.best_cost = r.path_length;
    result.best_path.push_back({-1, knots, times.back()});
    return result;
  }

 private:
  const lazyboe::PlanningContext* context_ = nullptr;
};

// Its registry entry: a name, one line, what it needs (a simulator only), no parameters.
inline void register_straight_planner() {
  lazyboe::PlannerInfo info;
  info.name = "straight";
  info.description = "one straight joint-space command from start to goal (an example planner)";
  info.make = [](const lazyboe::ParameterValues&) { return std::make_unique<StraightPlanner>(); };
  lazyboe::register_planner(std::move(info));
}

}  // namespace straight
