// Planning through the library only: the planners (LazyBoE, BoE, RRT, SST, lazysp) with plan() and
// realize_path on one small dense bundle built and perturbed in memory (no tool runs).
// Covered: every planner solves an easy problem; every returned trajectory passes the
// independent re-validation of planning_fixture (and that re-validation catches broken ones);
// the output is made of simulated edges only, LazyBoE does take edges lazily while the others
// never do; a RolloutPool changes nothing but who simulates; LazyBoE refuses a bundle without
// perturbation analysis; a start or goal outside the bundle's coverage fails at once with a
// reason; a lazy chain without progress ends. lazysp: fully re-validated paths of simulated
// edges only, the same result for a seed with or without a pool, a goal beyond the bundle's
// coverage solved by its growth, a candidate edge that collides repaired around.
// test_query_cli runs the same through lazyboe-query.
//
// Run time matters: the bundle (2000 edges, p = 4) is built once per process, budgets are
// 0.5-3 s.
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/planning/planners/bundle_search.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/planning/rollout_scheduler.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/sim/rollout_pool.h"
#include "lazyboe/sim/simulator.h"
#include "planning_fixture.h"

namespace lazyboe::test {
namespace {

using Clock = std::chrono::steady_clock;

// ------------------------------------------------------------------------------------------
// The bundle: built once per process in memory, as the tools build it
// ------------------------------------------------------------------------------------------

struct Fixture : PlanningFixture {
  Fixture() : Fixture(build_small_bundles()) {}
  explicit Fixture(const SmallBundles& built)
      : PlanningFixture(built.perturbed,
                        BundleView::from_memory(built.perturbed, "the small bundle (in memory)")),
        unperturbed(built.unperturbed) {}
  std::shared_ptr<const Bundle> unperturbed;  // before the perturbation analysis
};

const Fixture& fixture() { return shared_fixture<Fixture>(); }

// ------------------------------------------------------------------------------------------
// Calling the planners (every test goes through these or calls plan() itself)
// ------------------------------------------------------------------------------------------

struct LibraryRun {
  std::string planner;
  PlanningProblem problem;
  PlanResult result;
  Trajectory trajectory;
  bool realized = false;
  std::string error;  // plan or realize_path threw
};

PlanningProblem library_problem(const JointVectorRef& start, const JointVectorRef& goal,
                                double budget) {
  PlanningProblem p;
  p.start = start;
  p.goal.kind = Goal::Kind::Joint;
  p.goal.q = goal;
  p.goal.tolerance = kTolerance;
  p.termination.budget = budget * time_scale();  // the sanitizers slow the planners
  p.seed = 1;
  return p;
}

constexpr int kSampleEvery = 10;  // 0.01 s at 1 kHz, the tool's default

// The easy problem a -> b with every planner, through the library, in parallel threads (one
// workspace each; the simulator, bundle and index are shared read-only, as in the tool).
const std::vector<LibraryRun>& library_runs() {
  static const std::vector<LibraryRun> runs = [] {
    const Fixture& f = fixture();
    const PlanningContext context = bundle_context(f.sim, f.view, f.index);
    std::vector<LibraryRun> out(kPlanners.size());
    std::vector<std::thread> threads;
    for (size_t i = 0; i < kPlanners.size(); ++i) {
      threads.emplace_back([&, i] {
        LibraryRun& r = out[i];
        r.planner = kPlanners[i];
        r.problem = library_problem(f.a, f.b, easy_budget(r.planner));
        SimulatorWorkspace ws(f.sim);
        try {
          r.result = plan(context, ws, r.planner, searching(r.planner), r.problem);
          if (r.result.success) {
            r.trajectory = realize_path(f.sim, ws, r.problem.start, r.result.best_path,
                                        r.problem.goal, kSampleEvery);
            r.realized = true;
          }
        } catch (const std::exception& e) {
          r.error = e.what();
        }
      });
    }
    for (std::thread& t : threads) t.join();
    return out;
  }();
  return runs;
}

// ------------------------------------------------------------------------------------------
// Every planner finds a path on an easy problem
// ------------------------------------------------------------------------------------------

TEST(Planners, EveryPlannerSolvesAnEasyProblem) {
  const Fixture& f = fixture();
  ASSERT_GE((f.a - f.b).norm(), 0.35);
  ASSERT_LE((f.a - f.b).norm(), 0.45);
  for (const LibraryRun& r : library_runs()) {
    SCOPED_TRACE("library, " + r.planner);
    EXPECT_TRUE(r.error.empty()) << r.error;
    EXPECT_TRUE(r.result.success) << "failure: " << r.result.failure;
    EXPECT_TRUE(r.realized);
    EXPECT_GE(r.result.n_solutions, 1);
    EXPECT_FALSE(r.result.best_path.empty());
    EXPECT_GE(r.result.time_to_first_solution, 0.0);
    EXPECT_LE(r.result.time_to_first_solution, r.problem.termination.budget + 0.5 * time_scale());
    EXPECT_TRUE(r.result.failure.empty()) << r.result.failure;
  }
}

// ------------------------------------------------------------------------------------------
// Every returned trajectory passes an independent re-validation
// ------------------------------------------------------------------------------------------

TEST(Planners, EveryReturnedTrajectoryPassesIndependentRevalidation) {
  const Fixture& f = fixture();
  int checked = 0;
  for (const LibraryRun& r : library_runs()) {
    if (!r.realized) continue;
    SCOPED_TRACE("library, " + r.planner);
    EXPECT_EQ(validate(f, r.trajectory, f.a, f.b, kTolerance, r.planner), "");
    // One edges entry per path step, naming the step's bundle edge.
    ASSERT_EQ(r.trajectory.edges.size(), r.result.best_path.size());
    for (size_t k = 0; k < r.result.best_path.size(); ++k) {
      EXPECT_EQ(r.trajectory.edges[k], r.result.best_path[k].bundle_edge) << "step " << k;
    }
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(kPlanners.size()))
      << "every query should have returned a trajectory";
}

// Every planner in the registry (a new one is tested without another line here) solves the
// easy problem a -> b through make_planner, setup and solve, and its path passes realize_path
// and the independent re-validation. Planners not built in (OMPL's, without OMPL) are skipped.
class EveryRegisteredPlanner : public ::testing::TestWithParam<std::string> {};

std::vector<std::string> registered_names() {
  std::vector<std::string> names;
  for (const PlannerInfo& info : planner_registry()) names.push_back(info.name);
  return names;
}

TEST_P(EveryRegisteredPlanner, SolvesAnEasyProblemWithAValidPath) {
  const std::string name = GetParam();
  const PlannerInfo& info = planner_info(name);
  std::string why;
  if (!info.available(&why)) GTEST_SKIP() << name << ": " << why;
  const Fixture& f = fixture();
  const PlanningContext context = bundle_context(f.sim, f.view, f.index);
  PlanningProblem problem = library_problem(f.a, f.b, 5);
  problem.termination.stop_at_first = true;
  const std::unique_ptr<Planner> planner = make_planner(name, searching(name));
  planner->setup(context);
  SimulatorWorkspace ws(f.sim);
  const PlanResult r = planner->solve(problem, ws);
  ASSERT_TRUE(r.success) << name << ": " << r.failure;
  EXPECT_GE(r.n_solutions, 1);
  EXPECT_GT(r.counters.simulations, 0u);
  const Trajectory t =
      realize_path(f.sim, ws, problem.start, r.best_path, problem.goal, kSampleEvery);
  EXPECT_NEAR(t.cost, r.best_cost, 1e-9 * (1 + r.best_cost));
  EXPECT_EQ(validate(f, t, f.a, f.b, kTolerance, name), "");
  // Steps name bundle edges only for planners with a bundle (whose own commands, as lazysp's
  // growth steps, name none), and only edges of the bundle.
  for (const PathStep& s : r.best_path) {
    if (!info.needs.bundle) {
      EXPECT_EQ(s.bundle_edge, -1);
    }
    EXPECT_LT(s.bundle_edge, static_cast<int64_t>(f.view.size()));
  }
  planner->clear();
  // Solving again after clear() gives the same answer (a planner keeps nothing between solves).
  const PlanResult again = planner->solve(problem, ws);
  if (!info.needs.ompl) {  // OMPL's process-wide generator has moved on
    EXPECT_EQ(again.best_cost, r.best_cost);
    EXPECT_EQ(again.counters.simulations, r.counters.simulations);
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryRegisteredPlanner, ::testing::ValuesIn(registered_names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string id = p.param;
                           for (char& c : id)
                             c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return id;
                         });

TEST(Planners, TheRevalidationCatchesBrokenTrajectories) {
  const Fixture& f = fixture();
  const LibraryRun* run = nullptr;
  for (const LibraryRun& r : library_runs()) {
    if (r.realized && r.planner == "boe") run = &r;
  }
  ASSERT_NE(run, nullptr) << "boe found no path";
  const Trajectory& good = run->trajectory;
  ASSERT_GE(good.t.size(), 4u);
  const size_t mid = good.t.size() / 2;
  auto problems = [&](const Trajectory& t) {
    return validate(f, t, t.q[0], f.b, kTolerance, "boe");
  };
  SimulatorWorkspace ws(f.sim);
  JointVector collide = good.q[mid];
  while (check_state(f.sim, ws, collide) == RolloutStatus::Valid && collide[1] < f.robot.q_max[1])
    collide[1] += 0.05;
  ASSERT_NE(check_state(f.sim, ws, collide), RolloutStatus::Valid);

  Trajectory t = good;
  t.t[mid] = t.t[mid - 1];
  EXPECT_TRUE(contains(problems(t), "strictly increasing")) << problems(t);
  t = good;
  t.dq[0][3] = 0.01;
  EXPECT_TRUE(contains(problems(t), "first dq")) << problems(t);
  t = good;
  t.q[mid][2] += 0.2;
  EXPECT_TRUE(contains(problems(t), "discontinuity")) << problems(t);
  t = good;
  t.q[mid] = collide;
  EXPECT_TRUE(contains(problems(t), "check_state")) << problems(t);
  t = good;
  t.dq[mid][0] = f.robot.dq_max[0] * 1.01;
  EXPECT_TRUE(contains(problems(t), "velocity limit")) << problems(t);
  t = good;
  t.q.back() = f.a;
  EXPECT_TRUE(contains(problems(t), "from the goal")) << problems(t);
  t = good;
  t.edges.back() = static_cast<int64_t>(f.view.size());
  EXPECT_TRUE(contains(problems(t), "not a bundle edge")) << problems(t);
  EXPECT_TRUE(contains(validate(f, good, f.b, f.b, kTolerance, "boe"), "query start"));
  // An end state that is not the simulated one (a stored, lazy end would differ like this).
  t = good;
  t.q.back()[6] += 1e-6;
  EXPECT_TRUE(contains(resimulate(f, f.a, bundle_commands(f, good.edges), t), "differs"));
  t = good;
  t.t.back() += 0.01;
  EXPECT_TRUE(contains(resimulate(f, f.a, bundle_commands(f, good.edges), t), "duration"));
  EXPECT_EQ(resimulate(f, f.a, bundle_commands(f, good.edges), good), "");
}

// ------------------------------------------------------------------------------------------
// No lazy edge in any output
// ------------------------------------------------------------------------------------------

TEST(Planners, OutputsAreMadeOfSimulatedEdgesOnly) {
  const Fixture& f = fixture();
  bool lazy_somewhere = false;
  for (const LibraryRun& r : library_runs()) {
    if (!r.realized) continue;
    SCOPED_TRACE("library, " + r.planner);
    // The path's commands, simulated one after the other from the start, end exactly where
    // the trajectory ends; for the bundle planners the edge ids name the same commands.
    std::vector<CommandProfile> commands;
    for (const PathStep& s : r.result.best_path) {
      commands.push_back(s.profile(f.robot.dof));
    }
    EXPECT_EQ(resimulate(f, f.a, commands, r.trajectory), "");
    if (is_bundle_planner(r.planner)) {
      EXPECT_EQ(resimulate(f, f.a, bundle_commands(f, r.trajectory.edges), r.trajectory), "");
    }
    // A lazy node's cost is an estimate from stored states; a path of simulated edges costs
    // exactly what re-simulating it measures.
    EXPECT_NEAR(r.result.best_cost, r.trajectory.cost, 1e-9);
    // The lazy searches count the edges they take without simulating (lazysp: its predicted
    // states); the others take none.
    if (r.planner == "lazyboe") lazy_somewhere |= r.result.counters.lazy_edges > 0;
    if (r.planner != "lazyboe" && r.planner != "lazysp") {
      EXPECT_EQ(r.result.counters.lazy_edges, 0u);
    }
  }
  EXPECT_TRUE(lazy_somewhere)
      << "lazyboe never took an edge lazily (counters.lazy_edges = 0 everywhere)";
}

// ------------------------------------------------------------------------------------------
// Parallel rollouts
// ------------------------------------------------------------------------------------------

TEST(Planners, ARolloutPoolChangesNothingButWhoSimulates) {
  const Fixture& f = fixture();
  const PlanningContext context = bundle_context(f.sim, f.view, f.index);
  for (const std::string planner : {"lazyboe", "boe"}) {
    SCOPED_TRACE(planner);
    PlanningProblem p = library_problem(f.a, f.c, 10);
    p.termination.stop_at_first = true;
    p.seed = 7;
    SimulatorWorkspace ws(f.sim);
    const PlanResult alone = plan(context, ws, planner, searching(planner), p);
    RolloutPool pool(f.sim, 3);
    const PlanResult pooled = plan(context, ws, planner, searching(planner), p, &pool);
    ASSERT_TRUE(alone.success) << alone.failure;
    EXPECT_GT(pool.rollouts(), 0u) << "the search did not use the pool";
    // Unused rollouts are only those of the last wave, when the search stops.
    EXPECT_LE(pool.rollouts(), pooled.counters.simulations + kWavePerThread * pool.threads() - 1);
    EXPECT_EQ(pooled.success, alone.success);
    EXPECT_EQ(pooled.n_solutions, alone.n_solutions);
    EXPECT_EQ(pooled.best_cost, alone.best_cost);
    EXPECT_EQ(pooled.counters.nodes, alone.counters.nodes);
    EXPECT_EQ(pooled.counters.simulations, alone.counters.simulations);
    EXPECT_EQ(pooled.counters.lazy_edges, alone.counters.lazy_edges);
    EXPECT_EQ(pooled.counters.collision_checks, alone.counters.collision_checks);
    ASSERT_EQ(pooled.best_path.size(), alone.best_path.size());
    for (size_t s = 0; s < alone.best_path.size(); ++s)
      EXPECT_EQ(pooled.best_path[s].bundle_edge, alone.best_path[s].bundle_edge) << "step " << s;
  }
}

// ------------------------------------------------------------------------------------------
// A bundle without perturbation analysis
// ------------------------------------------------------------------------------------------

// LazyBoE needs the analysis; boe on the same bundle works (test_query_cli).
// lazy_model transfer: lazy children at the node moved by the edge's displacement, with
// P_lazy_prop under transfer. It solves the easy problems with re-validated paths, takes edges
// lazily, is repeatable and independent of a pool, and differs from the stored model.
TEST(Planners, LazyBoEWithTransferSolvesWithValidPaths) {
  const Fixture& f = fixture();
  ASSERT_TRUE(f.view.has_transfer());
  const PlanningContext context = bundle_context(f.sim, f.view, f.index);
  const ParameterValues transfer = {{"lazy_model", 1}};
  uint64_t simulations[2] = {0, 0};
  for (const JointVector* goal : {&f.b, &f.c}) {
    PlanningProblem p = library_problem(f.a, *goal, 5);
    p.termination.stop_at_first = true;
    SimulatorWorkspace ws(f.sim);
    const PlanResult r = plan(context, ws, "lazyboe", searching("lazyboe", transfer), p);
    ASSERT_TRUE(r.success) << r.failure;
    EXPECT_GT(r.counters.lazy_edges, 0u);
    const Trajectory t = realize_path(f.sim, ws, p.start, r.best_path, p.goal, kSampleEvery);
    EXPECT_EQ(validate(f, t, f.a, *goal, kTolerance, "lazyboe"), "");
    RolloutPool pool(f.sim, 3);
    const PlanResult again = plan(context, ws, "lazyboe", searching("lazyboe", transfer), p, &pool);
    EXPECT_EQ(again.best_cost, r.best_cost);
    EXPECT_EQ(again.counters.simulations, r.counters.simulations);
    EXPECT_EQ(again.counters.lazy_edges, r.counters.lazy_edges);
    const PlanResult stored = plan(context, ws, "lazyboe", searching("lazyboe"), p);
    ASSERT_TRUE(stored.success) << stored.failure;
    simulations[0] += stored.counters.simulations;
    simulations[1] += r.counters.simulations;
  }
  EXPECT_NE(simulations[0], simulations[1]) << "the two lazy models searched alike";
}

TEST(Planners, LazyBoEWithTransferRefusesABundleWithoutTransferStatistics) {
  const Fixture& f = fixture();
  Bundle old = f.data;
  Perturbation& p = old.perturbation;
  p.has_transfer = false;
  p.transfer_lazy.clear();
  p.transfer_max_error.clear();
  p.p_lazy_prop_transfer.clear();
  const BundleView view = BundleView::from_memory(std::make_shared<const Bundle>(old), "old");
  ASSERT_TRUE(view.has_perturbation());
  ASSERT_FALSE(view.has_transfer());
  const EdgeIndex index(view);
  const PlanningContext context = bundle_context(f.sim, view, index);
  SimulatorWorkspace ws(f.sim);
  try {
    plan(context, ws, "lazyboe", searching("lazyboe", {{"lazy_model", 1}}),
         library_problem(f.a, f.b, 1));
    ADD_FAILURE() << "lazy_model transfer ran without transfer statistics";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "transfer statistics")) << e.what();
  }
  EXPECT_TRUE(
      plan(context, ws, "lazyboe", searching("lazyboe"), library_problem(f.a, f.b, 1)).success);
}

TEST(Planners, LazyBoEOnABundleWithoutPerturbationIsRefused) {
  const Fixture& f = fixture();
  const BundleView plain = BundleView::from_memory(f.unperturbed, "the unperturbed bundle");
  EXPECT_FALSE(plain.has_perturbation());
  // And through the library.
  const EdgeIndex plain_index(plain);
  const PlanningContext context = bundle_context(f.sim, plain, plain_index);
  SimulatorWorkspace ws(f.sim);
  try {
    plan(context, ws, "lazyboe", searching("lazyboe"), library_problem(f.a, f.b, 1));
    ADD_FAILURE() << "lazyboe planned on a bundle without perturbation analysis";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "lazyboe-perturb")) << e.what();
  }
}

