#include "lazyboe/planning/planners/lazysp.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "lazyboe/planning/planners/bundle_search.h"
#include "lazyboe/planning/planners/tree_search.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {
namespace {

// Random streams of a query seed: LazyBoE 0, RRT and SST 1, lazysp 2, OMPL (its process-wide
// seed) 4 and its planners 5.
constexpr uint64_t kStream = 2;
// Scheduling between the lazy part and the growth is counted in work, not time, so that a
// seed gives the same result on any machine: one rollout is worth about this many expansions
// (a k-d tree query and its successors; measured on the 100k table bundle, ~1 ms vs ~20 us).
constexpr double kExpansionsPerRollout = 50;
constexpr double kHeadStart = 50;  // rollouts' worth of lazy work before growth gets a turn
constexpr double kLazyShare = 3;   // then lazy work may be up to 3x the growth's,
// divided by 1 + (failed candidates) / this: where the scene keeps blocking what the bundle
// predicts, the growth gets most of the work, as RRT would.
constexpr double kFailuresPerShare = 20;
// Expansions of a round's first search in a scene other than the bundle's, with the scene's
// marks in the edge cost, before the round searches without them.
constexpr size_t kMarkedSearchLimit = 1000;

// The declared parameters' values (lazysp_planner_info has their defaults).
struct Settings {
  double theta, epsilon, resolution, risk_weight, edge_penalty, goal_bias, mark_weight;
  size_t expansion_limit;
  bool direct;
};

// A state of the lazy search: predicted (never simulated) or, for a source, a real node's.
struct Predicted {
  JointVector q;
  double g = 0;       // real cost to the source plus the predicted edges' displacements and risk
  double length = 0;  // the same without the risk: a lower bound of the arc length (pruning)
  int parent = -1;    // -1: a source
  uint32_t edge = 0;  // from the parent
  int real = -1;      // a source's real node
  uint64_t cell = 0;
};

using Neighbours = std::vector<std::pair<uint32_t, double>>;

// A real (simulated) state of lazysp's tree, reached by a bundle edge or a growth command.
struct LazySpNode : SearchNode {
  int64_t bundle_edge = -1;  // the bundle edge from the parent, or -1
  int command = -1;          // else the growth's command (index into commands_), or -1: the root
};

class LazySpSearch {
 public:
  // One thread: the solve's rollout pool is not used.
  explicit LazySpSearch(const BundleSolve& solve)
      : ctx_(solve.context),
        bundle_(*solve.context.bundle),
        s_(solve.context, solve.ws, solve.problem),
        set_(settings_of(solve.theta, solve.values)),
        h_scale_(ctx_.mean_displacement > 0 ? 1 + set_.edge_penalty / ctx_.mean_displacement : 1),
        rng_(solve.problem.seed, kStream) {}

  // Beyond a bundle, the growth needs a sampling box.
  static void check_context(const PlanningContext& ctx, const ParameterValues&) {
    check_sampling_box(ctx, "lazysp");
  }

  PlanResult run();

 private:
  bool lazy_turn();
  void lazy_round();
  bool candidate(size_t& expansions, size_t limit, bool use_marks, std::vector<Predicted>& chain);
  int search(size_t& expansions, size_t limit);
  int expand(int p);
  bool push(Predicted x, double h);
  bool validate(const std::vector<Predicted>& chain);
  void grow();
  // A real node: the end of rollout r from `parent` (-1 and r.qf the start: the root).
  int add_real(const RolloutResult& r, int parent, int64_t edge, int command);
  void found(int node, const char* by);
  std::vector<PathStep> path_to(int node);
  bool prunable(double g, double h);
  bool within_limits(const JointVector& q) const;
  uint64_t cell(const JointVector& q) const;
  // The bundle's P_collision (its build scene's), and in a marked search the scene's marks.
  double risk(uint32_t e) const {
    const double stored = bundle_.has_perturbation() ? bundle_.p_collision(e) : 0.0;
    const bool marked = use_marks_ && ctx_.scene_marks->may_collide(e);
    return set_.risk_weight * stored + (marked ? set_.mark_weight : 0.0);
  }
  static uint64_t key(int v, uint32_t e) { return (static_cast<uint64_t>(v) << 32) | e; }
  static Settings settings_of(double theta, const ParameterValues& v) {
    return {theta,
            v.get("epsilon"),
            v.get("resolution"),
            v.get("risk_weight"),
            v.get("edge_penalty"),
            v.get("goal_bias"),
            v.get("mark_weight"),
            static_cast<size_t>(v.get("expansion_limit")),
            v.get("direct") != 0};
  }

