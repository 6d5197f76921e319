#include "lazyboe/planning/planners/bundle_search.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace lazyboe {
namespace {

JointVector row(const double* p, int n) { return Eigen::Map<const Eigen::VectorXd>(p, n); }

// The joints of q outside the bundle's sampling region, with their values and bounds; empty
// when q lies inside it.
std::string joints_outside_region(const PlanningContext& ctx, const JointVectorRef& q) {
  std::string text;
  const JointVector& lo = ctx.sample_lower;
  const JointVector& hi = ctx.sample_upper;
  for (int i = 0; i < q.size() && lo.size() == q.size() && hi.size() == q.size(); ++i) {
    if (q[i] >= lo[i] && q[i] <= hi[i]) continue;
    char joint[160];
    std::snprintf(joint, sizeof joint, "%sjoint %d (%s) is %.3f, the bundle's region [%.3f, %.3f]",
                  text.empty() ? "" : "; ", i + 1, ctx.sim.robot.joints[i].name.c_str(), q[i],
                  lo[i], hi[i]);
    text += joint;
  }
  return text;
}

// The distance from q to the nearest edge start (end, for `ends`): by the index, widening the
// radius, or by a scan of the ends without an end index; infinity when there is none.
double nearest_edge(const PlanningContext& ctx, const JointVectorRef& q, bool ends) {
  const EdgeIndex* index = ends ? ctx.end_index : ctx.index;
  double nearest = std::numeric_limits<double>::infinity();
  if (!index && !ends) return nearest;  // no start index: nothing to measure with
  if (!index) {                         // no end index: every end state, as edge_ends_near does
    const int n = ctx.bundle->dof();
    for (size_t e = 0; e < ctx.bundle->size(); ++e)
      nearest = std::min(nearest, squared_distance(q.data(), ctx.bundle->qf(e), n));
    return std::sqrt(nearest);
  }
  std::vector<std::pair<uint32_t, double>> found;
  for (double radius = std::max(ctx.theta, 0.05); found.empty() && radius < 64; radius *= 2)
    index->within(q.data(), radius, found);
  for (const auto& f : found) nearest = std::min(nearest, f.second);
  return std::sqrt(nearest);
}

// What puts q out of the bundle's reach, for a coverage failure: the joints outside the bundle's
// sampling region, and how far the nearest edge start (end, for `ends`) lies.
std::string coverage_hint(const PlanningContext& ctx, const JointVectorRef& q, bool ends) {
  const std::string outside = joints_outside_region(ctx, q);
  const double nearest = nearest_edge(ctx, q, ends);
  char text[120] = "";
  if (std::isfinite(nearest)) {
    std::snprintf(text, sizeof text, "; the nearest edge %s is %.3f rad away",
                  ends ? "end" : "start", nearest);
  }
  return (outside.empty() ? "inside the bundle's region" : outside) + text;
}

}  // namespace

ParameterSpec theta_parameter() {
  ParameterSpec p;
  p.name = "theta";
  p.lower = 0;
  p.lower_exclusive = true;
  p.description = "neighbourhood radius in joint space, rad";
  p.default_from = "the bundle's (its perturbation analysis's, else its design theta)";
  return p;
}

ParameterSpec direct_parameter() {
  return boolean_parameter(
      "direct", true,
      "first simulate the straight command from the start to a joint goal; when it arrives, it "
      "is the answer (found_by: direct) and no search runs");
}

double bundle_planner_setup(const PlanningContext& ctx, const ParameterValues& values,
                            const std::string& planner, bool perturbation) {
  if (!ctx.bundle || !ctx.index) fail("planner", planner + " needs an edge bundle");
  if (perturbation && !ctx.bundle->has_perturbation()) {
    fail(ctx.bundle->path(), "has no complete perturbation analysis, which " + planner +
                                 " needs (run lazyboe-perturb)");
  }
  const double theta = values.get_or("theta", ctx.theta);
  if (!(theta > 0)) fail("theta", "must be > 0");
  return theta;
}