// ------------------------------------------------------------------------------------------
// Start or goal outside the bundle's coverage
// ------------------------------------------------------------------------------------------

TEST(Planners, StartOrGoalOutsideTheCoverageFailsWithAReason) {
  const Fixture& f = fixture();
  const JointVector far_start = far_start_state(f), far_goal = far_goal_state(f);
  ASSERT_EQ(far_start.size(), 7) << "no collision-free state far from the bundle's starts";
  ASSERT_EQ(far_goal.size(), 7) << "no collision-free state far from the bundle's ends";

  // Library: a clear failure at once, not a timeout.
  const PlanningContext context = bundle_context(f.sim, f.view, f.index);
  SimulatorWorkspace ws(f.sim);
  for (const std::string planner : {"lazyboe", "boe"}) {
    for (bool start_is_far : {true, false}) {
      SCOPED_TRACE(planner + std::string(start_is_far ? ", far start" : ", far goal"));
      const auto t0 = Clock::now();
      const PlanResult r =
          plan(context, ws, planner, searching(planner),
               library_problem(start_is_far ? far_start : f.a, start_is_far ? f.b : far_goal, 5));
      const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      EXPECT_FALSE(r.success);
      EXPECT_LT(seconds, 1.0 * time_scale()) << "ran into its budget instead of failing at once";
      EXPECT_TRUE(contains(r.failure, "theta")) << "failure: " << r.failure;
      EXPECT_TRUE(contains(r.failure, "bundle")) << "failure: " << r.failure;
      EXPECT_TRUE(contains(r.failure, start_is_far ? "start" : "goal")) << "failure: " << r.failure;
      EXPECT_FALSE(contains(r.failure, "time budget")) << "failure: " << r.failure;
      // How far it is from the bundle: the nearest edge start (end, for the goal).
      EXPECT_TRUE(contains(
          r.failure, start_is_far ? "; the nearest edge start is " : "; the nearest edge end is "))
          << "failure: " << r.failure;
    }
  }
  // A start outside the sampling region (joint 2 below it, like the Panda's ready pose): the
  // failure names the joint, its value and the region's bounds.
  JointVector low = f.a;
  low[1] = context.sample_lower[1] - 0.6;
  ASSERT_EQ(check_state(f.sim, ws, low), RolloutStatus::Valid) << "the test's start collides";
  const PlanResult r =
      plan(context, ws, "lazyboe", searching("lazyboe"), library_problem(low, f.b, 5));
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(contains(r.failure, "joint 2 (panda_joint2) is ")) << r.failure;
  EXPECT_TRUE(contains(r.failure, "the bundle's region [")) << r.failure;
  EXPECT_TRUE(contains(r.failure, "; the nearest edge start is ")) << r.failure;
}

