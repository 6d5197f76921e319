#include "lazyboe/planning/planners/boe.h"

#include "lazyboe/planning/planners/bundle_search.h"

namespace lazyboe {

PlannerInfo boe_planner_info() {
  PlannerInfo info;
  info.name = "boe";
  info.description = "Bundle of Edges: best-first search simulating every edge within theta";
  info.needs.bundle = true;
  info.parameters = {theta_parameter(), direct_parameter()};
  info.make = bundle_planner_factory<BundleSearch>(info);
  return info;
}

}  // namespace lazyboe
