#include "lazyboe/planning/planners/tree_search.h"

#include <algorithm>
#include <limits>

namespace lazyboe {

ParameterSpec goal_bias_parameter() {
  ParameterSpec p;
  p.name = "goal_bias";
  p.default_value = 0.05;
  p.lower = 0;
  p.upper = 1;
  p.description = "probability of sampling the goal (joint goals) instead of a random state";
  return p;
}

void check_sampling_box(const PlanningContext& ctx, const std::string& planner) {
  const int n = ctx.sim.robot.dof;
  if (ctx.sample_lower.size() != n || ctx.sample_upper.size() != n) {
    fail("planner", planner + " needs a sampling box of " + std::to_string(n) + " joints");
  }
}

TreeSearch::TreeSearch(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p,
                       const ParameterValues& values)
    : ctx_(ctx), s_(ctx, ws, p), rng_(p.seed, 1), goal_bias_(values.get("goal_bias")) {}

PlanResult TreeSearch::run() {
  const int n = ctx_.sim.robot.dof;
  TreeNode root;
  root.q = s_.problem().start;
  root.h = s_.heuristic(root.q);
  add(root, -1);
  start(root);
  JointVector x(n);
  std::vector<double> knots;
  while (!s_.should_stop()) {
    sample(x);
    const int from = select(x);
    const double duration = sample_command_profile(ctx_.sim.robot, ctx_.command, rng_, knots);
    const CommandProfile profile{knots.data(), static_cast<int>(knots.size() / n), n, duration};
    const RolloutResult r = s_.simulate_from(s_.node(from).q, profile);
    if (!r.valid()) continue;
    TreeNode c;
    c.reached(r, s_.node(from).cost);
    c.parent = from;
    c.h = s_.heuristic(c.q);
    if (!admit(c)) continue;
    c.command = static_cast<int>(commands_.size());
    commands_.push_back({-1, knots, duration});
    const int id = add(c, from);
    added(id);
    const int in_goal = s_.in_goal(c.h) ? id : connect(id);
    if (in_goal >= 0) {
      s_.solution(in_goal, [this](int u) {
        return s_.path_to(u, [this](const TreeNode& n) { return commands_[n.command]; });
      });
      if (stop_at_solution()) break;
    }
  }
  PlanResult& result = s_.result();
  if (!result.success) result.failure = s_.stop_failure();
  return s_.take_result();
}

void sample_state(const PlanningContext& ctx, const PlanningProblem& p, double goal_bias,
                  Random& rng, JointVector& x) {
  if (p.goal.kind == Goal::Kind::Joint && rng.uniform() < goal_bias) {
    x = p.goal.q;
    return;
  }
  // Pose goals and sets: one of their configurations.
  const std::vector<JointVector>& in_goal = p.goal.configurations;
  if (!in_goal.empty() && rng.uniform() < goal_bias) {
    x = in_goal[static_cast<size_t>(rng.uniform() * in_goal.size()) % in_goal.size()];
    return;
  }
  for (int i = 0; i < x.size(); ++i) x[i] = rng.uniform(ctx.sample_lower[i], ctx.sample_upper[i]);
}

// Pose goals and goal sets: the direct command from node v into the goal
// (SearchState::goal_connection); the node it reached in the goal, or -1.
int TreeSearch::connect(int v) {
  int simulations = 0;
  std::optional<PathStep> step = s_.goal_connection(s_.node(v).q, simulations);
  if (!step) return -1;
  TreeNode g;
  g.reached(*step->outcome, s_.node(v).cost);
  g.parent = v;
  g.h = s_.heuristic(g.q);
  if (!s_.in_goal(g.h)) return -1;
  g.command = static_cast<int>(commands_.size());
  commands_.push_back({-1, std::move(step->knots), step->command_duration});
  const int id = add(g, v);
  added(id);
  return id;
}

void TreeSearch::sample(JointVector& x) { sample_state(ctx_, s_.problem(), goal_bias_, rng_, x); }

int TreeSearch::nearest(const JointVector& x) {
  return nearest_node(s_.nodes(), x, [this](int v) { return live(v); });
}

int TreeSearch::add(TreeNode c, int from) {
  const int id = s_.add(std::move(c));
  children_.push_back(0);
  retired_.push_back(0);
  if (from >= 0) ++children_[from];
  return id;
}

}  // namespace lazyboe
