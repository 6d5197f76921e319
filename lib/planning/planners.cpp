#include "lazyboe/planning/planners.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <unordered_set>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/ompl_planners.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {
namespace {

struct Node {
  JointVector q;  // state at rest; for a lazy node, the stored end of its edge
  int parent = -1;
  int64_t edge = -1;  // bundle edge from the parent, or index into `commands` (RRT/SST)
  double cost = 0;    // arc length from the start (estimated for lazy nodes)
  double h = 0;       // heuristic: distance to the goal
  bool lazy = false;
  bool dead = false;      // failed simulation (lazy chains) or pruned (SST)
  bool inactive = false;  // SST: no longer the representative of its witness
  bool expanded = false;
};

// Bookkeeping common to every search: nodes, solutions, counters.
class SearchState {
 public:
  SearchState(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p)
      : ctx_(ctx), ws_(ws), problem_(p), deadline_(p.params.budget), goal_data_(ctx.sim.robot) {}

  const PlanningProblem& problem() const { return problem_; }
  const Deadline& deadline() const { return deadline_; }
  std::vector<Node>& nodes() { return nodes_; }
  PlanResult& result() { return result_; }

  double heuristic(const JointVectorRef& q) {
    return problem_.goal.distance(ctx_.sim.robot, goal_data_, q);
  }
  bool in_goal(double h) const { return h <= problem_.goal.tolerance; }

  int add(Node n) {
    nodes_.push_back(std::move(n));
    ++result_.counters.nodes;
    return static_cast<int>(nodes_.size()) - 1;
  }

  RolloutResult simulate_from(const JointVectorRef& q, const CommandProfile& profile) {
    const RolloutResult r = simulate(ctx_.sim, ws_, q, profile);
    count(r);
    return r;
  }
  // Counts a rollout the search uses (run here, or ahead of time by a RolloutPool).
  void count(const RolloutResult& r) {
    ++result_.counters.simulations;
    result_.counters.collision_checks += r.collision_checks;
  }

  // A real node inside the goal region: a solution.
  void solution(int node, const std::function<std::vector<PathStep>(int)>& path_to) {
    ++result_.n_solutions;
    if (!result_.success) {
      result_.success = true;
      result_.time_to_first_solution = deadline_.elapsed();
    }
    if (!(nodes_[node].cost >= result_.best_cost)) {  // also when best_cost is NaN
      result_.best_cost = nodes_[node].cost;
      result_.best_path = path_to(node);
    }
  }

  bool should_stop() const {
    return deadline_.passed() || (problem_.params.stop_at_first && result_.success);
  }

 private:
  const PlanningContext& ctx_;
  SimulatorWorkspace& ws_;
  const PlanningProblem& problem_;
  Deadline deadline_;
  RobotData goal_data_;
  std::vector<Node> nodes_;
  PlanResult result_;
};

JointVector row(const double* p, int n) { return Eigen::Map<const Eigen::VectorXd>(p, n); }

// ---- BoE and LazyBoE ------------------------------------------------------------------------

class BundleSearch {
 public:
  BundleSearch(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p,
               bool lazy, RolloutPool* pool)
      : ctx_(ctx),
        s_(ctx, ws, p),
        lazy_(lazy),
        theta_(p.params.theta),
        rng_(p.params.seed, 0),
        pool_(pool && pool->threads() > 1 ? pool : nullptr) {}

