#include "lazyboe/planning/planners/boe.h"

#include "lazyboe/planning/planners/bundle_search.h"

namespace lazyboe {
namespace {

class BoE final : public BundlePlanner {
 public:
  using BundlePlanner::BundlePlanner;

 private:
  PlanResult search(const BundleSolve& solve) override { return BundleSearch(solve).run(); }
};

}  // namespace

PlannerInfo boe_planner_info() {
  PlannerInfo info;
  info.name = "boe";
  info.description = "Bundle of Edges: best-first search simulating every edge within theta";
  info.needs.bundle = true;
  info.parameters = {theta_parameter(), direct_parameter()};
  info.make = planner_factory<BoE>(info);
  return info;
}

}  // namespace lazyboe
