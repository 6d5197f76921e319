// LazyBoE (the paper, Algorithm 1): BoE's search, but an edge is taken lazily (its stored end
// state, no simulation) with probability P_select = (1 - P_collision) P_lazy_prop; lazy chains
// use radius theta/2 and are simulated when they stop improving the heuristic or reach the goal
// region; only simulated edges enter a path. Needs the bundle's perturbation analysis.
// Choices where the paper leaves room: docs/algorithms.md.
#pragma once

#include "lazyboe/planning/registry.h"

namespace lazyboe {

PlannerInfo lazyboe_planner_info();

}  // namespace lazyboe