TEST(Planners, ALazyChainWithoutProgressEnds) {
  const Fixture& f = fixture();
  const int n = f.data.dof();
  const size_t k = 0;
  Bundle one;
  one.header = f.data.header;
  auto rows = [&](const std::vector<double>& v, size_t from, size_t to) {
    return std::vector<double>(v.begin() + from * n, v.begin() + to * n);
  };
  one.q0 = rows(f.data.q0, k, k + 1);
  one.qf = one.q0;  // the stored end is the start
  one.duration = {f.data.duration[k]};
  one.command_duration = {f.data.command_duration[k]};
  one.attempt = {f.data.attempt[k]};
  one.knot_offset = {0, f.data.knot_offset[k + 1] - f.data.knot_offset[k]};
  one.knots = rows(f.data.knots, f.data.knot_offset[k], f.data.knot_offset[k + 1]);
  one.sample_offset = {0, 0};
  one.header.valid = 1;
  one.header.target_edges = 1;
  Perturbation& p = one.perturbation;
  p = f.data.perturbation;
  p.done = {p.perturbations};
  p.valid = {p.perturbations};
  p.lazy = {p.perturbations};
  p.collision = {0};
  p.max_error = {0.0};
  p.p_lazy_prop = {1.0};  // always taken lazily
  p.p_collision = {0.0};
  p.transfer_lazy = {p.perturbations};
  p.transfer_max_error = {0.0};
  p.p_lazy_prop_transfer = {1.0};
  const BundleView view =
      BundleView::from_memory(std::make_shared<const Bundle>(one), "one self-loop edge");
  const EdgeIndex index(view);
  const PlanningContext context = bundle_context(f.sim, view, index);

  const JointVector start = f.edge_start(k);
  JointVector goal = start;
  goal[n - 1] += 0.5;  // beyond the tolerance, within theta + tolerance of the stored end
  PlanningProblem problem = library_problem(start, goal, 0.5);
  SimulatorWorkspace ws(f.sim);
  const PlanResult r = plan(context, ws, "lazyboe", searching("lazyboe"), problem);
  EXPECT_GT(r.counters.lazy_edges, 0u);
  EXPECT_LE(r.counters.lazy_edges, r.counters.simulations + 2)
      << "lazy edges " << r.counters.lazy_edges << ", simulations " << r.counters.simulations
      << ": a lazy chain went on without simulating";
}

