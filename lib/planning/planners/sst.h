// Stable Sparse RRT (Li, Littlefield and Bekris 2016): Best-Near selection within the selection
// radius delta_BN, and a witness set with pruning radius delta_s = pruning_ratio * delta_BN
// that keeps one lowest-cost representative per witness. Anytime: it runs until its budget.
#pragma once

#include "lazyboe/planning/registry.h"

namespace lazyboe {

PlannerInfo sst_planner_info();

// selection_radius and pruning_ratio, as SST (ours and OMPL's) declares them.
ParameterSpec selection_radius_parameter();
ParameterSpec pruning_ratio_parameter();

}  // namespace lazyboe
