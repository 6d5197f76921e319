// lazysp: lazy shortest path over the bundle, validated forward. A weighted-A* search over
// states predicted by displacement transfer (an edge applied from x ends near
// x + qf(e) - q0(e)), without simulation; only the candidate path is simulated, edge by edge
// from the exact start; a failed edge is never tried again from that real state and the search
// restarts from every real state reached. When the bundle offers no candidate, it grows from
// its real states with random commands of the bundle's family (as RRT), so it does not give up
// while budget remains. Anytime. Choices: docs/algorithms.md.
#pragma once

#include "lazyboe/planning/registry.h"

namespace lazyboe {

PlannerInfo lazysp_planner_info();

}  // namespace lazyboe
