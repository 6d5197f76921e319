// Plans one query on an edge bundle with the installed library:
//   plan_one_query BUNDLE START GOAL [PLANNER [TOLERANCE [BUDGET]]]
// START and GOAL are comma-separated joint values; PLANNER a registered planner (default
// lazyboe); TOLERANCE the joint-space goal radius in rad (default 0.3); BUDGET the planning
// time limit in s (default 5). Prints the result and the re-validated trajectory's duration and
// cost; exit status 0 on success.
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/registry.h"

namespace {

lazyboe::JointVector joints(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  for (std::string cell; std::getline(in, cell, ',');)
    v.push_back(lazyboe::parse_real_in(cell, {-1e3, 1e3}, "joint value", " rad"));
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s BUNDLE START GOAL [PLANNER [TOLERANCE [BUDGET]]]\n", argv[0]);
    return 2;
  }
  try {
    // The bundle (memory-mapped), its robot and environment, simulator and neighbour index.
    const lazyboe::PlanningSession session(argv[1], true, "", "");
    lazyboe::SimulatorWorkspace ws(session.sim);  // one per thread

    lazyboe::PlanningProblem problem;
    problem.start = joints(argv[2]);
    problem.goal.kind = lazyboe::Goal::Kind::Joint;
    problem.goal.q = joints(argv[3]);
    // Strict numbers (the whole text, finite), in the ranges lazyboe-query accepts.
    problem.goal.tolerance =
        argc > 5 ? lazyboe::parse_real_in(argv[5], {0, 1e3, true}, "TOLERANCE", " rad") : 0.3;
    problem.termination.budget =
        argc > 6
            ? lazyboe::parse_real_in(argv[6], {0, lazyboe::kMaxBudgetSeconds, true}, "BUDGET", " s")
            : 5.0;
    problem.termination.stop_at_first = true;
    lazyboe::validate_problem(session.sim, ws, problem);  // limits, collision, reach

    const std::string planner = argc > 4 ? argv[4] : "lazyboe";
    const lazyboe::PlanResult result = lazyboe::plan(session.context(), ws, planner, {}, problem);
    if (!result.success) {
      std::printf("%s: no solution: %s\n", planner.c_str(), result.failure.c_str());
      return 1;
    }
    // Every returned path is simulated again from the exact start with every check.
    const lazyboe::Trajectory t =
        lazyboe::realize_path(session.sim, ws, problem.start, result.best_path, problem.goal, 10);
    std::printf(
        "%s: solved in %.3f s, %zu edges, %llu simulations; trajectory %.2f s, cost %.3f rad\n",
        planner.c_str(), result.time_to_first_solution, result.best_path.size(),
        static_cast<unsigned long long>(result.counters.simulations), t.duration, t.cost);
    return 0;
  } catch (const lazyboe::Error& e) {
    std::fprintf(stderr, "plan_one_query: error: %s\n", e.what());
    return 1;
  }
}
