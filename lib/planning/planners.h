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

#include "lazyboe/planning/problem.h"
#include "lazyboe/sim/rollout_pool.h"

namespace lazyboe {

// Runs the planner named in problem.params.planner within its budget. Throws Error for an
// unknown planner or a planner that needs what the context lacks (a bundle, perturbation data).
// With a pool of several threads, BoE and LazyBoE run the independent rollouts of an expansion
// in parallel, in waves of up to kWavePerThread * pool->threads(); the result is the same for
// any number of threads (but the time it takes). Only the last wave, when the search stops,
// can hold rollouts the search does not use.
// Rollout lengths vary widely (a collision can end one at once): a wave of one per thread keeps
// threads waiting on the longest. 8 per thread balanced best (docs/performance.md), running
// about 5 % more rollouts than waves of one.
constexpr int kWavePerThread = 8;

PlanResult plan(const PlanningContext& context, SimulatorWorkspace& ws,
                const PlanningProblem& problem, RolloutPool* pool = nullptr);

}  // namespace lazyboe
