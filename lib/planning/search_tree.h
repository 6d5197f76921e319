// Bookkeeping every search of ours shares: the tree's nodes, the solutions found, the
// counters, the clock. Each search has its own node type (OMPL's Motion) derived from
// SearchNode: BundleNode (BoE, LazyBoE), TreeNode (RRT, SST), lazysp's LazySpNode; what only one
// planner needs (LazyBoE's lazy and failed nodes, SST's witnesses and pruning) it keeps itself.
// Internal to the planners (not installed).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/planner.h"

namespace lazyboe {

// What every search's node has.
struct SearchNode {
  JointVector q;  // state at rest; for a LazyBoE lazy node, where its edge is taken to end
  int parent = -1;
  double cost = 0;  // arc length from the start (estimated for lazy nodes)
  double h = 0;     // heuristic: distance to the goal
  // The simulation of the command from the parent, once the node is real (what a returned path
  // hands the post-processing: PathStep::outcome).
  double edge_length = 0, edge_duration = 0;
  int edge_ticks = 0;

  // Makes the node the end of rollout r (valid) from its parent, which costs parent_cost.
  void reached(const RolloutResult& r, double parent_cost) {
    q = r.qf;
    cost = parent_cost + r.path_length;
    edge_length = r.path_length;
    edge_duration = r.duration;
    edge_ticks = r.ticks;
  }
  // The rollout that reached it, as far as a returned path needs it.
  RolloutResult outcome() const {
    RolloutResult r;
    r.qf = q;
    r.path_length = edge_length;
    r.duration = edge_duration;
    r.ticks = edge_ticks;
    return r;
  }
};

// Configurations of a pose goal or goal set the direct connection tries, nearest the start
// first (one after another while each fails).
constexpr int kDirectTargets = 3;
// How near (joint space, rad) a real node must be to a configuration of a pose goal for
// goal_connection to try the direct command to it.
constexpr double kGoalConnectRadius = 1.0;

template <typename Node>
class SearchState {
 public:
  SearchState(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p)
      : ctx_(ctx),
        ws_(ws),
        problem_(p),
        deadline_(p.termination.budget),
        goal_data_(ctx.sim.robot) {}

  const PlanningContext& context() const { return ctx_; }
  const PlanningProblem& problem() const { return problem_; }
  std::vector<Node>& nodes() { return nodes_; }
  Node& node(int v) { return nodes_[v]; }
  PlanResult& result() { return result_; }
  // The result, moved out (its path holds every step's per-tick rows): a search's last call.
  PlanResult take_result() { return std::move(result_); }

  double heuristic(const JointVectorRef& q) {
    return problem_.goal.distance(ctx_.sim.robot, goal_data_, q);
  }
  bool in_goal(double h) const { return h <= problem_.goal.tolerance; }
  // Whether q keeps the task's tilt limit (end_effector_limits.max_tilt; true without one): a
  // predicted state beyond it is a place the task may not go.
  bool within_tilt(const JointVectorRef& q) {
    const EndEffectorLimits& e = ctx_.sim.end_effector;
    if (!e.any() || !std::isfinite(e.max_tilt)) return true;
    forward_kinematics(ctx_.sim.robot, goal_data_, q);
    return end_effector_tilt(ctx_.sim.robot, goal_data_, e) <= e.max_tilt;
  }

  int add(Node n) {
    nodes_.push_back(std::move(n));
    ++result_.counters.nodes;
    return static_cast<int>(nodes_.size()) - 1;
  }

  // Whether q passes the simulator's check of a state (limits, collisions, tilt), counted as a
  // collision check: a look at a predicted motion before simulating it.
  bool state_free(const JointVectorRef& q) {
    ++result_.counters.collision_checks;
    return check_state(ctx_.sim, ws_, q) == RolloutStatus::Valid;
  }

  // Whether the joint-space line from `from` to `to` looks free (line_looks_free), its states
  // counted as collision checks; `checks`, when given, gets them added too.
  bool line_free(const JointVectorRef& from, const JointVectorRef& to, uint64_t* checks = nullptr) {
    uint64_t looked = 0;
    const bool free = line_looks_free(ctx_.sim, ws_, from, to, &looked);
    result_.counters.collision_checks += looked;
    if (checks) *checks += looked;
    return free;
  }

