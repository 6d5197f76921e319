#include "lazyboe/planning/planners/rrt.h"

#include "lazyboe/planning/planners/tree_search.h"

namespace lazyboe {
namespace {

class Rrt final : public TreePlanner {
 public:
  using TreePlanner::TreePlanner;

 private:
  PlanResult search(const PlanningContext& context, SimulatorWorkspace& ws,
                    const PlanningProblem& problem) override {
    return TreeSearch(context, ws, problem, values()).run();
  }
};

}  // namespace

PlannerInfo rrt_planner_info() {
  PlannerInfo info;
  info.name = "rrt";
  info.description = "kinodynamic RRT with goal bias; stops at its first solution";
  info.parameters = {goal_bias_parameter()};
  info.make = planner_factory<Rrt>(info);
  return info;
}

}  // namespace lazyboe