  PlanResult run() {
    const BundleView& b = *ctx_.bundle;
    const int n = b.dof();
    Node root;
    root.q = s_.problem().start;
    root.h = s_.heuristic(root.q);
    push(s_.add(root));
    std::vector<std::pair<uint32_t, double>> neighbours;
    // Coverage: a start or goal the bundle cannot reach is a clear failure, not a timeout.
    ctx_.index->within(root.q.data(), theta_, neighbours);
    if (neighbours.empty()) {
      s_.result().failure = "no bundle edge starts within theta = " + std::to_string(theta_) +
                            " rad of the start: it is outside the bundle's coverage";
      return s_.result();
    }
    const Goal& goal = s_.problem().goal;
    if (goal.kind == Goal::Kind::Joint) {
      const double reach = theta_ + goal.tolerance;
      bool covered = false;
      for (size_t e = 0; e < b.size() && !covered; ++e) {
        covered = (row(b.qf(e), n) - goal.q).squaredNorm() <= reach * reach;
      }
      if (!covered) {
        s_.result().failure =
            "no bundle edge ends within theta + tolerance = " + std::to_string(reach) +
            " rad of the goal: it is outside the bundle's coverage";
        return s_.result();
      }
    }
    while (!s_.should_stop()) {
      if (open_.empty()) {
        // LazyBoE: once the lazy search has run dry, every edge it took lazily is simulated
        // from its node (a second, exhaustive pass over the real nodes, as BoE would).
        if (!lazy_ || exhaustive_) break;
        exhaustive_ = true;
        for (size_t u = 0; u < s_.nodes().size(); ++u) {
          Node& node = s_.nodes()[u];
          if (node.lazy || node.dead || s_.in_goal(node.h)) continue;
          node.expanded = false;
          push(static_cast<int>(u));
        }
        if (open_.empty()) break;
      }
      const int v = open_.top().second;
      open_.pop();
      if (s_.nodes()[v].expanded || dead(v)) continue;
      if (s_.in_goal(s_.nodes()[v].h) && !s_.nodes()[v].lazy) continue;  // already a solution
      if (prunable(v)) continue;
      const bool lazy_node = s_.nodes()[v].lazy;
      ctx_.index->within(s_.nodes()[v].q.data(), lazy_node ? theta_ / 2 : theta_, neighbours);
      if (neighbours.empty() && lazy_node) {
        // The lazy chain cannot go on (nothing starts within theta/2 of its stored end): it
        // terminates and is simulated; the node goes back to the queue as a real one, keyed by
        // its simulated heuristic (realize), and competes with the rest before its expansion.
        realize(v);
        continue;
      }
      s_.nodes()[v].expanded = true;
      // Most promising edges first (heuristic at their stored end): the same edges are taken,
      // but a goal reached in this expansion is reached sooner.
      order_by_promise(neighbours, n);
      // P_select draws for the whole neighbourhood up front (so that the rollouts of a real
      // node can be run ahead, in parallel; see rollout_from).
      const bool lazy_search = lazy_ && !exhaustive_;
      take_lazy_.assign(neighbours.size(), 0);
      if (lazy_search) {
        for (size_t k = 0; k < neighbours.size(); ++k) {
          const uint32_t e = neighbours[k].first;
          take_lazy_[k] = rng_.uniform() < (1 - b.p_collision(e)) * b.p_lazy_prop(e);
        }
      }
      begin_expansion(v, neighbours);
      for (size_t k = 0; k < neighbours.size(); ++k) {
        const uint32_t e = neighbours[k].first;
        if (s_.should_stop() || dead(v)) break;
        if (lazy_search) {
          if (take_lazy_[k]) {
            take_lazily(v, e, n, k);
            continue;
          }
          if (s_.nodes()[v].lazy && !realize(v)) break;  // simulate the lazy chain up to v first
        }
        simulate_edge(v, e, k);
      }
    }
    PlanResult& r = s_.result();
    if (!r.success && r.failure.empty()) {
      r.failure = open_.empty() ? "search exhausted: no more nodes to expand within the bundle"
                                : "no solution within the time budget";
    }
    return r;
  }

 private:
  void push(int node) { open_.emplace(s_.nodes()[node].h, node); }

  void order_by_promise(std::vector<std::pair<uint32_t, double>>& edges, int n) {
    const BundleView& b = *ctx_.bundle;
    for (auto& [e, key] : edges) key = s_.heuristic(row(b.qf(e), n));
    std::stable_sort(edges.begin(), edges.end(),
                     [](const auto& x, const auto& y) { return x.second < y.second; });
  }

  // A node under a dead ancestor (a lazy chain that failed) is dead too.
  bool dead(int v) {
    for (int u = v; u >= 0; u = s_.nodes()[u].parent) {
      if (s_.nodes()[u].dead) return true;
      if (!s_.nodes()[u].lazy) break;
    }
    return false;
  }

  // After a solution, a node whose cost plus the least remaining arc length (joint goals:
  // distance to the goal minus the tolerance) cannot beat the best is not expanded.
  bool prunable(int v) {
    const PlanResult& r = s_.result();
    if (!r.success || s_.problem().goal.kind != Goal::Kind::Joint) return false;
    const Node& node = s_.nodes()[v];
    return node.cost + std::max(0.0, node.h - s_.problem().goal.tolerance) >= r.best_cost;
  }

  std::vector<PathStep> path_to(int node) {
    std::vector<PathStep> steps;
    const BundleView& b = *ctx_.bundle;
    for (int u = node; s_.nodes()[u].parent >= 0; u = s_.nodes()[u].parent) {
      const CommandProfile c = b.command(s_.nodes()[u].edge);
      steps.push_back({s_.nodes()[u].edge,
                       std::vector<double>(c.knots, c.knots + c.n_knots * c.dof), c.duration});
    }
    std::reverse(steps.begin(), steps.end());
    return steps;
  }