  const PlanningContext& ctx_;
  const BundleView& bundle_;
  SearchState<LazySpNode> s_;
  const Settings set_;
  // The heuristic counts the edge penalty too: h / mean displacement more edges to the goal.
  const double h_scale_;
  Random rng_;
  bool goal_covered_ = true;
  std::unordered_set<uint64_t> tried_;  // (real node, edge) pairs simulated, valid or not
  std::vector<PathStep> commands_;      // the growth's commands, by LazySpNode::command
  Neighbours neighbours_;
  // One round of the lazy search (rebuilt every round from the real nodes).
  std::vector<Predicted> preds_;
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>>
      open_;
  std::unordered_map<uint64_t, double> best_in_cell_;
  // Scheduling, in rollouts' worth of work.
  double lazy_work_ = 0, growth_work_ = 0;
  bool exhausted_ = false;        // the last round found no candidate
  bool use_marks_ = false;        // the search costs the scene's marks
  bool marked_search_ = true;     // rounds still begin with a search that costs them
  double failed_candidates_ = 0;  // validated without reaching the goal
  size_t reals_at_exhaustion_ = 0;
};

PlanResult LazySpSearch::run() {
  if (set_.direct && s_.connect_directly()) return s_.result();
  RolloutResult at_start;
  at_start.qf = s_.problem().start;
  add_real(at_start, -1, -1, -1);
  // A predicted state x + qf(e) - q0(e), with x within theta of q0(e), lies within theta of
  // qf(e): a joint goal farther than theta + tolerance from every edge end is beyond the lazy
  // search, and only the growth can reach it.
  const Goal& goal = s_.problem().goal;
  if (goal.kind == Goal::Kind::Joint)
    goal_covered_ = edge_ends_near(ctx_, goal.q, set_.theta + goal.tolerance, neighbours_);
  while (!s_.should_stop()) {
    if (lazy_turn()) {
      lazy_round();
    } else {
      grow();
    }
  }
  PlanResult& r = s_.result();
  if (!r.success) r.failure = "no solution within the time budget";
  return r;
}

// The lazy part runs first and while it has not used more than its share; after a round
// without a candidate it waits for new real states and for the growth to have done as much.
bool LazySpSearch::lazy_turn() {
  if (!goal_covered_) return false;
  if (exhausted_)
    return s_.result().counters.nodes > reals_at_exhaustion_ && lazy_work_ <= growth_work_;
  const double share = kLazyShare / (1 + failed_candidates_ / kFailuresPerShare);
  return lazy_work_ <= kHeadStart + share * growth_work_;
}

// In a scene other than the bundle's, a round first looks for a candidate with the edges the scene
// may block (workspace-index marks) costed, within kMarkedSearchLimit expansions, then as in the
// bundle's scene. A goal enclosed by marked edges (a shelf's compartment) would let the marked
// search cost a hundred times more expansions: after one marked search finds nothing, the solve
// skips them.
void LazySpSearch::lazy_round() {
  const uint64_t rollouts = s_.result().counters.simulations;
  size_t expansions = 0;
  std::vector<Predicted> chain;
  bool found = false;
  if (ctx_.scene_marks && marked_search_) {
    found = candidate(expansions, kMarkedSearchLimit, true, chain);
    marked_search_ = found;  // once it finds nothing, the goal is enclosed by marked edges
  }
  if (!found) found = candidate(expansions, set_.expansion_limit, false, chain);
  if (found && !validate(chain)) ++failed_candidates_;
  lazy_work_ += static_cast<double>(expansions) / kExpansionsPerRollout +
                static_cast<double>(s_.result().counters.simulations - rollouts);
  exhausted_ = !found;
  reals_at_exhaustion_ = s_.result().counters.nodes;
}

// A candidate of one search within `limit` expansions in all: its source (a real state) and
// predicted states, in order; false when there is none.
bool LazySpSearch::candidate(size_t& expansions, size_t limit, bool use_marks,
                             std::vector<Predicted>& chain) {
  use_marks_ = use_marks;
  const int goal = search(expansions, limit);
  chain.clear();
  for (int u = goal; u >= 0; u = preds_[u].parent) chain.push_back(preds_[u]);
  std::reverse(chain.begin(), chain.end());
  return goal >= 0;
}

// Weighted A* (f = g + epsilon h) from every real node at once, each with its real cost, over
// predicted states; returns the predicted goal state of the candidate, or -1.
int LazySpSearch::search(size_t& expansions, size_t limit) {
  preds_.clear();
  open_ = {};
  best_in_cell_.clear();
  const std::vector<LazySpNode>& nodes = s_.nodes();
  for (size_t v = 0; v < nodes.size(); ++v) {
    const LazySpNode& n = nodes[v];
    if (s_.in_goal(n.h) || prunable(n.cost, n.h)) continue;  // a solution, or no better one
    Predicted x;
    x.q = n.q;
    x.g = n.cost;
    x.length = n.cost;
    x.real = static_cast<int>(v);
    push(x, n.h);
  }
  while (!open_.empty() && expansions < limit) {
    if (expansions % 8 == 0 && s_.out_of_time()) return -1;
    const int p = open_.top().second;
    open_.pop();
    if (best_in_cell_[preds_[p].cell] < preds_[p].g) continue;  // superseded in its cell
    ++expansions;
    const int goal = expand(p);
    if (goal >= 0) return goal;
  }
  return -1;
}

// The successors of predicted state p by displacement transfer; the cheapest one in the goal
// region, if any, is the candidate (goal test at generation: one expansion sooner).
int LazySpSearch::expand(int p) {
  const Predicted x = preds_[p];  // preds_ grows below
  ctx_.index->within(x.q.data(), set_.theta, neighbours_);
  const int n = bundle_.dof();
  int goal = -1;
  double goal_g = std::numeric_limits<double>::infinity();
  for (const auto& [e, d2] : neighbours_) {
    // From a real state, an edge simulated before is known: its real end is a source itself.
    if (x.real >= 0 && tried_.count(key(x.real, e))) continue;
    const JointVector step = Eigen::Map<const Eigen::VectorXd>(bundle_.qf(e), n) -
                             Eigen::Map<const Eigen::VectorXd>(bundle_.q0(e), n);
    Predicted c;
    c.q = x.q + step;
    if (!within_limits(c.q)) continue;
    c.g = x.g + step.norm() + risk(e) + set_.edge_penalty;
    c.length = x.length + step.norm();  // |qf - q0| is a lower bound of the arc length
    c.parent = p;
    c.edge = e;
    const double h = s_.heuristic(c.q);
    if (prunable(c.length, h) || !push(c, h)) continue;
    ++s_.result().counters.lazy_edges;
    if (s_.in_goal(h) && c.g < goal_g) {
      goal = static_cast<int>(preds_.size()) - 1;
      goal_g = c.g;
    }
  }
  return goal;
}

// Merging: a state is kept only if it is the cheapest so far in its cell of side `resolution`.
bool LazySpSearch::push(Predicted x, double h) {
  x.cell = cell(x.q);
  const auto [it, fresh] = best_in_cell_.try_emplace(x.cell, x.g);
  if (!fresh) {
    if (it->second <= x.g) return false;
    it->second = x.g;
  }
  open_.emplace(x.g + set_.epsilon * h * h_scale_, static_cast<int>(preds_.size()));
  preds_.push_back(std::move(x));
  return true;
}

// Simulates the candidate from its real source, edge by edge, each from the previous real end.
// A failed edge stays tried from that real state; the valid prefix stays in the tree as real
// nodes, from which the next round plans. A real end farther than theta/2 from its prediction
// ends the validation: the rest of the candidate was planned from a place the robot is not.
// True when it reached the goal.
bool LazySpSearch::validate(const std::vector<Predicted>& chain) {
  int r = chain.front().real;
  for (size_t k = 1; k < chain.size(); ++k) {
    if (s_.out_of_time()) return false;
    const uint32_t e = chain[k].edge;
    tried_.insert(key(r, e));
    const RolloutResult res = s_.simulate_from(s_.node(r).q, bundle_.command(e));
    if (!res.valid()) return false;
    const int c = add_real(res, r, e, -1);
    if (s_.in_goal(s_.node(c).h)) {  // really in the goal region: a solution
      found(c, "bundle");
      return true;
    }
    if ((res.qf - chain[k].q).norm() > set_.theta / 2) return false;
    r = c;
  }
  return false;
}

// One RRT step from the real nodes: a goal-biased sample, its nearest real node, a random
// command of the bundle's family.
void LazySpSearch::grow() {
  const int n = ctx_.sim.robot.dof;
  JointVector x(n);
  sample_state(ctx_, s_.problem(), set_.goal_bias, rng_, x);
  const int from = nearest_node(s_.nodes(), x, [](int) { return true; });
  std::vector<double> knots;
  const double duration = sample_command_profile(ctx_.sim.robot, ctx_.command, rng_, knots);
  const CommandProfile profile{knots.data(), static_cast<int>(knots.size() / n), n, duration};
  const RolloutResult res = s_.simulate_from(s_.node(from).q, profile);
  growth_work_ += 1;
  if (!res.valid()) return;
  commands_.push_back({-1, std::move(knots), duration});
  const int c = add_real(res, from, -1, static_cast<int>(commands_.size()) - 1);
  if (s_.in_goal(s_.node(c).h)) found(c, "growth");
}

int LazySpSearch::add_real(const RolloutResult& r, int parent, int64_t edge, int command) {
  LazySpNode n;
  n.reached(r, parent >= 0 ? s_.node(parent).cost : 0.0);
  n.parent = parent;
  n.bundle_edge = edge;
  n.command = command;
  n.h = s_.heuristic(n.q);
  return s_.add(std::move(n));
}

void LazySpSearch::found(int node, const char* by) {
  const bool better = !(s_.node(node).cost >= s_.result().best_cost);
  s_.solution(node, [this](int v) { return path_to(v); });
  if (better) s_.result().found_by = by;
}

std::vector<PathStep> LazySpSearch::path_to(int node) {
  std::vector<PathStep> steps;
  for (int u = node; s_.node(u).parent >= 0; u = s_.node(u).parent) {
    const LazySpNode& n = s_.node(u);
    if (n.bundle_edge < 0) {
      steps.push_back(commands_[n.command]);
    } else {
      const CommandProfile c = bundle_.command(n.bundle_edge);
      steps.push_back(
          {n.bundle_edge, std::vector<double>(c.knots, c.knots + c.n_knots * c.dof), c.duration});
    }
    steps.back().outcome = n.outcome();
  }
  std::reverse(steps.begin(), steps.end());
  return steps;
}

// After a solution, for joint goals: no state whose cost plus the least remaining arc length
// cannot beat the best (as BoE).
bool LazySpSearch::prunable(double g, double h) {
  const PlanResult& r = s_.result();
  if (!r.success || s_.problem().goal.kind != Goal::Kind::Joint) return false;
  return g + std::max(0.0, h - s_.problem().goal.tolerance) >= r.best_cost;
}

bool LazySpSearch::within_limits(const JointVector& q) const {
  const RobotModel& robot = ctx_.sim.robot;
  return (q.array() >= robot.q_min.array()).all() && (q.array() <= robot.q_max.array()).all();
}

// A 64-bit hash of the cell's integer coordinates (two cells sharing a hash would merge: for a
// round of a million states about one chance in 4 10^7, and then one state is lost).
uint64_t LazySpSearch::cell(const JointVector& q) const {
  uint64_t h = 0x9E3779B97F4A7C15ULL;
  for (int i = 0; i < q.size(); ++i) {
    const auto c = static_cast<int64_t>(std::floor(q[i] / set_.resolution));
    h ^= static_cast<uint64_t>(c) + 0x9E3779B97F4A7C15ULL + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ULL;
    h ^= h >> 31;
  }
  return h;
}

}  // namespace