bool edge_ends_near(const PlanningContext& ctx, const JointVectorRef& q, double radius,
                    std::vector<std::pair<uint32_t, double>>& scratch) {
  if (ctx.end_index) {
    ctx.end_index->within(q.data(), radius, scratch);
    return !scratch.empty();
  }
  // Without the index: every end state, by the index's own distance and boundary.
  const BundleView& bundle = *ctx.bundle;
  const int n = bundle.dof();
  scratch.clear();
  for (size_t e = 0; e < bundle.size(); ++e) {
    const double d2 = squared_distance(q.data(), bundle.qf(e), n);
    if (d2 < radius * radius) scratch.emplace_back(static_cast<uint32_t>(e), d2);
  }
  return !scratch.empty();
}

bool some_edge_ends_near(const PlanningContext& ctx, const JointVectorRef& q, double radius) {
  if (ctx.end_index) return ctx.end_index->any_within(q.data(), radius);
  std::vector<std::pair<uint32_t, double>> scratch;
  return edge_ends_near(ctx, q, radius, scratch);
}

void edges_ending_nearest(const PlanningContext& ctx, const JointVectorRef& q, size_t count,
                          double radius, std::vector<std::pair<uint32_t, double>>& scratch) {
  if (ctx.end_index) return ctx.end_index->nearest(q.data(), count, radius, scratch);
  edge_ends_near(ctx, q, radius, scratch);
  count = std::min(count, scratch.size());
  std::partial_sort(scratch.begin(), scratch.begin() + count, scratch.end(), nearer_edge);
  scratch.resize(count);
}

BundleSearch::BundleSearch(const BundleSolve& solve)
    : ctx_(solve.context),
      bundle_(*solve.context.bundle),
      s_(solve.context, solve.ws, solve.problem),
      theta_(solve.theta),
      direct_(solve.values.get("direct") != 0),
      ahead_(solve.context.sim, solve.pool) {}

JointVector BundleSearch::edge_end(uint32_t e) const { return row(bundle_.qf(e), bundle_.dof()); }
JointVector BundleSearch::edge_start(uint32_t e) const { return row(bundle_.q0(e), bundle_.dof()); }
double BundleSearch::heuristic_at_end(uint32_t e) {
  return s_.heuristic(row(bundle_.qf(e), bundle_.dof()));
}

PlanResult BundleSearch::run() {
  if (direct_ && s_.connect_directly()) return s_.take_result();
  BundleNode root;
  root.q = s_.problem().start;
  root.h = s_.heuristic(root.q);
  push(s_.add(root));
  if (!covered()) return s_.take_result();
  Neighbours neighbours;
  while (!s_.should_stop()) {
    const int v = pop();
    if (v < 0) break;
    if (skip(v)) continue;
    ctx_.index->within(s_.node(v).q.data(), radius(v), neighbours);
    if (neighbours.empty() && defer(v)) continue;
    expand(v, neighbours);
  }
  PlanResult& r = s_.result();
  if (!r.success && r.failure.empty()) {
    r.failure = open_.empty() ? "search exhausted: no more nodes to expand within the bundle "
                                "(try lazysp, whose growth leaves the bundle, or a larger theta)"
                              : s_.stop_failure();
  }
  return s_.take_result();
}