  void found(int node) {
    s_.solution(node, [this](int u) { return path_to(u); });
  }

  // ---- Rollouts of the expanded node, ahead of time ----
  // Once the expanded node v is real, every rollout the rest of its expansion needs starts at
  // v's state: the edges not taken lazily (and not simulated from v before), and the lazy ones
  // whose stored end is in the goal region (take_lazily simulates them at once). Those are
  // independent, so with a RolloutPool they run in waves of kWavePerThread per thread, in
  // expansion order, and the search consumes them in that order exactly as if it had run them
  // itself: its results do not depend on the number of threads. Only when the search stops
  // (first solution, budget) can the rest of a wave go unused; counters count used rollouts.

  void begin_expansion(int v, const std::vector<std::pair<uint32_t, double>>& neighbours) {
    expanding_ = v;
    expansion_ = &neighbours;
    ahead_.assign(neighbours.size(), Ahead::Unplanned);
    planned_from_ = -1;
  }

  bool needs_rollout_from_real(int v, size_t k) {
    const uint32_t e = (*expansion_)[k].first;
    if (!take_lazy_[k]) return !simulated_.count((static_cast<uint64_t>(v) << 32) | e);
    return s_.in_goal(s_.heuristic(row(ctx_.bundle->qf(e), ctx_.bundle->dof())));
  }

  // The rollout of neighbour k's edge from the expanded node v, which is real.
  RolloutResult rollout_from(int v, size_t k) {
    const uint32_t e = (*expansion_)[k].first;
    if (!pool_ || v != expanding_)
      return s_.simulate_from(s_.nodes()[v].q, ctx_.bundle->command(e));
    if (planned_from_ < 0) {
      // v became real at neighbour k: from here on, mark which neighbours need a rollout.
      planned_from_ = static_cast<long>(k);
      for (size_t j = k; j < ahead_.size(); ++j)
        ahead_[j] = needs_rollout_from_real(v, j) ? Ahead::Needed : Ahead::None;
    }
    if (ahead_[k] != Ahead::Done) {
      // A wave: this rollout and the next ones needed.
      wave_.clear();
      tasks_.clear();
      for (size_t j = k;
           j < ahead_.size() && static_cast<int>(wave_.size()) < kWavePerThread * pool_->threads();
           ++j) {
        if (j != k && ahead_[j] != Ahead::Needed) continue;
        wave_.push_back(j);
        tasks_.push_back({s_.nodes()[v].q.data(), ctx_.bundle->command((*expansion_)[j].first)});
      }
      if (results_.size() < ahead_.size()) results_.resize(ahead_.size());
      wave_results_.resize(wave_.size());
      pool_->run(tasks_.data(), wave_results_.data(), static_cast<int>(wave_.size()));
      for (size_t w = 0; w < wave_.size(); ++w) {
        results_[wave_[w]] = wave_results_[w];
        ahead_[wave_[w]] = Ahead::Done;
      }
    }
    ahead_[k] = Ahead::None;  // used
    s_.count(results_[k]);
    return results_[k];
  }

  void simulate_edge(int v, uint32_t e, size_t k) {
    // The same edge from the same real node always gives the same rollout: never twice.
    if (!simulated_.insert((static_cast<uint64_t>(v) << 32) | e).second) return;
    const RolloutResult r = rollout_from(v, k);
    if (!r.valid()) return;
    Node c;
    c.q = r.qf;
    c.parent = v;
    c.edge = e;
    c.cost = s_.nodes()[v].cost + r.path_length;
    c.h = s_.heuristic(c.q);
    const int id = s_.add(c);
    if (s_.in_goal(c.h)) {
      found(id);
    } else {
      push(id);
    }
  }

  void take_lazily(int v, uint32_t e, int n, size_t k) {
    const BundleView& b = *ctx_.bundle;
    ++s_.result().counters.lazy_edges;
    Node c;
    c.q = row(b.qf(e), n);
    c.parent = v;
    c.edge = e;
    c.lazy = true;
    c.cost = s_.nodes()[v].cost + (row(b.qf(e), n) - row(b.q0(e), n)).norm();
    c.h = s_.heuristic(c.q);
    const int id = s_.add(c);
    // SHOULD_TERMINATE_LAZY: the lazy path reaches the goal region (simulate it, the child
    // included), or the heuristic rises again (simulate the chain up to the parent, which was
    // the best point of it; the child waits in the queue). A tie counts as rising: an edge
    // whose stored end lies within theta/2 of its own start can be taken again from that end,
    // and a chain without progress would otherwise grow forever for free.
    if (s_.in_goal(c.h)) {
      realize(id, k);
    } else if (c.h >= s_.nodes()[v].h && s_.nodes()[v].lazy) {
      if (realize(v)) push(id);
    } else {
      push(id);
    }
  }

