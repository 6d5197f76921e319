// OMPL's control-based planners on exactly our problem: oc::RRT ("ompl-rrt"), oc::SST
// ("ompl-sst") and oc::KPIECE1 ("ompl-kpiece") search with our simulator, validity checks,
// command family and goal region, so their rows compare with our rrt/sst on equal terms.
//
// Wiring (details and the differences from our rrt/sst: docs/algorithms.md, "OMPL planners"):
//   state     ob::RealVectorStateSpace(dof): joint positions at rest, as in all our planners
//             (every motion starts and ends at rest). Uniform samples come from the problem's
//             sampling box (the context's sample_lower/upper) through our own Random; the space's
//             bounds are that box, widened to hold the start and a joint goal (OMPL refuses a
//             start outside the bounds; our planners do not).
//   control   one whole velocity-command profile of our family (sample_command_profile with
//             the context's command family) in an oc::RealVectorControlSpace of dimension 2 +
//             max_knots*dof (duration, knot count, knots); its sampler draws from our Random seeded
//             with the problem's seed. One OMPL step = one whole command (control duration 1..1,
//             step 1).
//   propagate simulate(): every check along the motion (limits, torque, jerk, collision at
//             margin spacing, settling). An invalid rollout gives a NaN state, which the
//             validity checker (NaN test, then our check_state) rejects, so OMPL keeps only
//             motions our simulator accepts.
//   goal      ob::GoalSampleableRegion with distanceGoal = Goal::distance, threshold =
//             tolerance (inclusive, as Goal::contains); joint goals can be sampled (goal bias),
//             position goals cannot.
//   cost      an objective whose motion cost is the simulated arc length (the propagator's
//             last rollout), so SST compares the cost our planners report.
//   budget    ob::timedPlannerTerminationCondition(budget); only exact solutions count.
//   random    per query: our Random (seed, streams 2/3) for controls and states, the planner's
//             own RNG re-seeded from the problem's seed. OMPL's remaining draws (e.g.
//             nearest-neighbour pivots) come from its process-wide seed: seed_ompl, set once per
//             process.
//
// Thread safety: solves may run concurrently on different workspaces; every OMPL object
// lives inside one solve. The only process-wide settings are OMPL's seed and log level (warnings
// and errors only, on stderr), both made once.
#pragma once

#include <cstdint>

#include "lazyboe/planning/registry.h"

namespace lazyboe {

// True when the library was built with OMPL (LAZYBOE_HAVE_OMPL). Without it the three
// planners are still registered, and refuse at setup.
bool ompl_available();

// Seeds OMPL's process-wide random generator. Only the first call in a process has an effect
// (OMPL cannot be re-seeded once it has drawn); a solve calls it with its problem's seed when
// no one has before. OMPL rows are therefore exactly repeatable only for a whole run made the
// same way (same queries, same order, one job); see docs/algorithms.md. No-op without OMPL.
void seed_ompl(uint64_t seed);

// The registry entries. A returned path holds our commands (bundle_edge = -1), so realize_path
// re-simulates it.
PlannerInfo ompl_rrt_planner_info();
PlannerInfo ompl_sst_planner_info();
PlannerInfo ompl_kpiece_planner_info();

}  // namespace lazyboe