  RolloutResult simulate_from(const JointVectorRef& q, const CommandProfile& profile) {
    const RolloutResult r = simulate(ctx_.sim, ws_, q, profile);
    count(r);
    return r;
  }
  // Counts `n` simulations of one corrected command, the last of them `last`.
  void count_simulations(int n, const RolloutResult& last) {
    result_.counters.simulations += n - 1;
    count(last);
  }
  // Counts a rollout the search uses (run here, or ahead of time by a RolloutPool).
  void count(const RolloutResult& r) {
    ++result_.counters.simulations;
    result_.counters.collision_checks += r.collision_checks;
    if (r.valid()) ++valid_;
    const int e = static_cast<int>(r.status) - static_cast<int>(RolloutStatus::EndEffectorSpeed);
    if (e >= 0 && e < 3) ++end_effector_rejections_[e];
  }

  // The path from the root to `node`: per node on the way, its step (`step_of(node)`: the
  // command that reached it) with the rollout that reached it (PathStep::outcome).
  template <typename StepOf>
  std::vector<PathStep> path_to(int node, StepOf step_of) const {
    std::vector<PathStep> steps;
    for (int u = node; nodes_[u].parent >= 0; u = nodes_[u].parent) {
      steps.push_back(step_of(nodes_[u]));
      steps.back().outcome = nodes_[u].outcome();
    }
    std::reverse(steps.begin(), steps.end());
    return steps;
  }

  // After a solution, for joint goals: whether a state of cost g and heuristic h cannot beat
  // the best (its cost plus the least remaining arc length, h minus the tolerance): the
  // searches neither expand nor keep it.
  bool prunable(double g, double h) const {
    if (!result_.success || problem_.goal.kind != Goal::Kind::Joint) return false;
    return g + std::max(0.0, h - problem_.goal.tolerance) >= result_.best_cost;
  }

  // A real node inside the goal region: a solution. `path_to` gives a node's path.
  void solution(int node, const std::function<std::vector<PathStep>(int)>& path_to) {
    offer(nodes_[node].cost, [&] { return path_to(node); });
  }

  // Direct connection first (issue 27): the straight command from the start to a joint goal
  // within the context's command limits (direct_step; for a pose goal or goal set, to each of
  // its first kDirectTargets configurations in turn). When it ends valid in the goal region it
  // is the solve's answer, found_by "direct" (no path is shorter by more than the goal's
  // tolerance, so the search is not run); true then.
  // With `look`, a target (the joint goal, or one of a pose goal's configurations) whose
  // joint-space line from the start collides (line_free) is not simulated.
  bool connect_directly(bool look = false) {
    const Goal& goal = problem_.goal;
    const int targets =
        goal.kind == Goal::Kind::Joint
            ? 1
            : std::min<int>(kDirectTargets, static_cast<int>(goal.configurations.size()));
    for (int k = 0; k < std::max(1, targets); ++k) {
      const JointVector* target = direct_target(goal, k);
      if (look && target && !line_free(problem_.start, *target)) continue;
      int simulations = 0;
      std::optional<PathStep> step =
          direct_step(ctx_.sim, ws_, ctx_.command, problem_, &simulations, k);
      if (!step) return false;
      count_simulations(simulations, *step->outcome);
      if (!solves(ctx_.sim, ws_, *step, problem_.goal)) continue;
      offer(step->outcome->path_length, [&] { return std::vector<PathStep>{std::move(*step)}; });
      result_.found_by = "direct";
      return true;
    }
    return false;
  }

  // Pose goals and goal sets, whose small regions a bundle edge or a random command seldom ends
  // in: from q within kGoalConnectRadius of one of the goal's configurations, the direct
  // command to the nearest, corrected to land in the goal (direct_step_to). The step when it
  // simulates valid; `simulations` gets how many it ran (all counted here).
  std::optional<PathStep> goal_connection(const JointVector& q, int& simulations) {
    simulations = 0;
    const auto [nearest, distance] = problem_.goal.nearest_configuration(q);
    if (!nearest || distance > kGoalConnectRadius) return std::nullopt;
    return connection(q, *nearest, simulations);
  }