  // Simulates the lazy chain ending at `x` from its last simulated ancestor. Nodes that pass
  // become real (their state the simulated end); the first failure kills the rest of the chain.
  // `k`: x is the lazy child of the expanded node for its neighbour k (a one-edge chain).
  bool realize(int x, long k = -1) {
    std::vector<int> chain;
    for (int u = x; s_.nodes()[u].lazy; u = s_.nodes()[u].parent) chain.push_back(u);
    std::reverse(chain.begin(), chain.end());
    for (int u : chain) {
      Node& node = s_.nodes()[u];
      const Node& parent = s_.nodes()[node.parent];
      const RolloutResult r = k >= 0 && chain.size() == 1 && node.parent == expanding_
                                  ? rollout_from(node.parent, static_cast<size_t>(k))
                                  : s_.simulate_from(parent.q, ctx_.bundle->command(node.edge));
      if (!r.valid()) {
        s_.nodes()[u].dead = true;
        return false;
      }
      Node& n = s_.nodes()[u];  // (no reallocation above, but keep references short)
      n.q = r.qf;
      n.lazy = false;
      n.cost = s_.nodes()[n.parent].cost + r.path_length;
      n.h = s_.heuristic(n.q);
      if (s_.in_goal(n.h)) {
        found(u);
      } else if (!n.expanded) {
        push(u);  // re-queued with its real heuristic
      }
    }
    return true;
  }

  const PlanningContext& ctx_;
  SearchState s_;
  bool lazy_;
  bool exhaustive_ = false;
  std::unordered_set<uint64_t> simulated_;  // (node, edge) pairs simulated
  double theta_;
  Random rng_;
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>>
      open_;
  // The expansion in progress: its node, neighbours, P_select draws, rollouts run ahead.
  enum class Ahead : uint8_t { Unplanned, None, Needed, Done };
  RolloutPool* pool_;  // null: every rollout runs when it is needed, on the search's workspace
  int expanding_ = -1;
  const std::vector<std::pair<uint32_t, double>>* expansion_ = nullptr;
  std::vector<char> take_lazy_;
  std::vector<Ahead> ahead_;
  long planned_from_ = -1;
  std::vector<size_t> wave_;
  std::vector<RolloutTask> tasks_;
  std::vector<RolloutResult> results_, wave_results_;
};

// ---- RRT and SST ----------------------------------------------------------------------------

class TreeSearch {
 public:
  TreeSearch(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p, bool sst)
      : ctx_(ctx), s_(ctx, ws, p), sst_(sst), rng_(p.params.seed, 1) {}

  PlanResult run() {
    const PlannerParams& params = s_.problem().params;
    const int n = ctx_.sim.robot.dof;
    Node root;
    root.q = s_.problem().start;
    root.h = s_.heuristic(root.q);
    s_.add(root);
    children_.push_back(0);
    if (sst_) witnesses_.push_back({root.q, 0});
    const double delta_bn = params.selection_radius,
                 delta_s = params.pruning_ratio * params.selection_radius;
    JointVector x(n);
    std::vector<double> knots;
    while (!s_.should_stop()) {
      sample(x);
      const int from = sst_ ? select_sst(x, delta_bn) : nearest(x);
      const double duration = sample_command_profile(ctx_.sim.robot, params.command, rng_, knots);
      const CommandProfile profile{knots.data(), static_cast<int>(knots.size() / n), n, duration};
      const RolloutResult r = s_.simulate_from(s_.nodes()[from].q, profile);
      if (!r.valid()) continue;
      Node c;
      c.q = r.qf;
      c.parent = from;
      c.cost = s_.nodes()[from].cost + r.path_length;
      c.h = s_.heuristic(c.q);
      int witness = -1;
      if (sst_) {
        witness = nearest_witness(c.q);
        if (witness < 0 || (witnesses_[witness].q - c.q).norm() > delta_s) {
          witnesses_.push_back({c.q, -1});
          witness = static_cast<int>(witnesses_.size()) - 1;
        }
        const int rep = witnesses_[witness].representative;
        if (rep >= 0 && s_.nodes()[rep].cost <= c.cost) continue;  // not better locally: drop
        if (rep >= 0) deactivate(rep);
      }
      c.edge = static_cast<int64_t>(commands_.size());
      commands_.push_back({-1, knots, duration});
      const int id = s_.add(c);
      children_.push_back(0);
      ++children_[from];
      if (sst_) witnesses_[witness].representative = id;
      if (s_.in_goal(c.h)) {
        s_.solution(id, [this](int u) { return path_to(u); });
        if (!sst_) break;  // RRT stops at its first solution
      }
    }
    PlanResult& r = s_.result();
    if (!r.success) r.failure = "no solution within the time budget";
    return r;
  }

