// BoE, Bundle of Edges (Shome and Kavraki 2021): greedy best-first search that re-simulates
// every bundle edge starting within theta of the expanded node. Choices where the paper leaves
// room: docs/algorithms.md.
#pragma once

#include "lazyboe/planning/registry.h"

namespace lazyboe {

PlannerInfo boe_planner_info();

}  // namespace lazyboe
