#include "lazyboe/planning/planners/rrt.h"

#include "lazyboe/planning/planners/tree_search.h"

namespace lazyboe {

PlannerInfo rrt_planner_info() {
  PlannerInfo info;
  info.name = "rrt";
  info.description = "kinodynamic RRT with goal bias; stops at its first solution";
  info.parameters = {goal_bias_parameter()};
  info.make = tree_planner_factory<TreeSearch>(info);
  return info;
}

}  // namespace lazyboe
