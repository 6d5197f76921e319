#include "lazyboe/planning/planners/lazyboe.h"

#include <algorithm>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/planners/bundle_search.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {
namespace {

constexpr double kTransferIndex = 1;  // lazy_model's index of "transfer"

class LazySearch : public BundleSearch {
 public:
  explicit LazySearch(const BundleSolve& solve)
      : BundleSearch(solve),
        transfer_(solve.values.get("lazy_model") == kTransferIndex),
        rng_(solve.problem.seed, 0) {}

 private:
  // Once the lazy search has run dry, every edge it took lazily is simulated from its node (a
  // second, exhaustive pass over the real nodes, as BoE would).
  bool refill() override {
    if (exhaustive_) return false;
    exhaustive_ = true;
    for (size_t u = 0; u < s_.nodes().size(); ++u) {
      BundleNode& node = s_.nodes()[u];
      const int v = static_cast<int>(u);
      if (lazy(v) || failed(v) || s_.in_goal(node.h)) continue;
      node.expanded = false;
      push(v);
    }
    return true;
  }

  double radius(int v) override { return lazy(v) ? theta_ / 2 : theta_; }

  // The lazy chain cannot go on (nothing starts within theta/2 of its stored end): it
  // terminates and is simulated; the node goes back to the queue as a real one, keyed by its
  // simulated heuristic (realize), and competes with the rest before its expansion.
  bool defer(int v) override {
    if (!lazy(v)) return false;
    realize(v);
    return true;
  }

  // P_select draws for the whole neighbourhood up front, so that the rollouts of a real node
  // can be run ahead, in parallel (RolloutScheduler).
  void begin_expansion(int, const Neighbours& neighbours) override {
    lazy_search_ = !exhaustive_;
    take_lazy_.assign(neighbours.size(), 0);
    if (!lazy_search_) return;
    for (size_t k = 0; k < neighbours.size(); ++k) {
      const uint32_t e = neighbours[k].first;
      take_lazy_[k] = rng_.uniform() < (1 - collision_prior(ctx_, e)) * p_lazy_prop(e);
    }
  }

  bool visit(int v, size_t k, uint32_t e) override {
    if (lazy_search_) {
      if (take_lazy_[k]) {
        take_lazily(v, e, k);
        return true;
      }
      if (lazy(v) && !realize(v)) return false;  // simulate the chain up to v first
    }
    simulate_edge(v, e, k);
    return true;
  }

  // Rollouts from the real node: the edges not taken lazily (and not simulated from it
  // before), and the lazy ones whose stored end is in the goal region (take_lazily simulates
  // them at once).
  bool needs_rollout(int v, size_t k) override {
    if (!take_lazy_[k]) return BundleSearch::needs_rollout(v, k);
    return s_.in_goal(s_.heuristic(lazy_end(v, expansion_edge(k))));
  }

  double promise(int v, uint32_t e) override { return s_.heuristic(lazy_end(v, e)); }

  // Where a lazy child of v by edge e is taken to be: the edge's stored end (the paper), or
  // v's state moved by the edge's displacement (transfer: the command from a shifted start
  // ends shifted by about as much).
  JointVector lazy_end(int v, uint32_t e) {
    return transfer_ ? JointVector(s_.node(v).q + (edge_end(e) - edge_start(e))) : edge_end(e);
  }
  double p_lazy_prop(uint32_t e) const {
    return transfer_ ? bundle_.p_lazy_prop_transfer(e) : bundle_.p_lazy_prop(e);
  }

  void take_lazily(int v, uint32_t e, size_t k);
  bool realize(int x, long k = -1);

  // LazyBoE's own node data, by node id (nodes the shared search adds are real: absent here).
  bool lazy(int v) const { return static_cast<size_t>(v) < lazy_.size() && lazy_[v]; }
  bool failed(int v) const { return static_cast<size_t>(v) < failed_.size() && failed_[v]; }
  static void set(std::vector<char>& flags, int v, bool value) {
    if (flags.size() <= static_cast<size_t>(v)) flags.resize(static_cast<size_t>(v) + 1, 0);
    flags[v] = value;
  }
  // A node under a failed lazy ancestor is dead too.
  bool dead(int v) override {
    for (int u = v; u >= 0; u = s_.node(u).parent) {
      if (failed(u)) return true;
      if (!lazy(u)) break;
    }
    return false;
  }
  bool is_solution(int v) override { return s_.in_goal(s_.node(v).h) && !lazy(v); }

