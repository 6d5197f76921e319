// Kinodynamic RRT (LaValle and Kuffner 2001) with goal bias: random commands of the bundle's
// family from the nearest tree node; stops at its first solution.
#pragma once

#include "lazyboe/planning/registry.h"

namespace lazyboe {

PlannerInfo rrt_planner_info();

}  // namespace lazyboe