// ------------------------------------------------------------------------------------------
// lazysp: lazy search over predicted states, forward validation, growth
// ------------------------------------------------------------------------------------------

// The context a planning session makes: with the k-d tree over edge end states too.
const EdgeIndex& end_index() {
  static const EdgeIndex ends(fixture().view, EdgePoint::End);
  return ends;
}

PlanningContext session_context(const Fixture& f, const Simulator& sim) {
  PlanningContext c = bundle_context(f.sim, f.view, f.index);
  PlanningContext out{sim, c.bundle, c.index};
  out.end_index = &end_index();
  out.theta = c.theta;
  out.mean_displacement = c.mean_displacement;
  out.sample_lower = c.sample_lower;
  out.sample_upper = c.sample_upper;
  out.command = c.command;
  return out;
}

// The end-state index finds exactly the edges a scan of every end state finds.
TEST(LazySp, TheEndStateIndexAgreesWithAScan) {
  const Fixture& f = fixture();
  EXPECT_EQ(end_index().point(), EdgePoint::End);
  EXPECT_EQ(f.index.point(), EdgePoint::Start);
  std::vector<std::pair<uint32_t, double>> found;
  for (const JointVector& q : {f.a, f.b, f.c}) {
    for (const double radius : {0.1, 0.3, 0.75}) {
      end_index().within(q.data(), radius, found);
      std::vector<uint32_t> ids, scanned;
      for (const auto& [e, d2] : found) ids.push_back(e);
      for (size_t e = 0; e < f.view.size(); ++e) {
        const JointVector end = Eigen::Map<const Eigen::VectorXd>(f.view.qf(e), f.robot.dof);
        if ((end - q).norm() < radius) scanned.push_back(static_cast<uint32_t>(e));
      }
      EXPECT_EQ(ids, scanned) << "radius " << radius;
    }
  }
}

// Without the end-state index (a context that has none), the coverage checks scan every end
// state and answer exactly as the index does: the same edges within, whether there is one, and
// the same nearest ones in the same order, also at a radius whose square is an edge end's
// squared distance (strictly within: that end is out).
TEST(LazySp, CoverageWithoutTheEndIndexAnswersAsWithIt) {
  const Fixture& f = fixture();
  const PlanningContext indexed = session_context(f, f.sim);
  PlanningContext scanning = session_context(f, f.sim);
  scanning.end_index = nullptr;
  std::vector<std::pair<uint32_t, double>> by_index, by_scan;
  std::vector<JointVector> queries = {f.a, f.b, f.c};
  for (const size_t e : {size_t{0}, f.view.size() / 2})
    queries.push_back(Eigen::Map<const Eigen::VectorXd>(f.view.qf(e), f.robot.dof));
  size_t nonempty = 0, exact_boundaries = 0;
  for (const JointVector& q : queries) {
    std::vector<double> radii = {1e-9, 0.1, 0.3, 0.75};
    edge_ends_near(indexed, q, 0.75, by_index);
    if (!by_index.empty()) {
      // A radius whose square is an edge end's squared distance exactly: that end is out.
      const auto [edge, d2] = by_index[by_index.size() / 2];
      double r = std::sqrt(d2);
      for (int k = 0; k < 8 && r * r != d2; ++k) r = std::nextafter(r, r * r < d2 ? 1e9 : 0.0);
      if (r * r == d2) {
        radii.push_back(r);
        edge_ends_near(scanning, q, r, by_scan);
        for (const auto& [e, d] : by_scan) EXPECT_NE(e, edge) << "the boundary is strict";
        ++exact_boundaries;
      }
    }
    for (const double radius : radii) {
      const bool found = edge_ends_near(indexed, q, radius, by_index);
      EXPECT_EQ(edge_ends_near(scanning, q, radius, by_scan), found);
      EXPECT_EQ(by_scan, by_index) << "radius " << radius;
      EXPECT_EQ(some_edge_ends_near(indexed, q, radius), found);
      EXPECT_EQ(some_edge_ends_near(scanning, q, radius), found);
      nonempty += found;
      for (const size_t count : {1, 8, 64}) {
        edges_ending_nearest(indexed, q, count, radius, by_index);
        edges_ending_nearest(scanning, q, count, radius, by_scan);
        EXPECT_EQ(by_scan, by_index) << "radius " << radius << " count " << count;
        EXPECT_LE(by_index.size(), count);
      }
    }
  }
  EXPECT_GT(nonempty, 5u) << "the queries found too few edge ends to compare";
  EXPECT_GT(exact_boundaries, 0u) << "no radius fell exactly on an edge end";
}

// A lazysp result passes realize_path on `sim`, the independent re-validation, and its
// commands re-simulated one after another from the start land exactly on the trajectory's
// end: no predicted state is in it. Returns the trajectory.
Trajectory expect_revalidated(const Fixture& f, const Simulator& sim, const PlanningProblem& p,
                              const PlanResult& r) {
  SimulatorWorkspace ws(sim);
  const Trajectory t = realize_path(sim, ws, p.start, r.best_path, p.goal, kSampleEvery);
  EXPECT_EQ(validate(f, t, p.start, p.goal.q, kTolerance, "lazysp"), "");
  std::vector<CommandProfile> commands;
  for (const PathStep& s : r.best_path) {
    commands.push_back(s.profile(f.robot.dof));
  }
  EXPECT_EQ(resimulate(f, p.start, commands, t), "");
  EXPECT_NEAR(r.best_cost, t.cost, 1e-9 * (1 + t.cost));
  EXPECT_EQ(t.edges.size(), r.best_path.size());
  return t;
}

// At its first solution (deterministic) and after improving it for the whole budget (anytime).
TEST(LazySp, ReturnsFullyRevalidatedPathsOfSimulatedEdges) {
  const Fixture& f = fixture();
  const PlanningContext context = session_context(f, f.sim);
  SimulatorWorkspace ws(f.sim);
  const std::vector<std::pair<JointVector, JointVector>> problems = {
      {f.a, f.b}, {f.a, f.c}, {f.c, f.a}};
  for (size_t k = 0; k < problems.size(); ++k) {
    for (const bool first : {true, false}) {
      SCOPED_TRACE("problem " + std::to_string(k) + (first ? ", first solution" : ", anytime"));
      PlanningProblem p = library_problem(problems[k].first, problems[k].second, first ? 10 : 0.3);
      p.termination.stop_at_first = first;
      const PlanResult r = plan(context, ws, "lazysp", searching("lazysp"), p);
      ASSERT_TRUE(r.success) << r.failure;
      EXPECT_GT(r.counters.lazy_edges, 0u);  // predicted states, never simulated
      EXPECT_GE(r.counters.simulations, r.best_path.size());
      const Trajectory t = expect_revalidated(f, f.sim, p, r);
      if (!first) continue;
      // The bundle covers these problems: the lazy search finds the path, of bundle edges.
      EXPECT_EQ(r.found_by, "bundle");
      EXPECT_EQ(r.n_solutions, 1);
      for (const PathStep& s : r.best_path) EXPECT_GE(s.bundle_edge, 0);
      EXPECT_EQ(resimulate(f, p.start, bundle_commands(f, t.edges), t), "");
      std::cout << "[ lazysp  ] problem " << k << ": " << r.best_path.size() << " edges, "
                << r.counters.simulations << " simulations to the first solution ("
                << r.time_to_first_solution * 1e3 << " ms)\n";
    }
  }
}