PlannerInfo lazysp_planner_info() {
  PlannerInfo info;
  info.name = "lazysp";
  info.description =
      "lazy shortest path over predicted (transferred) edge ends; simulates only the candidate "
      "path; grows with random commands where the bundle does not reach; anytime";
  info.needs.bundle = true;
  ParameterSpec limit = real_parameter(
      "expansion_limit", 20000, 1, false,
      "predicted states expanded per round of the lazy search before it gives the growth a turn");
  limit.type = ParameterType::Integer;
  limit.upper = 1e9;
  info.parameters = {
      theta_parameter(),
      direct_parameter(),
      real_parameter("epsilon", 2.0, 1, false,
                     "heuristic weight of the lazy search (f = g + epsilon h; 1: A*)"),
      real_parameter("resolution", 0.05, 1e-6, false,  // a floor keeps the cell index finite
                     "cell side, rad, below which predicted states are merged"),
      real_parameter(
          "risk_weight", 0.5, 0, false,
          "rad of cost added per unit of an edge's P_collision (0 without perturbation)"),
      real_parameter("edge_penalty", 0.3, 0, false,
                     "rad of cost added per predicted edge: favours candidates of fewer edges, "
                     "each one simulation"),
      goal_bias_parameter(),
      limit,
      real_parameter("mark_weight", 2.0, 0, false,
                     "rad of cost added per edge a scene other than the bundle's may block "
                     "(workspace index), in the first search of each round"),
  };
  info.make = bundle_planner_factory<LazySpSearch>(info);
  return info;
}

}  // namespace lazyboe