// Coverage: a start or goal the bundle cannot reach is a clear failure, not a timeout.
bool BundleSearch::covered() {
  if (!ctx_.index->any_within(s_.problem().start.data(), theta_)) {
    s_.result().failure = "no bundle edge starts within theta = " + std::to_string(theta_) +
                          " rad of the start: it is outside the bundle's coverage (" +
                          coverage_hint(ctx_, s_.problem().start, false) +
                          "); try lazysp, whose growth leaves the bundle; a larger theta; or a "
                          "bundle built with a --region that holds the start";
    return false;
  }
  const Goal& goal = s_.problem().goal;
  if (goal.kind != Goal::Kind::Joint) return true;
  const double reach = theta_ + goal.tolerance;
  if (some_edge_ends_near(ctx_, goal.q, reach)) return true;
  s_.result().failure = "no bundle edge ends within theta + tolerance = " + std::to_string(reach) +
                        " rad of the goal: it is outside the bundle's coverage (" +
                        coverage_hint(ctx_, goal.q, true) +
                        "); try lazysp, a larger theta or tolerance, or a bundle built with a "
                        "--region that holds the goal";
  return false;
}

// The next node to expand, or -1 when there is none (the open list ran dry and no hook
// refilled it).
int BundleSearch::pop() {
  if (open_.empty() && (!refill() || open_.empty())) return -1;
  const int v = open_.top().second;
  open_.pop();
  return v;
}

bool BundleSearch::skip(int v) {
  if (s_.node(v).expanded || dead(v)) return true;
  if (is_solution(v)) return true;  // already one
  return s_.prunable(s_.node(v).cost, s_.node(v).h);
}

void BundleSearch::expand(int v, Neighbours& neighbours) {
  s_.node(v).expanded = true;
  // Most promising edges first (heuristic at their stored end): the same edges are taken,
  // but a goal reached in this expansion is reached sooner.
  order_by_promise(v, neighbours);
  begin_expansion(v, neighbours);
  expanding_ = v;
  expansion_ = &neighbours;
  ahead_.begin(v, neighbours.size());
  for (size_t k = 0; k < neighbours.size(); ++k) {
    if (s_.should_stop() || dead(v)) break;
    if (!visit(v, k, neighbours[k].first)) break;
  }
}

void BundleSearch::order_by_promise(int v, Neighbours& edges) {
  for (auto& [e, key] : edges) key = promise(v, e);
  std::stable_sort(edges.begin(), edges.end(),
                   [](const auto& x, const auto& y) { return x.second < y.second; });
}

PathStep bundle_edge_step(const BundleView& bundle, uint32_t e) {
  const CommandProfile c = bundle.command(e);
  return {e, std::vector<double>(c.knots, c.knots + c.n_knots * c.dof), c.duration};
}

void BundleSearch::found(int node) {
  s_.solution(node, [this](int u) {
    return s_.path_to(u, [this](const BundleNode& n) {
      return bundle_edge_step(bundle_, static_cast<uint32_t>(n.bundle_edge));
    });
  });
}

bool BundleSearch::needs_rollout(int v, size_t k) { return !simulated(v, expansion_edge(k)); }

RolloutResult BundleSearch::rollout_from(int v, size_t k) {
  const uint32_t e = (*expansion_)[k].first;
  if (!ahead_.enabled() || v != expanding_)
    return s_.simulate_from(s_.node(v).q, bundle_.command(e));
  // v became real at neighbour k (or was real): from here on, plan which neighbours need a
  // rollout from it.
  if (!ahead_.planned()) ahead_.plan(k, [&](size_t j) { return needs_rollout(v, j); });
  const RolloutResult& r = ahead_.take(
      k, s_.node(v).q.data(), [&](size_t j) { return bundle_.command((*expansion_)[j].first); });
  s_.count(r);
  return r;
}

void BundleSearch::simulate_edge(int v, uint32_t e, size_t k) {
  // The same edge from the same real node always gives the same rollout: never twice.
  if (!simulated_.insert(key(v, e)).second) return;
  const RolloutResult r = rollout_from(v, k);
  if (!r.valid()) return;
  BundleNode c;
  c.reached(r, s_.node(v).cost);
  c.parent = v;
  c.bundle_edge = e;
  c.h = s_.heuristic(c.q);
  const int id = s_.add(c);
  if (s_.in_goal(c.h)) {
    found(id);
  } else {
    push(id);
  }
}

}  // namespace lazyboe