// The edge penalty charges each predicted edge (one simulation each): the lazy search then
// prefers candidates of fewer, longer edges. Without it, the first solutions of problems across
// the bundle's region (edge starts over 0.9 rad apart) have more edges in all.
TEST(LazySp, TheEdgePenaltyFavoursCandidatesOfFewerEdges) {
  const Fixture& f = fixture();
  const PlanningContext context = session_context(f, f.sim);
  EXPECT_EQ(context.mean_displacement, mean_edge_displacement(f.view));
  EXPECT_GT(context.mean_displacement, 0.05);
  SimulatorWorkspace ws(f.sim);
  size_t edges_without = 0, edges_with = 0, problems = 0;
  for (size_t e = 0; e < f.view.size() && problems < 6; e += 7) {
    const JointVector from = f.edge_start(e), to = f.edge_start(f.view.size() - 1 - e);
    if ((to - from).norm() < 0.9) continue;
    ++problems;
    PlanningProblem p = library_problem(from, to, 10);
    p.termination.stop_at_first = true;
    const PlanResult without =
        plan(context, ws, "lazysp", searching("lazysp", {{"edge_penalty", 0.0}}), p);
    const PlanResult with =
        plan(context, ws, "lazysp", searching("lazysp", {{"edge_penalty", 1.0}}), p);
    ASSERT_TRUE(without.success && with.success);
    edges_without += without.best_path.size();
    edges_with += with.best_path.size();
    expect_revalidated(f, f.sim, p, with);
  }
  ASSERT_EQ(problems, 6u);
  std::cout << "[ lazysp  ] first solutions of 6 problems: " << edges_without
            << " edges without the penalty, " << edges_with << " with 1 rad per edge\n";
  EXPECT_LT(edges_with, edges_without);
}

TEST(LazySp, IdenticalResultsForAFixedSeedWithOrWithoutAPool) {
  const Fixture& f = fixture();
  const PlanningContext context = session_context(f, f.sim);
  PlanningProblem p = library_problem(f.a, f.c, 10);
  p.termination.stop_at_first = true;
  p.seed = 3;
  SimulatorWorkspace ws(f.sim);
  const ParameterValues defaults = searching("lazysp", {{"connect_radius", 1.0}});
  const PlanResult first = plan(context, ws, "lazysp", defaults, p);
  const PlanResult again = plan(context, ws, "lazysp", defaults, p);
  RolloutPool pool(f.sim, 3);
  const PlanResult pooled = plan(context, ws, "lazysp", defaults, p, &pool);
  ASSERT_TRUE(first.success) << first.failure;
  for (const PlanResult* r : {&again, &pooled}) {
    EXPECT_EQ(r->success, first.success);
    EXPECT_EQ(r->best_cost, first.best_cost);
    EXPECT_EQ(r->n_solutions, first.n_solutions);
    EXPECT_EQ(r->found_by, first.found_by);
    EXPECT_EQ(r->counters.nodes, first.counters.nodes);
    EXPECT_EQ(r->counters.simulations, first.counters.simulations);
    EXPECT_EQ(r->counters.lazy_edges, first.counters.lazy_edges);
    EXPECT_EQ(r->counters.collision_checks, first.counters.collision_checks);
    ASSERT_EQ(r->best_path.size(), first.best_path.size());
    for (size_t s = 0; s < first.best_path.size(); ++s) {
      EXPECT_EQ(r->best_path[s].bundle_edge, first.best_path[s].bundle_edge) << "step " << s;
      EXPECT_EQ(r->best_path[s].knots, first.best_path[s].knots) << "step " << s;
    }
  }
}

// A joint goal farther than theta + tolerance from every edge end: BoE fails at once (with the
// end-state index as with the scan); lazysp reaches it through its growth.
TEST(LazySp, AGoalBeyondTheBundlesCoverageIsSolvedByTheGrowth) {
  const Fixture& f = fixture();
  const double theta = f.view.perturbation_theta();
  const JointVector goal =
      far_state(f, f.b, {1.1, -1.1, 1.2, -1.2, 1.3, -1.3, 1.5, -1.5}, theta + kTolerance, true);
  ASSERT_EQ(goal.size(), 7) << "no collision-free state just beyond the bundle's ends";
  ASSERT_GT(nearest_distance(f, goal, true), theta + kTolerance);
  const PlanningContext context = session_context(f, f.sim);
  const PlanningContext scanning = bundle_context(f.sim, f.view, f.index);  // no end index
  SimulatorWorkspace ws(f.sim);
  PlanningProblem p = library_problem(f.b, goal, 20);
  p.termination.stop_at_first = true;
  const PlanResult boe = plan(context, ws, "boe", searching("boe"), p);
  EXPECT_FALSE(boe.success);
  EXPECT_TRUE(contains(boe.failure, "goal")) << boe.failure;
  EXPECT_EQ(plan(scanning, ws, "boe", searching("boe"), p).failure, boe.failure);

  const PlanResult r = plan(context, ws, "lazysp", searching("lazysp"), p);
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.found_by, "growth");
  EXPECT_EQ(r.best_path.back().bundle_edge, -1);  // the last step is a growth command
  expect_revalidated(f, f.sim, p, r);
  std::cout << "[ lazysp  ] beyond coverage: " << r.best_path.size() << " steps, "
            << r.counters.simulations << " simulations, " << r.time_to_first_solution << " s\n";
}

// A joint goal whose tolerance (1 cm of joint motion) no bundle edge or random command lands in:
// lazysp's candidates end within candidate_radius of it, and the direct command from a real
// state within connect_radius, corrected, does (found_by "connection", its last step). Without
// the connection nothing reaches it.
TEST(LazySp, ANarrowJointGoalIsReachedByTheDirectCommandFromANearState) {
  const Fixture& f = fixture();
  const PlanningContext context = session_context(f, f.sim);
  SimulatorWorkspace ws(f.sim);
  PlanningProblem p = library_problem(f.a, f.c, 10);
  p.goal.tolerance = 0.01;
  p.termination.stop_at_first = true;
  const PlanResult r =
      plan(context, ws, "lazysp", searching("lazysp", {{"connect_radius", 1.0}}), p);
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.found_by, "connection");
  ASSERT_GE(r.best_path.size(), 2u);
  EXPECT_EQ(r.best_path.back().bundle_edge, -1);       // the connection
  for (size_t k = 0; k + 1 < r.best_path.size(); ++k)  // from a validated candidate's end
    EXPECT_GE(r.best_path[k].bundle_edge, 0) << "step " << k;
  const Trajectory t = expect_revalidated(f, f.sim, p, r);
  EXPECT_LE((t.q.back() - p.goal.q).norm(), p.goal.tolerance);
  std::cout << "[ lazysp  ] narrow goal: " << r.best_path.size() << " steps, "
            << r.counters.simulations << " simulations\n";

  // Candidates that must end in the goal's own tolerance: the lazy search looks far longer
  // (here it kept about 800 times the predicted states and had not solved it within 1 s).
  p.termination.budget = 1;
  const PlanResult aiming_at_tolerance =
      plan(context, ws, "lazysp",
           searching("lazysp", {{"connect_radius", 1.0}, {"candidate_radius", 0.0}}), p);
  EXPECT_GT(aiming_at_tolerance.counters.lazy_edges, 2 * r.counters.lazy_edges);
  std::cout << "[ lazysp  ] narrow goal: predicted states kept " << r.counters.lazy_edges
            << ", aiming at the tolerance " << aiming_at_tolerance.counters.lazy_edges << " ("
            << (aiming_at_tolerance.success ? "solved" : "not solved") << ")\n";

  const PlanResult without = plan(context, ws, "lazysp", searching("lazysp"), p);
  EXPECT_FALSE(without.success && without.best_path.back().bundle_edge >= 0 &&
               without.counters.simulations <= r.counters.simulations)
      << "the bundle alone reaches the narrow goal as cheaply: the test shows nothing";
}