 private:
  struct Witness {
    JointVector q;
    int representative;
  };

  void sample(JointVector& x) {
    const PlannerParams& p = s_.problem().params;
    if (s_.problem().goal.kind == Goal::Kind::Joint && rng_.uniform() < p.goal_bias) {
      x = s_.problem().goal.q;
      return;
    }
    for (int i = 0; i < x.size(); ++i) x[i] = rng_.uniform(p.sample_lower[i], p.sample_upper[i]);
  }

  int nearest(const JointVector& x) {
    int best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    const std::vector<Node>& nodes = s_.nodes();
    for (size_t v = 0; v < nodes.size(); ++v) {
      if (nodes[v].dead || nodes[v].inactive) continue;
      const double d = (nodes[v].q - x).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(v);
      }
    }
    return best;
  }

  // SST's Best-Near selection: the lowest-cost active node within delta_BN, else the nearest.
  int select_sst(const JointVector& x, double delta_bn) {
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    const std::vector<Node>& nodes = s_.nodes();
    for (size_t v = 0; v < nodes.size(); ++v) {
      if (nodes[v].dead || nodes[v].inactive) continue;
      if ((nodes[v].q - x).norm() <= delta_bn && nodes[v].cost < best_cost) {
        best_cost = nodes[v].cost;
        best = static_cast<int>(v);
      }
    }
    return best >= 0 ? best : nearest(x);
  }

  int nearest_witness(const JointVector& q) const {
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t w = 0; w < witnesses_.size(); ++w) {
      const double d = (witnesses_[w].q - q).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(w);
      }
    }
    return best;
  }

  // The old representative becomes inactive; inactive leaves are removed, recursively upwards.
  void deactivate(int v) {
    std::vector<Node>& nodes = s_.nodes();
    nodes[v].inactive = true;
    while (v > 0 && nodes[v].inactive && !nodes[v].dead && children_[v] == 0) {
      nodes[v].dead = true;
      const int parent = nodes[v].parent;
      --children_[parent];
      v = parent;
    }
  }

  std::vector<PathStep> path_to(int node) {
    std::vector<PathStep> steps;
    for (int u = node; s_.nodes()[u].parent >= 0; u = s_.nodes()[u].parent)
      steps.push_back(commands_[s_.nodes()[u].edge]);
    std::reverse(steps.begin(), steps.end());
    return steps;
  }

  const PlanningContext& ctx_;
  SearchState s_;
  bool sst_;
  Random rng_;
  std::vector<PathStep> commands_;
  std::vector<int> children_;
  std::vector<Witness> witnesses_;
};

}  // namespace

PlanResult plan(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& problem,
                RolloutPool* pool) {
  const std::string& name = problem.params.planner;
  if (name == "boe" || name == "lazyboe") {
    if (!ctx.bundle || !ctx.index) fail("planner", name + " needs an edge bundle");
    if (name == "lazyboe" && !ctx.bundle->has_perturbation()) {
      fail(ctx.bundle->path(),
           "has no complete perturbation analysis, which lazyboe needs (run lazyboe-perturb)");
    }
    if (!(problem.params.theta > 0)) fail("theta", "must be > 0");
    return BundleSearch(ctx, ws, problem, name == "lazyboe", pool).run();
  }
  if (name == "rrt" || name == "sst") {
    PlanningProblem p = problem;
    if (name == "rrt") p.params.stop_at_first = true;
    return TreeSearch(ctx, ws, p, name == "sst").run();
  }
  if (is_ompl_planner(name)) return plan_ompl(ctx, ws, problem);
  fail("planner", "unknown planner '" + name +
                      "' (expected lazyboe, boe, rrt, sst, ompl-rrt, ompl-sst or ompl-kpiece)");
}

}  // namespace lazyboe
