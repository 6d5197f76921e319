// The planners. All four share one Simulator (and so one validity check) through the
// PlanningContext; they differ only in their search:
//   boe      Bundle of Edges (Shome and Kavraki 2021): greedy best-first search that re-simulates
//            every bundle edge starting within theta of the expanded node.
//   lazyboe  LazyBoE (paper, Algorithm 1): BoE's search, but an edge is taken lazily (its stored
//            end state, no simulation) with probability P_select = (1 - P_collision) P_lazy_prop;
//            lazy chains use radius theta/2 and are simulated when they stop improving the
//            heuristic or reach the goal region; only simulated edges enter a path.
//   rrt      kinodynamic RRT (LaValle and Kuffner 2001) with goal bias; first solution.
//   sst      Stable Sparse RRT (Li, Littlefield and Bekris 2016) with selection and pruning radii.
// Choices where the papers leave room are in docs/algorithms.md.
#pragma once

#include "planning/problem.h"

namespace lazyboe {

// Runs the planner named in problem.params.planner within its budget. Throws Error for an
// unknown planner or a planner that needs what the context lacks (a bundle, perturbation data).
PlanResult plan(const PlanningContext& context, SimulatorWorkspace& ws,
                const PlanningProblem& problem);

}  // namespace lazyboe
