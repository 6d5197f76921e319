// Plans one query on an edge bundle with the installed library:
//   plan_one_query BUNDLE START GOAL [PLANNER [TOLERANCE [BUDGET]]]
// START and GOAL are comma-separated joint values; PLANNER a registered planner (default
// lazyboe), or "straight", the example planner this program registers (straight_planner.h);
// TOLERANCE the joint-space goal radius in rad (default 0.3); BUDGET the planning
// time limit in s (default 5). Prints the result and the executable trajectory's duration, stops
// and cost; exit status 0 on success.
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/request.h"
#include "straight_planner.h"

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
    straight::register_straight_planner();  // a planner of our own, beside the library's
    // The bundle (memory-mapped), its robot and neighbour indexes, and its own scene's
    // simulator (session.sim()).
    const lazyboe::PlanningSession session(argv[1], true, "", "");
    lazyboe::SimulatorWorkspace ws(session.sim());  // one per thread

    lazyboe::PlanRequest request;  // what every front end answers (lazyboe/planning/request.h)
    request.planner = argc > 4 ? argv[4] : "lazyboe";
    lazyboe::PlanningProblem& problem = request.problem;
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

    // Plan, then post-process into an executable trajectory, simulated again from the exact
    // start with every check (as lazyboe-query does; request.output.raw for the edge chain).
    const lazyboe::PlanAnswer answer = lazyboe::answer_request(session.context(), request, ws);
    const lazyboe::PlanResult& result = answer.result;
    if (!result.success) {
      std::printf("%s: no solution: %s\n", request.planner.c_str(), result.failure.c_str());
      return 1;
    }
    const lazyboe::Trajectory& t = answer.trajectory;
    std::printf(
        "%s: solved in %.3f s, %zu edges, %llu simulations; trajectory %.2f s, %d stops, cost "
        "%.3f rad\n",
        request.planner.c_str(), result.time_to_first_solution, result.best_path.size(),
        static_cast<unsigned long long>(result.counters.simulations), t.duration, t.stops, t.cost);
    return 0;
  } catch (const lazyboe::Error& e) {
    std::fprintf(stderr, "plan_one_query: error: %s\n", e.what());
    return 1;
  }
}