// An obstacle the bundle never saw, on the way of lazysp's first path a -> c (a ball at the
// hand's place halfway along it): the scene with it.
struct BlockedScene {
  BlockedScene(const Fixture& f, const Environment& env)
      : collision(build_collision_model(f.robot, env)), sim(f.robot, collision, f.sim.options) {}
  BlockedScene(const BlockedScene&) = delete;  // sim refers to this object's collision model
  BlockedScene& operator=(const BlockedScene&) = delete;
  CollisionModel collision;
  Simulator sim;  // refers to `collision`
};

// A ball of `radius` where the hand is at q.
Obstacle ball_at(const Fixture& f, const JointVector& q, double radius) {
  RobotData data(f.robot);
  forward_kinematics(f.robot, data, q);
  Obstacle ball;
  ball.name = "unseen";
  ball.shape.type = ShapeType::Sphere;
  ball.shape.radius = radius;
  ball.pose.p = link_pose(f.robot, data, f.robot.tip_link()).p;
  return ball;
}

// The fixture's scene with a ball of `radius` where the hand is at q.
std::unique_ptr<BlockedScene> scene_with_ball(const Fixture& f, const JointVector& q,
                                              double radius) {
  Environment env = f.env;
  env.obstacles.push_back(ball_at(f, q, radius));
  return std::make_unique<BlockedScene>(f, env);
}

std::unique_ptr<BlockedScene> blocked_scene(const Fixture& f, const PlanningProblem& p,
                                            const PlanResult& clear) {
  SimulatorWorkspace ws(f.sim);
  const Trajectory t = realize_path(f.sim, ws, p.start, clear.best_path, p.goal, kSampleEvery);
  return scene_with_ball(f, t.q[t.q.size() / 2], 0.04);
}

// The problem a -> c, its first answer without the look (precheck 0) in the fixture's scene, and
// that scene with the ball on the answer's way.
struct BlockedProblem {
  PlanningProblem p;
  PlanResult clear;
  std::unique_ptr<BlockedScene> scene;
};

const ParameterValues& without_look() {
  static const ParameterValues values = searching("lazysp", {{"precheck", 0}});
  return values;
}

BlockedProblem blocked_problem(const Fixture& f) {
  BlockedProblem b{library_problem(f.a, f.c, 10), {}, nullptr};
  b.p.termination.stop_at_first = true;
  SimulatorWorkspace ws(f.sim);
  b.clear = plan(session_context(f, f.sim), ws, "lazysp", without_look(), b.p);
  if (b.clear.success) b.scene = blocked_scene(f, b.p, b.clear);
  return b;
}

// Without the look before simulating (precheck 0): the same first candidate (the lazy search
// simulates nothing) now collides when simulated, and lazysp plans around it instead of
// returning it.
TEST(LazySp, ACandidateEdgeThatCollidesIsRepairedAround) {
  const Fixture& f = fixture();
  const BlockedProblem b = blocked_problem(f);
  ASSERT_TRUE(b.clear.success) << b.clear.failure;
  const PlanningProblem& p = b.p;
  const PlanResult& clear = b.clear;
  const Simulator& blocked = b.scene->sim;
  SimulatorWorkspace bws(blocked);
  ASSERT_EQ(check_state(blocked, bws, p.start), RolloutStatus::Valid);
  ASSERT_EQ(check_state(blocked, bws, p.goal.q), RolloutStatus::Valid);
  EXPECT_THROW(realize_path(blocked, bws, p.start, clear.best_path, p.goal, 0), Error);

  const PlanResult r = plan(session_context(f, blocked), bws, "lazysp", without_look(), p);
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.found_by, "bundle");
  EXPECT_GT(r.counters.simulations, r.best_path.size()) << "no simulation failed";
  expect_revalidated(f, blocked, p, r);
  std::vector<int64_t> before, after;
  for (const PathStep& s : clear.best_path) before.push_back(s.bundle_edge);
  for (const PathStep& s : r.best_path) after.push_back(s.bundle_edge);
  EXPECT_NE(before, after);
  std::cout << "[ lazysp  ] repaired: " << r.best_path.size() << " edges, "
            << r.counters.simulations << " simulations (" << clear.counters.simulations
            << " without the obstacle)\n";
}

// With the look (the default), the candidate's edges, their stored samples shifted to the
// predicted starts, meet the ball before anything is simulated: the same problem is solved
// with fewer simulations than without the look, none of them wasted on that edge, and the
// answer is as valid. In the bundle's own scene the look changes nothing.
TEST(LazySp, TheLookBeforeSimulatingSeesTheObstacle) {
  const Fixture& f = fixture();
  const BlockedProblem b = blocked_problem(f);
  ASSERT_TRUE(b.clear.success) << b.clear.failure;
  const PlanningProblem& p = b.p;
  const PlanResult& clear = b.clear;
  SimulatorWorkspace ws(f.sim);
  const PlanResult looked_clear =
      plan(session_context(f, f.sim), ws, "lazysp", searching("lazysp"), p);
  ASSERT_TRUE(looked_clear.success) << looked_clear.failure;
  EXPECT_EQ(looked_clear.best_cost, clear.best_cost);
  EXPECT_EQ(looked_clear.counters.simulations, clear.counters.simulations);
  EXPECT_GT(looked_clear.counters.collision_checks, clear.counters.collision_checks);

  const BlockedScene& scene = *b.scene;
  SimulatorWorkspace bws(scene.sim);
  const PlanningContext context = session_context(f, scene.sim);
  const PlanResult without = plan(context, bws, "lazysp", without_look(), p);
  const PlanResult looked = plan(context, bws, "lazysp", searching("lazysp"), p);
  ASSERT_TRUE(without.success) << without.failure;
  ASSERT_TRUE(looked.success) << looked.failure;
  EXPECT_LT(looked.counters.simulations, without.counters.simulations);
  // Every simulation is a step of the answer: none was spent on an edge the ball blocks.
  EXPECT_EQ(looked.found_by, "bundle");
  EXPECT_EQ(looked.counters.simulations, looked.best_path.size());
  expect_revalidated(f, scene.sim, p, looked);
  std::cout << "[ lazysp  ] the look: " << looked.counters.simulations << " simulations against "
            << without.counters.simulations << " without it\n";
}

// A narrow joint goal (1 cm) behind a ball: the ball sits where the hand passes on the direct
// command into the goal that solves the problem in the fixture's scene, so the direct commands
// from that side collide. With approaches lazysp comes in along a bundle edge looked at backward
// from the goal (found_by "approach": the last steps are the straight command to the approach,
// a bundle edge, and at most one more direct command); without them it does not.
constexpr double kPocketAlong = 0.4;  // of the way: the goal and the start stay free of the ball
struct PocketProblem {
  PlanningProblem p;
  std::unique_ptr<BlockedScene> scene;
};

PocketProblem pocket_problem(const Fixture& f, double along) {
  PocketProblem b{library_problem(f.a, f.c, 10), nullptr};
  b.p.goal.tolerance = 0.01;
  b.p.termination.stop_at_first = true;
  SimulatorWorkspace ws(f.sim);
  const PlanResult open = plan(session_context(f, f.sim), ws, "lazysp",
                               searching("lazysp", {{"connect_radius", 1.0}}), b.p);
  if (!open.success || open.found_by != "connection") return b;
  const Trajectory t = realize_path(f.sim, ws, b.p.start, open.best_path, b.p.goal, kSampleEvery);
  // The hand on the last step (the direct command), `along` of the way from its start.
  const double t0 = t.t.back() - open.best_path.back().outcome->duration;
  size_t k = 0;
  while (k + 1 < t.t.size() && t.t[k] < t0 + along * (t.t.back() - t0)) ++k;
  b.scene = scene_with_ball(f, t.q[k], 0.03);
  return b;
}