  const bool transfer_;
  Random rng_;
  bool exhaustive_ = false;
  bool lazy_search_ = false;
  std::vector<char> take_lazy_;
  std::vector<char> lazy_;    // taken without simulation (its state: where it is taken to end)
  std::vector<char> failed_;  // its simulation failed, so its lazy subtree is dead
};

void LazySearch::take_lazily(int v, uint32_t e, size_t k) {
  ++s_.result().counters.lazy_edges;
  BundleNode c;
  c.q = lazy_end(v, e);
  c.parent = v;
  c.bundle_edge = e;
  c.cost = s_.node(v).cost + (edge_end(e) - edge_start(e)).norm();
  c.h = s_.heuristic(c.q);
  const int id = s_.add(c);
  set(lazy_, id, true);
  // SHOULD_TERMINATE_LAZY: the lazy path reaches the goal region (simulate it, the child
  // included), or the heuristic rises again (simulate the chain up to the parent, which was
  // the best point of it; the child waits in the queue). A tie counts as rising: an edge
  // whose stored end lies within theta/2 of its own start can be taken again from that end,
  // and a chain without progress would otherwise grow forever for free.
  if (s_.in_goal(c.h)) {
    realize(id, static_cast<long>(k));
  } else if (c.h >= s_.node(v).h && lazy(v)) {
    if (realize(v)) push(id);
  } else {
    push(id);
  }
}

// Simulates the lazy chain ending at `x` from its last simulated ancestor. Nodes that pass
// become real (their state the simulated end); the first failure kills the rest of the chain.
// `k`: x is the lazy child of the expanded node for its neighbour k (a one-edge chain).
bool LazySearch::realize(int x, long k) {
  std::vector<int> chain;
  for (int u = x; lazy(u); u = s_.node(u).parent) chain.push_back(u);
  std::reverse(chain.begin(), chain.end());
  for (int u : chain) {
    const int parent = s_.node(u).parent;
    const RolloutResult r =
        k >= 0 && chain.size() == 1 && parent == expanding()
            ? rollout_from(parent, static_cast<size_t>(k))
            : s_.simulate_from(s_.node(parent).q, bundle_.command(s_.node(u).bundle_edge));
    if (!r.valid()) {
      set(failed_, u, true);
      return false;
    }
    BundleNode& n = s_.node(u);
    n.reached(r, s_.node(parent).cost);
    set(lazy_, u, false);
    n.h = s_.heuristic(n.q);
    if (s_.in_goal(n.h)) {
      found(u);
    } else if (!n.expanded) {
      push(u);  // re-queued with its real heuristic
    }
  }
  return true;
}

class LazyBoE final : public BundlePlanner {
 public:
  using BundlePlanner::BundlePlanner;

 private:
  void check_context(const PlanningContext& ctx) override {
    if (values().get("lazy_model") == kTransferIndex && !ctx.bundle->has_transfer()) {
      fail(ctx.bundle->path(),
           "has no transfer statistics, which lazyboe's lazy_model transfer needs (run "
           "lazyboe-perturb --replace with this version)");
    }
  }

  PlanResult search(const BundleSolve& solve) override { return LazySearch(solve).run(); }
};

}  // namespace

PlannerInfo lazyboe_planner_info() {
  PlannerInfo info;
  info.name = "lazyboe";
  info.description =
      "LazyBoE: BoE taking edges lazily with P_select = (1 - P_collision) P_lazy_prop";
  info.needs.bundle = true;
  info.needs.perturbation = true;
  ParameterSpec model;
  model.name = "lazy_model";
  model.type = ParameterType::Choice;
  model.choices = {"stored", "transfer"};
  model.default_value = 0;
  model.description =
      "where a lazy edge ends: its stored end (the paper) or the node moved by the edge's "
      "displacement, with P_lazy_prop under transfer";
  info.parameters = {theta_parameter(), direct_parameter(), model};
  info.make = planner_factory<LazyBoE>(info);
  return info;
}

}  // namespace lazyboe
