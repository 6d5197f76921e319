// The search over bundle edges that BoE and LazyBoE share (internal; not installed): greedy
// best-first search on the heuristic (distance to the goal), where expanding a node simulates
// every bundle edge that starts within theta of it, applying the edge's command from the
// node's own state. LazyBoE (lazyboe.cpp) overrides the hooks below to take edges lazily.
#pragma once

#include <cstdint>
#include <queue>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/planning/rollout_scheduler.h"
#include "lazyboe/planning/search_tree.h"

namespace lazyboe {

// A node of the bundle searches: a state reached by a bundle edge.
struct BundleNode : SearchNode {
  int64_t bundle_edge = -1;  // the edge from the parent (-1: the root)
  bool expanded = false;
};

// What a bundle planner gives the search it makes for one solve (BundlePlanner): each search
// takes what it uses.
struct BundleSolve {
  const PlanningContext& context;
  SimulatorWorkspace& ws;
  const PlanningProblem& problem;
  double theta;                   // resolved at setup: the parameter, else the context's
  RolloutPool* pool;              // may run an expansion's rollouts ahead (BoE, LazyBoE)
  const ParameterValues& values;  // the planner's declared parameters
};

class BundleSearch {
 public:
  explicit BundleSearch(const BundleSolve& solve);

  virtual ~BundleSearch() = default;

  PlanResult run();

 protected:
  using Neighbours = std::vector<std::pair<uint32_t, double>>;  // (edge, sort key)

  // ---- Hooks (BoE's behaviour by default) ----
  // The open list ran dry: true when it was refilled and the search goes on.
  virtual bool refill() { return false; }
  // Radius of the neighbourhood expanded from node v.
  virtual double radius(int /*v*/) { return theta_; }
  // Node v has no neighbour: true when it was dealt with (and is not expanded now).
  virtual bool defer(int /*v*/) { return false; }
  // Called once per expansion, with the neighbours in the order they are visited.
  virtual void begin_expansion(int /*v*/, const Neighbours& /*neighbours*/) {}
  // Visits neighbour k (edge e) of the expanded node v; false ends the expansion.
  virtual bool visit(int v, size_t k, uint32_t e) {
    simulate_edge(v, e, k);
    return true;
  }
  // The sort key of edge e in the expansion of v (smaller first): the heuristic at its stored
  // end.
  virtual double promise(int /*v*/, uint32_t e) { return heuristic_at_end(e); }
  // Whether neighbour k of the real node v needs a rollout from v in this expansion.
  virtual bool needs_rollout(int v, size_t k);
  // Whether node v can no longer be part of a path (LazyBoE: under a failed lazy edge).
  virtual bool dead(int /*v*/) { return false; }
  // Whether node v is a solution (LazyBoE: not while its edge is only taken lazily).
  virtual bool is_solution(int v) { return s_.in_goal(s_.node(v).h); }

  // ---- For the hooks ----
  void push(int node) { open_.emplace(s_.node(node).h, node); }
  bool simulated(int v, uint32_t e) const { return simulated_.count(key(v, e)) > 0; }
  // Simulates edge e from the real node v (k: its place in the expansion) and adds the child.
  void simulate_edge(int v, uint32_t e, size_t k);
  // The rollout of neighbour k's edge from node v: from the scheduler when v is the real node
  // being expanded, else run here.
  RolloutResult rollout_from(int v, size_t k);
  void found(int node);
  double heuristic_at_end(uint32_t e);
  JointVector edge_end(uint32_t e) const;
  JointVector edge_start(uint32_t e) const;
  int expanding() const { return expanding_; }
  uint32_t expansion_edge(size_t k) const { return (*expansion_)[k].first; }

  const PlanningContext& ctx_;
  const BundleView& bundle_;
  SearchState<BundleNode> s_;
  const double theta_;
  const bool direct_;  // the `direct` parameter

 private:
  static uint64_t key(int v, uint32_t e) { return (static_cast<uint64_t>(v) << 32) | e; }
  bool covered();
  int pop();
  bool skip(int v);
  void expand(int v, Neighbours& neighbours);
  void order_by_promise(int v, Neighbours& edges);

  std::unordered_set<uint64_t> simulated_;  // (node, edge) pairs simulated
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>>
      open_;
  int expanding_ = -1;
  const Neighbours* expansion_ = nullptr;
  RolloutScheduler ahead_;
};

// Bundle edge e as a step of a returned path (its command and duration).
PathStep bundle_edge_step(const BundleView& bundle, uint32_t e);

// theta, as BoE and LazyBoE declare it (default: the bundle's).
ParameterSpec theta_parameter();
// `direct`, as every bundle planner declares it: SearchState::connect_directly before the search.
ParameterSpec direct_parameter();

// Setup shared by the bundle planners: the context must have a bundle and its index (and,
// with `perturbation`, the perturbation analysis); returns theta (the parameter, else the
// context's), which must be > 0.
double bundle_planner_setup(const PlanningContext& context, const ParameterValues& values,
                            const std::string& planner, bool perturbation);

// Whether some bundle edge ends within `radius` of q: through the context's end-state index
// when it has one (a k-d tree query), else by scanning every end state. `scratch` gets those
// edges with their squared distances, by edge id (as EdgeIndex::within gives them).
bool edge_ends_near(const PlanningContext& context, const JointVectorRef& q, double radius,
                    std::vector<std::pair<uint32_t, double>>& scratch);
// The same question when the edges are not needed (a coverage check): the index's search stops
// at the first edge end it finds, rather than listing and sorting thousands.
bool some_edge_ends_near(const PlanningContext& context, const JointVectorRef& q, double radius);
// The `count` edges ending nearest q within `radius`, nearest first (equal distances by edge id),
// into `scratch` with their squared distances.
void edges_ending_nearest(const PlanningContext& context, const JointVectorRef& q, size_t count,
                          double radius, std::vector<std::pair<uint32_t, double>>& scratch);

// The base of the bundle planners (BoE, LazyBoE, lazysp): setup checks that the context has a
// bundle and its index (and the perturbation analysis, when the planner's needs say so),
// resolves theta (the parameter, else the context's) and runs the planner's own checks; each
// solve runs the planner's search, made from a BundleSolve.
class BundlePlanner : public DeclaredPlanner {
 public:
  using DeclaredPlanner::DeclaredPlanner;

  void prepare(const PlanningContext& context) final {
    const double theta = bundle_planner_setup(context, values(), name(), needs().perturbation);
    check_context(context);
    theta_ = theta;  // only once every check passed
  }

  PlanResult solve(const PlanningProblem& problem, SimulatorWorkspace& ws,
                   RolloutPool* pool) final {
    return search(BundleSolve{context(), ws, problem, theta_, pool, values()});
  }

 protected:
  // What the planner needs of the context beyond a bundle; throws Error naming it.
  virtual void check_context(const PlanningContext& /*context*/) {}
  // One solve: the planner's own search.
  virtual PlanResult search(const BundleSolve& solve) = 0;

 private:
  double theta_ = 0;
};

}  // namespace lazyboe