TEST(LazySp, AGoalInAPocketIsApproachedAlongAnEdgeLookedAtBackward) {
  const Fixture& f = fixture();
  const PocketProblem b = pocket_problem(f, kPocketAlong);
  ASSERT_TRUE(b.scene) << "the open scene's answer is not a direct command into the goal";
  const Simulator& pocket = b.scene->sim;
  SimulatorWorkspace ws(pocket);
  ASSERT_EQ(check_state(pocket, ws, b.p.start), RolloutStatus::Valid);
  ASSERT_EQ(check_state(pocket, ws, b.p.goal.q), RolloutStatus::Valid);
  const PlanningContext context = session_context(f, pocket);
  const PlanResult r =
      plan(context, ws, "lazysp", searching("lazysp", {{"connect_radius", 1.0}}), b.p);
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.found_by, "approach");
  const std::vector<PathStep>& path = r.best_path;
  ASSERT_GE(path.size(), 3u);
  const size_t edge = path.back().bundle_edge >= 0 ? path.size() - 1 : path.size() - 2;
  EXPECT_GE(path[edge].bundle_edge, 0);       // the approach's edge
  EXPECT_EQ(path[edge - 1].bundle_edge, -1);  // the straight command to the approach
  expect_revalidated(f, pocket, b.p, r);

  const PlanResult without =
      plan(context, ws, "lazysp", searching("lazysp", {{"connect_radius", 1.0}, {"approaches", 0}}),
           b.p);
  EXPECT_NE(without.found_by, "approach");
  EXPECT_FALSE(without.success && without.counters.simulations <= r.counters.simulations)
      << "without approaches as cheap: the test shows nothing";
  std::cout << "[ lazysp  ] pocket: " << r.counters.simulations << " simulations with approaches, "
            << without.counters.simulations << " without ("
            << (without.success ? "solved" : "not solved") << ")\n";
}

// The problem a -> c (stop_at_first) and the fixture's scene with a ball in the middle of its
// joint-space line, where the direct command would pass.
struct BallOnTheLine {
  PlanningProblem p;
  std::unique_ptr<BlockedScene> scene;
};

BallOnTheLine ball_on_the_line(const Fixture& f) {
  BallOnTheLine b{library_problem(f.a, f.c, 10), scene_with_ball(f, 0.5 * (f.a + f.c), 0.04)};
  b.p.termination.stop_at_first = true;
  return b;
}

// A path of one blended step: re-validated, and kept as it is by the post-processing (no
// simulation); its executable trajectory.
ExecutableTrajectory expect_kept_as_is(const Fixture& f, const PlanningContext& context,
                                       SimulatorWorkspace& ws, const PlanningProblem& p,
                                       const PlanResult& r) {
  expect_revalidated(f, context.sim, p, r);
  ExecutionOptions options;
  options.limits = context.command;
  const ExecutableTrajectory e =
      make_executable(context.sim, ws, p.start, r.best_path, p.goal, options, kSampleEvery);
  EXPECT_EQ(e.stats.simulations, 0);
  return e;
}

// The shortcut of a candidate that looks free (parameter `candidate_shortcut`): a ball on the
// joint-space line a -> c blocks the straight way, so the shortcut goes through a predicted state
// of the candidate. Its straight parts are simulated as one command with the junction blended
// (found_by "shortcut", one step with knot times), which the post-processing keeps without a
// simulation; without the shortcut, the candidate's edges are simulated, each with its settle.
TEST(LazySp, ACandidateThatLooksFreeIsSimulatedAsItsShortcut) {
  const Fixture& f = fixture();
  const BallOnTheLine b = ball_on_the_line(f);
  const PlanningProblem& p = b.p;
  const Simulator& blocked = b.scene->sim;
  SimulatorWorkspace ws(blocked);
  ASSERT_EQ(check_state(blocked, ws, p.start), RolloutStatus::Valid);
  ASSERT_EQ(check_state(blocked, ws, p.goal.q), RolloutStatus::Valid);
  ASSERT_FALSE(line_looks_free(blocked, ws, p.start, p.goal.q)) << "the ball misses the line";
  const PlanningContext context = session_context(f, blocked);
  const PlanResult r =
      plan(context, ws, "lazysp", searching("lazysp", {{"candidate_shortcut", 1}}), p);
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.found_by, "shortcut");
  ASSERT_EQ(r.best_path.size(), 1u);
  const PathStep& step = r.best_path[0];
  EXPECT_EQ(step.bundle_edge, -1);
  EXPECT_FALSE(step.knot_times.empty()) << "not the blended command";
  EXPECT_FALSE(step.outcome_rows.empty());
  EXPECT_EQ(expect_kept_as_is(f, context, ws, p, r).stats.stops, 0);

  const PlanResult edges = plan(context, ws, "lazysp", searching("lazysp"), p);
  ASSERT_TRUE(edges.success) << edges.failure;
  EXPECT_NE(edges.found_by, "shortcut");
  double edge_seconds = 0;
  for (const PathStep& s : edges.best_path) edge_seconds += s.outcome->duration;
  EXPECT_LT(step.outcome->duration, edge_seconds);
  std::cout << "[ lazysp  ] shortcut: one command of " << step.outcome->duration << " s in "
            << r.counters.simulations << " simulations; the candidate's " << edges.best_path.size()
            << " edges take " << edge_seconds << " s in " << edges.counters.simulations << "\n";
}

// Where the direct command is blocked (a ball on the joint-space line a -> c), lazysp first tries
// straight commands through one sampled waypoint, blended into one (parameter `waypoints`):
// found_by "waypoint", no lazy search, one step the post-processing keeps without a simulation.
// Without waypoints the search answers.
TEST(LazySp, ABlockedDirectCommandIsTriedThroughAWaypointBeforeAnySearch) {
  const Fixture& f = fixture();
  const BallOnTheLine b = ball_on_the_line(f);
  const PlanningProblem& p = b.p;
  const Simulator& blocked = b.scene->sim;
  SimulatorWorkspace ws(blocked);
  ASSERT_FALSE(line_looks_free(blocked, ws, p.start, p.goal.q)) << "the ball misses the line";
  const PlanningContext context = session_context(f, blocked);
  const PlanResult r = plan(context, ws, "lazysp", {}, p);
  ASSERT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.found_by, "waypoint");
  EXPECT_EQ(r.counters.lazy_edges, 0u);
  EXPECT_LE(r.counters.simulations, 4u);
  ASSERT_EQ(r.best_path.size(), 1u);
  const PathStep& step = r.best_path[0];
  EXPECT_EQ(step.bundle_edge, -1);
  ASSERT_EQ(step.knot_times.size() * f.sim.robot.dof, step.knots.size());
  EXPECT_GE(step.knot_times.size(), 3u) << "not a command through a waypoint";
  expect_kept_as_is(f, context, ws, p, r);

  const PlanResult again = plan(context, ws, "lazysp", {}, p);
  ASSERT_TRUE(again.success && again.best_path.size() == 1u) << again.failure;
  EXPECT_EQ(again.best_path[0].knots, step.knots) << "the same seed drew other waypoints";
  const PlanResult without = plan(context, ws, "lazysp", {{"waypoints", 0}}, p);
  ASSERT_TRUE(without.success) << without.failure;
  EXPECT_NE(without.found_by, "waypoint");
  EXPECT_GT(without.counters.lazy_edges, 0u);
  // Waypoints need the direct command's turn and the look at lines.
  for (const char* off : {"direct", "precheck"})
    EXPECT_NE(plan(context, ws, "lazysp", {{off, 0}}, p).found_by, "waypoint") << off;
  // Anytime (no stop_at_first): a waypoint's answer does not end the solve, the search goes on.
  PlanningProblem anytime = library_problem(f.a, f.c, 0.3);
  const PlanResult longer = plan(context, ws, "lazysp", {}, anytime);
  ASSERT_TRUE(longer.success) << longer.failure;
  EXPECT_GT(longer.counters.lazy_edges, 0u);
  EXPECT_LE(longer.best_cost, r.best_cost);
  std::cout << "[ lazysp  ] waypoint: " << r.counters.simulations << " simulations, "
            << r.counters.collision_checks << " checks; without waypoints "
            << without.counters.simulations << " simulations (" << without.found_by << ")\n";
}

