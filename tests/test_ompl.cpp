// OMPL's control planners (ompl-rrt, ompl-sst, ompl-kpiece) on our problem: each solves an easy
// joint goal in the empty environment, its path passes realize_path (re-simulated, re-validated,
// ends in the goal) at the reported cost, and its counters are filled; RRT and KPIECE1 are
// repeatable for a seed (per query, also from two threads at once); the registry and the query
// reader route the names; a build without OMPL refuses them with a clear error.
// Budgets are small: the whole binary takes a few seconds.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/ompl/ompl_planners.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/registry.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

JointVector joints(std::initializer_list<double> v) {
  JointVector q(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) q[i++] = x;
  return q;
}

struct Query {
  std::string planner;
  PlanningProblem problem;
};

// Wall-clock budgets are scaled by time_scale() (test_util.h): the sanitizers slow the planners.
// Start at the centre of a small box, goal 0.39 rad away, tolerance 0.3.
Query easy_problem(const std::string& planner, double budget, uint64_t seed = 1) {
  PlanningProblem p;
  p.start = joints({0.0, 0.25, 0.0, -2.0, 0.0, 1.9, 0.8});
  p.goal.kind = Goal::Kind::Joint;
  p.goal.q = p.start + joints({0.2, -0.15, 0.15, 0.15, -0.15, 0.1, 0.1});
  p.goal.tolerance = 0.3;
  p.termination.budget = budget * time_scale();
  p.seed = seed;
  return {planner, p};
}

const Scene& scene() {
  static const Scene s("empty");
  return s;
}

// The sampling box of the problems above.
PlanningContext context() {
  PlanningContext ctx{scene().sim};
  ctx.sample_lower = joints({-0.3, 0.0, -0.3, -2.3, -0.3, 1.6, 0.5});
  ctx.sample_upper = joints({0.3, 0.5, 0.3, -1.7, 0.3, 2.2, 1.1});
  return ctx;
}

PlanResult run(const Query& q) {
  SimulatorWorkspace ws(scene().sim);
  return plan(context(), ws, q.planner, {}, q.problem);
}

void expect_solved(const std::string& planner, double budget) {
  if (!ompl_available()) GTEST_SKIP() << "built without OMPL";
  const Query q = easy_problem(planner, budget);
  const PlanningProblem& p = q.problem;
  const PlanResult r = run(q);
  ASSERT_TRUE(r.success) << planner << ": " << r.failure;
  EXPECT_GE(r.n_solutions, 1);
  EXPECT_TRUE(std::isfinite(r.time_to_first_solution));
  EXPECT_GE(r.time_to_first_solution, 0);
  EXPECT_LE(r.time_to_first_solution, (budget + 0.5) * time_scale());
  ASSERT_FALSE(r.best_path.empty());
  for (const PathStep& s : r.best_path) {
    EXPECT_EQ(s.bundle_edge, -1);
    EXPECT_GT(s.command_duration, 0);
    EXPECT_EQ(s.knots.size() % 7, 0u);
    EXPECT_GE(s.knots.size() / 7, 3u);
  }
  EXPECT_GT(r.counters.simulations, 0u);
  EXPECT_GT(r.counters.collision_checks, 0u);
  EXPECT_GT(r.counters.nodes, 1u);
  EXPECT_EQ(r.counters.lazy_edges, 0u);
  SimulatorWorkspace ws(scene().sim);
  Trajectory traj;
  ASSERT_NO_THROW(traj = realize_path(scene().sim, ws, p.start, r.best_path, p.goal, 20));
  EXPECT_NEAR(traj.cost, r.best_cost, 1e-9);
  EXPECT_LE((traj.q.back() - p.goal.q).norm(), p.goal.tolerance);
}

TEST(Ompl, Names) {
  for (const char* name : {"ompl-rrt", "ompl-sst", "ompl-kpiece"}) {
    ASSERT_NE(find_planner(name), nullptr) << name;
    EXPECT_TRUE(find_planner(name)->needs.ompl) << name;
    EXPECT_EQ(find_planner(name)->available(), ompl_available()) << name;
  }
  EXPECT_FALSE(find_planner("rrt")->needs.ompl);
  EXPECT_EQ(find_planner("ompl-prm"), nullptr);
  EXPECT_THROW(run(easy_problem("ompl-prm", 1)), Error);
}

TEST(Ompl, RrtSolvesEasyProblem) { expect_solved("ompl-rrt", 3); }
TEST(Ompl, SstSolvesEasyProblem) { expect_solved("ompl-sst", 1.5); }
TEST(Ompl, KpieceSolvesEasyProblem) { expect_solved("ompl-kpiece", 3); }

TEST(Ompl, SstStopsAtFirstWhenAsked) {
  if (!ompl_available()) GTEST_SKIP() << "built without OMPL";
  Query q = easy_problem("ompl-sst", 5);
  q.problem.termination.stop_at_first = true;
  const auto t0 = std::chrono::steady_clock::now();
  const PlanResult r = run(q);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.n_solutions, 1);
  EXPECT_LT(took, 4.5 * time_scale());
}

// RRT and KPIECE1 stop at their first solution, so with every draw seeded per query they give
// the same path for the same seed, also when two queries run at once.
TEST(Ompl, RepeatablePerQueryAndThreadSafe) {
  if (!ompl_available()) GTEST_SKIP() << "built without OMPL";
  for (const std::string planner : {"ompl-rrt", "ompl-kpiece"}) {
    const PlanResult a = run(easy_problem(planner, 5, 7));
    ASSERT_TRUE(a.success) << planner << ": " << a.failure;
    PlanResult b, c;
    std::thread tb([&] { b = run(easy_problem(planner, 5, 7)); });
    std::thread tc([&] { c = run(easy_problem(planner, 5, 7)); });
    tb.join();
    tc.join();
    for (const PlanResult* r : {&b, &c}) {
      ASSERT_TRUE(r->success) << planner << ": " << r->failure;
      ASSERT_EQ(r->best_path.size(), a.best_path.size()) << planner;
      for (size_t k = 0; k < a.best_path.size(); ++k) {
        EXPECT_EQ(r->best_path[k].knots, a.best_path[k].knots) << planner << " step " << k;
        EXPECT_EQ(r->best_path[k].command_duration, a.best_path[k].command_duration);
      }
      EXPECT_EQ(r->best_cost, a.best_cost);
      EXPECT_EQ(r->counters.simulations, a.counters.simulations);
      EXPECT_EQ(r->counters.nodes, a.counters.nodes);
    }
  }
}

TEST(Ompl, WithoutOmplRefusesClearly) {
  if (ompl_available()) GTEST_SKIP() << "built with OMPL";
  try {
    run(easy_problem("ompl-rrt", 1));
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("without OMPL"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("libompl-dev"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lazyboe::test