  // The direct command from q to `target`, corrected to land in the goal region
  // (direct_step_to), when it simulates valid; `simulations` gets how many it ran (all counted
  // here).
  std::optional<PathStep> connection(const JointVector& q, const JointVector& target,
                                     int& simulations) {
    return connection(q, target, problem_.goal, simulations);
  }
  // The same, corrected to land in `land_in`; with `room` below 1, within that fraction of
  // the command limits (kJunctionRoom: a blend of its junctions fits).
  std::optional<PathStep> connection(const JointVector& q, const JointVector& target,
                                     const Goal& land_in, int& simulations, double room = 1) {
    simulations = 0;
    CommandSampling limits = ctx_.command;
    limits.limit_scale *= room;
    std::optional<PathStep> step =
        direct_step_to(ctx_.sim, ws_, limits, q, target, &land_in, &simulations);
    if (!step) return std::nullopt;
    count_simulations(simulations, *step->outcome);
    if (!step->outcome->valid()) return std::nullopt;
    return step;
  }

  // Straight commands through `points` (from the first, a real state) blended into one
  // (blended_step_through), corrected to land in the goal; the step when it simulates valid;
  // `simulations` gets how many it ran (all counted here).
  std::optional<PathStep> blended_connection(const std::vector<JointVector>& points,
                                             int& simulations) {
    simulations = 0;
    ExecutionOptions options;
    options.limits = ctx_.command;
    std::optional<PathStep> step =
        blended_step_through(ctx_.sim, ws_, options, points, problem_.goal, &simulations);
    if (!step) return std::nullopt;
    count_simulations(simulations, *step->outcome);
    if (!step->outcome->valid()) return std::nullopt;
    return step;
  }

  // The budget has run out, or the caller cancelled the solve.
  bool out_of_time() const { return deadline_.passed() || problem_.termination.cancelled(); }
  bool should_stop() const {
    return out_of_time() || (problem_.termination.stop_at_first && result_.success) ||
           task_hopeless();
  }

  // A task whose end-effector limits no motion meets (issue 29) is a clear failure, not a
  // timeout: once the first kTaskHopelessAfter simulations have all broken them.
  static constexpr uint64_t kTaskHopelessAfter = 200;
  bool task_hopeless() const {
    const uint64_t broke =
        end_effector_rejections_[0] + end_effector_rejections_[1] + end_effector_rejections_[2];
    return valid_ == 0 && broke >= kTaskHopelessAfter && broke == result_.counters.simulations;
  }
  // Why a solve that stopped without a solution did: the budget, or a hopeless task.
  std::string stop_failure() const {
    if (!task_hopeless()) return "no solution within the time budget";
    const auto& n = end_effector_rejections_;
    return "no motion meets the end-effector limits: all of the first " +
           std::to_string(result_.counters.simulations) + " commands simulated broke them (speed " +
           std::to_string(n[0]) + ", acceleration " + std::to_string(n[1]) + ", tilt " +
           std::to_string(n[2]) + ")";
  }

 private:
  void offer(double cost, const std::function<std::vector<PathStep>()>& path) {
    ++result_.n_solutions;
    if (!result_.success) {
      result_.success = true;
      result_.time_to_first_solution = deadline_.elapsed();
    }
    if (!(cost >= result_.best_cost)) {  // also when best_cost is NaN
      result_.best_cost = cost;
      result_.best_path = path();
    }
  }

  const PlanningContext& ctx_;
  SimulatorWorkspace& ws_;
  const PlanningProblem& problem_;
  Deadline deadline_;
  RobotData goal_data_;
  std::vector<Node> nodes_;
  PlanResult result_;
  uint64_t valid_ = 0;                                 // valid simulations
  std::array<uint64_t, 3> end_effector_rejections_{};  // by speed, acceleration, tilt
};

}  // namespace lazyboe