// Where no single waypoint passes, two are tried: the scene of the test above, and a ball more on
// each answer through one waypoint (at the hand, halfway), until lazysp answers through two
// (found_by "two_waypoints": one blended step, re-validated), still with no lazy search.
TEST(LazySp, WhereNoSingleWaypointPassesTwoAreTried) {
  const Fixture& f = fixture();
  PlanningProblem p = library_problem(f.a, f.c, 10);
  p.termination.stop_at_first = true;
  Environment env = f.env;
  env.obstacles.push_back(ball_at(f, 0.5 * (f.a + f.c), 0.04));
  for (int balls = 1; balls <= 8; ++balls) {
    const BlockedScene scene(f, env);
    SimulatorWorkspace ws(scene.sim);
    const PlanResult r = plan(session_context(f, scene.sim), ws, "lazysp", {}, p);
    ASSERT_TRUE(r.success) << r.failure;
    if (r.found_by == "two_waypoints") {
      EXPECT_EQ(r.counters.lazy_edges, 0u);
      ASSERT_EQ(r.best_path.size(), 1u);
      EXPECT_EQ(r.best_path[0].bundle_edge, -1);
      EXPECT_GE(r.best_path[0].knot_times.size(), 4u) << "not a command through two waypoints";
      expect_kept_as_is(f, session_context(f, scene.sim), ws, p, r);
      std::cout << "[ lazysp  ] two waypoints after " << balls
                << " balls: " << r.counters.simulations << " simulations\n";
      return;
    }
    ASSERT_EQ(r.found_by, "waypoint") << "with " << balls << " balls, found by " << r.found_by
                                      << " before two waypoints were needed";
    const Trajectory t = realize_path(scene.sim, ws, p.start, r.best_path, p.goal, kSampleEvery);
    env.obstacles.push_back(ball_at(f, t.q[t.q.size() / 2], 0.04));
  }
  FAIL() << "eight balls and still one waypoint";
}

// When the look rejects a candidate, the round's search goes on without the rejected edge and
// what was planned through it (look_again) instead of starting again from every real node: in a
// scene whose ball the bundle's edges run into, it keeps fewer predicted states, and its answer
// is simulated and valid.
TEST(LazySp, ASearchTheLookRejectsGoesOnInsteadOfStartingAgain) {
  const Fixture& f = fixture();
  PlanningProblem p = library_problem(f.a, f.c, 10);
  p.termination.stop_at_first = true;
  const auto scene = scene_with_ball(f, 0.5 * (f.a + f.c), 0.06);
  SimulatorWorkspace ws(scene->sim);
  ASSERT_EQ(check_state(scene->sim, ws, p.start), RolloutStatus::Valid);
  ASSERT_EQ(check_state(scene->sim, ws, p.goal.q), RolloutStatus::Valid);
  const PlanningContext context = session_context(f, scene->sim);
  const PlanResult again = plan(context, ws, "lazysp", searching("lazysp"), p);
  const PlanResult anew = plan(context, ws, "lazysp", searching("lazysp", {{"look_again", 0}}), p);
  ASSERT_TRUE(again.success) << again.failure;
  ASSERT_TRUE(anew.success) << anew.failure;
  expect_revalidated(f, scene->sim, p, again);
  EXPECT_LT(again.counters.lazy_edges, anew.counters.lazy_edges);
  std::cout << "[ lazysp  ] predicted states with look_again " << again.counters.lazy_edges << " ("
            << again.counters.simulations << " simulations), starting again after each "
            << "rejection " << anew.counters.lazy_edges << " (" << anew.counters.simulations
            << ")\n";
}

// The goal test's look: the lazy search's candidate for a joint goal ends where the straight line
// into the goal looks free. In the fixture's scene, a problem's answer ends with the direct
// command from a candidate's last state; there the look changes nothing but the checks it costs.
// A ball on that command's line, a quarter of the way in, blocks it: without the look, that
// candidate and its neighbours are simulated before their connections are found blocked; with
// it, they are passed over unsimulated.
TEST(LazySp, TheGoalTestLooksAtTheLineIntoTheGoal) {
  const Fixture& f = fixture();
  const ParameterValues on = searching("lazysp", {{"connect_radius", 1.5}});
  const ParameterValues off = searching("lazysp", {{"connect_radius", 1.5}, {"goal_look", 0}});
  int blocked_problems = 0;
  uint64_t simulations_looked = 0, simulations_without = 0;
  for (const auto& [from, to] : std::vector<std::pair<JointVector, JointVector>>{
           {f.a, f.c}, {f.c, f.a}, {f.b, f.c}, {f.c, f.b}}) {
    PlanningProblem p = library_problem(from, to, 10);
    p.termination.stop_at_first = true;
    SimulatorWorkspace ws(f.sim);
    const PlanningContext open = session_context(f, f.sim);
    const PlanResult clear = plan(open, ws, "lazysp", off, p);
    const PlanResult clear_looked = plan(open, ws, "lazysp", on, p);
    ASSERT_TRUE(clear.success && clear_looked.success) << clear.failure;
    EXPECT_EQ(clear_looked.best_cost, clear.best_cost);
    EXPECT_EQ(clear_looked.counters.simulations, clear.counters.simulations);
    EXPECT_GT(clear_looked.counters.collision_checks, clear.counters.collision_checks);
    if (clear.found_by != "connection" || clear.best_path.size() < 2) continue;
    // The state the connection started from, and a ball on its line into the goal.
    const Trajectory t = realize_path(f.sim, ws, p.start, clear.best_path, p.goal, 0);
    const double t_end = t.duration - clear.best_path.back().outcome->duration;
    size_t k = 0;
    while (k + 1 < t.t.size() && t.t[k] < t_end - 1e-9) ++k;
    const JointVector end = t.q[k];
    const auto scene = scene_with_ball(f, end + 0.25 * (p.goal.q - end), 0.03);
    SimulatorWorkspace bws(scene->sim);
    if (check_state(scene->sim, bws, p.start) != RolloutStatus::Valid ||
        check_state(scene->sim, bws, p.goal.q) != RolloutStatus::Valid)
      continue;
    const PlanningContext context = session_context(f, scene->sim);
    const PlanResult looked = plan(context, bws, "lazysp", on, p);
    const PlanResult without = plan(context, bws, "lazysp", off, p);
    ASSERT_TRUE(looked.success) << looked.failure;
    ASSERT_TRUE(without.success) << without.failure;  // else its count is the budget's
    expect_revalidated(f, scene->sim, p, looked);
    simulations_looked += looked.counters.simulations;
    simulations_without += without.counters.simulations;
    ++blocked_problems;
  }
  ASSERT_GE(blocked_problems, 2) << "too few answers end with a connection: the test shows little";
  std::cout << "[ lazysp  ] the goal test's look, " << blocked_problems
            << " problems with a ball on the way in: " << simulations_looked << " simulations, "
            << simulations_without << " without it\n";
  EXPECT_LT(simulations_looked, simulations_without);
}

}  // namespace
}  // namespace lazyboe::test
