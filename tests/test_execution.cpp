// The execution stage (lib/planning/execution.h) on paths of the small planning bundle:
// blended and shortcut trajectories pass the fixture's independent re-validation and an
// independent re-simulation of their joined commands through simulate() (sample by sample at
// the control rate); a blend that would collide (an obstacle placed on the blended motion at a
// junction, clear of the raw chain) keeps its stop; first and last samples at rest; the stage
// without blending or shortcuts is the raw chain bit for bit; the same output on every run and
// with any thread count (test_query_cli); commands with knot times evaluate as evenly spaced ones
// do. The planners hand over their simulation of each step, so the raw chain is not simulated
// again; the bundle planners answer a free straight command with it (found_by direct), a blocked
// one by searching. Rollouts that go on from earlier ones' checkpoints change nothing but the
// ticks simulated. Straight commands through points blended into one command with knot times
// (lazysp's shortcut) are one rollout that the post-processing keeps as it is.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/sim/trajectory_check.h"
#include "planning_fixture.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

struct Fixture : PlanningFixture {
  Fixture() : Fixture(build_small_bundles()) {}
  explicit Fixture(const SmallBundles& built)
      : PlanningFixture(built.perturbed,
                        BundleView::from_memory(built.perturbed, "the small bundle (in memory)")) {}
};

const Fixture& fixture() { return shared_fixture<Fixture>(); }

PlanningProblem problem_to(const JointVectorRef& start, const JointVectorRef& goal) {
  PlanningProblem p;
  p.start = start;
  p.goal.q = goal;
  p.goal.tolerance = kTolerance;
  p.termination.budget = 3.0 * time_scale();  // the sanitizers slow the planners
  p.termination.stop_at_first = true;
  p.seed = 3;
  return p;
}

// A path of several bundle edges, a -> c, found once (BoE, deterministic for its seed).
struct PathCase {
  PlanningProblem problem;
  PlanResult result;
};

const PathCase& long_path() {
  static const PathCase c = [] {
    const Fixture& f = fixture();
    const PlanningContext context = bundle_context(f.sim, f.view, f.index);
    SimulatorWorkspace ws(f.sim);
    PathCase out;
    out.problem = problem_to(f.a, f.c);
    out.result = plan(context, ws, "boe", searching("boe"), out.problem);
    return out;
  }();
  return c;
}

ExecutionOptions options(bool shortcut, bool blend) {
  ExecutionOptions o;
  o.shortcut_attempts = shortcut ? o.shortcut_attempts : 0;
  o.blend = blend;
  o.limits = bundle_context(fixture().sim, fixture().view, fixture().index).command;
  return o;
}

ExecutableTrajectory execute(const Simulator& sim, const PathCase& c, const ExecutionOptions& o) {
  SimulatorWorkspace ws(sim);
  return make_executable(sim, ws, c.problem.start, c.result.best_path, c.problem.goal, o, 1);
}

// Simulates every segment's command again from its start, at every control tick, and compares
// each sample of the trajectory and the chaining of the segments. Empty when all agree.
std::string resimulate_segments(const Simulator& planning_sim, const ExecutableTrajectory& e,
                                const JointVectorRef& start) {
  // Segments that end at a stop settle until the arm can stop dead; the last as the planners'.
  const Simulator stopping = execution_simulator(planning_sim);
  std::ostringstream p;
  const int n = planning_sim.robot.dof;
  SimulatorWorkspace ws(planning_sim);
  JointVector q = start;
  size_t sample = 0;
  for (size_t s = 0; s < e.segments.size(); ++s) {
    const ExecutionSegment& seg = e.segments[s];
    if (!(seg.start == q)) p << "segment " << s << " does not start where the last ended\n";
    std::vector<double> ticks;
    const Simulator& sim = s + 1 == e.segments.size() ? planning_sim : stopping;
    const RolloutResult r = simulate(sim, ws, q, seg.profile(n), {nullptr, nullptr, 0, &ticks});
    if (!r.valid()) {
      p << "segment " << s << ": " << rollout_status_name(r.status) << "\n";
      return p.str();
    }
    const size_t rows = ticks.size() / (4 * n);
    for (size_t k = s == 0 ? 0 : 1; k < rows; ++k, ++sample) {
      if (sample >= e.trajectory.q.size()) return p.str() + "more ticks than samples\n";
      const double* row = &ticks[k * 4 * n];
      for (int i = 0; i < n; ++i) {
        if (row[i] != e.trajectory.q[sample][i] || row[n + i] != e.trajectory.dq[sample][i] ||
            row[2 * n + i] != e.trajectory.ddq[sample][i] ||
            row[3 * n + i] != e.trajectory.cmd[sample][i]) {
          p << "segment " << s << ", tick " << k << ": differs from sample " << sample << "\n";
          return p.str();
        }
      }
    }
    q = r.qf;
  }
  if (sample != e.trajectory.q.size()) p << "fewer ticks than samples\n";
  return p.str();
}

// The independent checker (lazyboe-robot validate-trajectory's): limits by finite differences
// and inverse dynamics at every control tick, collision, rest at both ends. Empty when valid.
std::string checker_verdict(const Simulator& sim, const Trajectory& t) {
  const int n = sim.robot.dof;
  std::vector<double> q, dq;
  for (size_t k = 0; k < t.q.size(); ++k) {
    q.insert(q.end(), t.q[k].data(), t.q[k].data() + n);
    dq.insert(dq.end(), t.dq[k].data(), t.dq[k].data() + n);
  }
  const TrajectoryChecker checker(sim.robot, sim.collision);
  TrajectoryCheckWorkspace ws(checker);
  const TrajectoryView view{static_cast<int>(t.t.size()), n, t.t.data(), q.data(), dq.data()};
  const TrajectoryCheckResult r = check_trajectory(checker, ws, view);
  return r.valid ? "" : describe_violation(checker, r.violation);
}

void expect_at_rest_ends(const Simulator& sim, const ExecutableTrajectory& e,
                         const PlanningProblem& problem) {
  const Trajectory& t = e.trajectory;
  ASSERT_FALSE(t.q.empty());
  EXPECT_EQ(t.t.front(), 0.0);
  EXPECT_TRUE(t.q.front() == problem.start);
  EXPECT_EQ(t.dq.front().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(t.ddq.front().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE(t.dq.back().cwiseAbs().maxCoeff(), sim.options.settle_velocity);
  EXPECT_EQ(t.cmd.back().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((t.ddq.back().array().abs() - sim.robot.dddq_max.array() * sim.dt).maxCoeff(), 0);
  EXPECT_LE((t.q.back() - problem.goal.q).norm(), problem.goal.tolerance);
}

// An executable trajectory, not the raw chain, that passes re-simulation and the independent
// checker and rests at both ends, the last in the goal.
void expect_executable(const Simulator& sim, const ExecutableTrajectory& e,
                       const PlanningProblem& problem) {
  EXPECT_FALSE(e.stats.fell_back);
  EXPECT_EQ(resimulate_segments(sim, e, problem.start), "");
  EXPECT_EQ(checker_verdict(sim, e.trajectory), "");
  expect_at_rest_ends(sim, e, problem);
}

TEST(Execution, BlendedTrajectoryPassesReSimulationAndReValidation) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  ASSERT_GE(c.result.best_path.size(), 2u) << "the test needs a path of several edges";
  const ExecutableTrajectory e = execute(f.sim, c, options(false, true));
  const ExecutionStats& s = e.stats;
  EXPECT_FALSE(s.fell_back);
  EXPECT_EQ(s.shortcuts, 0);
  EXPECT_EQ(s.junctions, static_cast<int>(c.result.best_path.size()) - 1);
  EXPECT_GE(s.blends_kept, 1);
  EXPECT_EQ(s.stops, s.junctions - s.blends_kept);
  EXPECT_EQ(e.trajectory.stops, s.stops);
  EXPECT_LT(e.trajectory.duration, s.raw_duration);
  // Rollouts went on from earlier ones where their commands agreed (corrections of joined
  // commands); the segments are still what a fresh simulation of their commands gives.
  EXPECT_GT(s.resumed_ticks, 0);
  EXPECT_EQ(resimulate_segments(f.sim, e, c.problem.start), "");
  EXPECT_EQ(validate(f, e.trajectory, c.problem.start, c.problem.goal.q, kTolerance, "boe"), "");
  EXPECT_EQ(checker_verdict(f.sim, e.trajectory), "");
  expect_at_rest_ends(f.sim, e, c.problem);
  std::vector<int64_t> edges;
  for (const PathStep& step : c.result.best_path) edges.push_back(step.bundle_edge);
  EXPECT_EQ(e.trajectory.edges, edges);
}

TEST(Execution, ShortcutTrajectoryPassesReSimulationAndIsShorter) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  const ExecutableTrajectory e = execute(f.sim, c, options(true, true));
  EXPECT_FALSE(e.stats.fell_back);
  EXPECT_GE(e.stats.shortcuts, 1);
  EXPECT_LT(e.stats.steps, e.stats.raw_steps);
  EXPECT_LE(e.trajectory.cost, e.stats.raw_cost);
  EXPECT_LT(e.trajectory.duration, e.stats.raw_duration);
  EXPECT_EQ(resimulate_segments(f.sim, e, c.problem.start), "");
  EXPECT_EQ(validate(f, e.trajectory, c.problem.start, c.problem.goal.q, kTolerance, "boe"), "");
  EXPECT_EQ(checker_verdict(f.sim, e.trajectory), "");
  expect_at_rest_ends(f.sim, e, c.problem);
}

// Without blends or shortcuts: the raw chain's commands, one segment each, every junction a
// stop. The raw chain itself fails the independent checker at its junctions (each edge ends
// below the settle velocity, the next starts from exactly zero: a torque step over the rate
// limit); the segments settle until the arm can stop dead, and pass.
TEST(Execution, WithoutBlendsOrShortcutsItIsTheRawChainStoppingForReal) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  const ExecutableTrajectory e = execute(f.sim, c, options(false, false));
  SimulatorWorkspace ws(f.sim);
  const Trajectory raw =
      realize_path(f.sim, ws, c.problem.start, c.result.best_path, c.problem.goal, 1);
  EXPECT_EQ(e.stats.blends_kept, 0);
  EXPECT_EQ(e.stats.stops, static_cast<int>(c.result.best_path.size()) - 1);
  EXPECT_EQ(e.trajectory.stops, raw.stops);
  ASSERT_EQ(e.segments.size(), c.result.best_path.size());
  // The first is the raw step's command exactly; the others are corrected by the small offset
  // their start has from the raw chain (displacement transfer).
  EXPECT_EQ(e.segments[0].knots, c.result.best_path[0].knots);
  for (size_t k = 0; k < e.segments.size(); ++k) {
    EXPECT_TRUE(e.segments[k].uniform);
    const std::vector<double>& raw_knots = c.result.best_path[k].knots;
    ASSERT_EQ(e.segments[k].knots.size(), raw_knots.size());
    for (size_t j = 0; j < raw_knots.size(); ++j)
      EXPECT_NEAR(e.segments[k].knots[j], raw_knots[j], 0.01) << "segment " << k;
  }
  EXPECT_LE((e.trajectory.q.back() - raw.q.back()).cwiseAbs().maxCoeff(), 2e-3);
  EXPECT_GE(e.trajectory.duration, raw.duration);  // the longer settles
  EXPECT_EQ(resimulate_segments(f.sim, e, c.problem.start), "");
  EXPECT_EQ(checker_verdict(f.sim, e.trajectory), "");
  EXPECT_NE(checker_verdict(f.sim, raw).find("torque_rate_limit"), std::string::npos);
}

TEST(Execution, SameOutputOnEveryRun) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  const ExecutableTrajectory a = execute(f.sim, c, options(true, true));
  const ExecutableTrajectory b = execute(f.sim, c, options(true, true));
  ASSERT_EQ(a.trajectory.q.size(), b.trajectory.q.size());
  for (size_t k = 0; k < a.trajectory.q.size(); ++k) {
    ASSERT_TRUE(a.trajectory.q[k] == b.trajectory.q[k]) << "sample " << k;
    ASSERT_TRUE(a.trajectory.cmd[k] == b.trajectory.cmd[k]) << "sample " << k;
  }
  EXPECT_EQ(a.stats.simulations, b.stats.simulations);
}

// An obstacle where the blended motion passes at a junction but the raw chain does not: the
// junction keeps its stop, and the trajectory is valid among the obstacles.
struct Obstructed {
  Environment env;
  std::unique_ptr<CollisionModel> collision;
  std::unique_ptr<Simulator> sim;
};

bool raw_chain_valid(const Simulator& sim, const PathCase& c) {
  SimulatorWorkspace ws(sim);
  try {
    realize_path(sim, ws, c.problem.start, c.result.best_path, c.problem.goal, 1000);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

// Candidates: a small sphere near a robot shape's centre at a blended state within 0.1 rad of
// the raw chain's junction state, moved away from where that shape is at the junction; the
// first that the blended state hits and the raw chain clears.
bool place_obstacle(const Fixture& f, const PathCase& c, const ExecutableTrajectory& blended,
                    int junction_step, Obstructed& out) {
  SimulatorWorkspace ws(f.sim);
  const Trajectory raw =
      realize_path(f.sim, ws, c.problem.start, c.result.best_path, c.problem.goal, 1);
  // The raw chain's junction state: the end of step junction_step.
  JointVector q_junction = c.problem.start;
  for (int k = 0; k <= junction_step; ++k) {
    const RolloutResult r = simulate(f.sim, ws, q_junction, f.view.command(raw.edges[k]));
    q_junction = r.qf;
  }
  RobotData blended_data(f.robot), raw_data(f.robot);
  for (size_t k = 0; k < blended.trajectory.q.size(); k += 5) {
    if ((blended.trajectory.q[k] - q_junction).norm() > 0.1) continue;
    forward_kinematics(f.robot, blended_data, blended.trajectory.q[k]);
    forward_kinematics(f.robot, raw_data, q_junction);
    for (const CollisionModel::RobotShape& shape : f.collision.robot) {
      if (shape.body < 3) continue;
      const Pose pb = link_pose(f.robot, blended_data, shape.link);
      const Pose pr = link_pose(f.robot, raw_data, shape.link);
      const Eigen::Vector3d xb = pb.p + pb.R * shape.in_body.p;
      const Eigen::Vector3d xr = pr.p + pr.R * shape.in_body.p;
      const Eigen::Vector3d away = (xb - xr).normalized();
      for (double reach : {0.9, 0.7, 0.5}) {
        Obstructed o;
        o.env = load_environment(f.data.header.env_file);
        Obstacle ball;
        ball.name = "junction_ball";
        ball.shape.type = ShapeType::Sphere;
        ball.shape.radius = 0.005;
        ball.pose.p = xb + reach * shape.sphere_radius * away;
        o.env.obstacles.push_back(ball);
        o.collision = std::make_unique<CollisionModel>(build_collision_model(f.robot, o.env));
        o.sim = std::make_unique<Simulator>(f.robot, *o.collision, f.sim.options);
        SimulatorWorkspace ows(*o.sim);
        if (check_state(*o.sim, ows, blended.trajectory.q[k]) != RolloutStatus::EnvCollision)
          continue;
        if (!raw_chain_valid(*o.sim, c)) continue;
        out = std::move(o);
        return true;
      }
    }
  }
  return false;
}

TEST(Execution, BlendThatWouldCollideKeepsItsStop) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  // One blend variant, so that the obstacle on it is on every blend tried.
  ExecutionOptions one_blend = options(false, true);
  one_blend.blend_scales = {0.5};
  const ExecutableTrajectory free = execute(f.sim, c, one_blend);
  ASSERT_EQ(free.stats.stops, 0) << "every junction is blended without the obstacle";
  Obstructed o;
  ASSERT_TRUE(place_obstacle(f, c, free, 0, o))
      << "no obstacle position hits the blend and clears the raw chain";
  const ExecutableTrajectory e = execute(*o.sim, c, one_blend);
  EXPECT_FALSE(e.stats.fell_back);
  EXPECT_GE(e.stats.stops, 1);
  EXPECT_EQ(resimulate_segments(*o.sim, e, c.problem.start), "");
  SimulatorWorkspace ws(*o.sim);
  for (size_t k = 0; k < e.trajectory.q.size(); ++k)
    ASSERT_EQ(check_state(*o.sim, ws, e.trajectory.q[k]), RolloutStatus::Valid) << "sample " << k;
  EXPECT_EQ(checker_verdict(*o.sim, e.trajectory),
            "");  // the kept stop too: at rest within every rate limit
  expect_at_rest_ends(*o.sim, e, c.problem);
}

// Rollouts that go on from earlier ones where their commands agree (corrections, a junction
// tried again or split into a stop) give the trajectories and decisions that simulating every
// rollout from its start gives; only the ticks simulated differ, by the ticks gone on from.
TEST(Execution, GoingOnFromEarlierRolloutsChangesNothing) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  ExecutionOptions one_blend = options(false, true);
  one_blend.blend_scales = {0.5};
  Obstructed o;
  ASSERT_TRUE(place_obstacle(f, c, execute(f.sim, c, one_blend), 0, o));
  struct Case {
    const Simulator* sim;
    ExecutionOptions options;
  };
  const std::vector<Case> cases = {
      {&f.sim, options(false, true)}, {&f.sim, options(true, true)}, {o.sim.get(), one_blend}};
  long resumed = 0;
  for (size_t k = 0; k < cases.size(); ++k) {
    SCOPED_TRACE("case " + std::to_string(k));
    ExecutionOptions fresh = cases[k].options;
    fresh.resume = false;
    const ExecutableTrajectory a = execute(*cases[k].sim, c, cases[k].options);
    const ExecutableTrajectory b = execute(*cases[k].sim, c, fresh);
    EXPECT_TRUE(a.trajectory.q == b.trajectory.q && a.trajectory.dq == b.trajectory.dq &&
                a.trajectory.ddq == b.trajectory.ddq && a.trajectory.cmd == b.trajectory.cmd);
    EXPECT_EQ(a.trajectory.cost, b.trajectory.cost);
    ASSERT_EQ(a.segments.size(), b.segments.size());
    for (size_t s = 0; s < a.segments.size(); ++s) {
      const RolloutResult &x = a.segments[s].result, &y = b.segments[s].result;
      EXPECT_TRUE(x.status == y.status && x.qf == y.qf && x.ticks == y.ticks &&
                  x.collision_checks == y.collision_checks && x.path_length == y.path_length)
          << "segment " << s;
    }
    EXPECT_EQ(a.stats.simulations, b.stats.simulations);
    EXPECT_EQ(a.stats.stops, b.stats.stops);
    EXPECT_EQ(b.stats.resumed_ticks, 0);
    EXPECT_EQ(a.stats.simulated_ticks + a.stats.resumed_ticks, b.stats.simulated_ticks);
    resumed += a.stats.resumed_ticks;
  }
  EXPECT_GT(resumed, 0);
}

// The planners hand over their simulation of every step: the post-processing does not simulate
// the raw chain again (issue 27), and gives exactly what it gave when it did.
TEST(Execution, TheRawChainIsNotSimulatedAgain) {
  const Fixture& f = fixture();
  PathCase c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  long handed_ticks = 0;
  for (const PathStep& s : c.result.best_path) {
    ASSERT_TRUE(s.outcome) << "a step without the planner's simulation";
    handed_ticks += s.outcome->ticks;
  }
  PathCase bare = c;  // the same path without the planner's simulations
  for (PathStep& s : bare.result.best_path) s.outcome.reset();
  for (bool shortcut : {false, true}) {
    SCOPED_TRACE(shortcut ? "shortcuts and blends" : "blends");
    const ExecutableTrajectory handed = execute(f.sim, c, options(shortcut, true));
    const ExecutableTrajectory again = execute(f.sim, bare, options(shortcut, true));
    EXPECT_EQ(again.stats.simulations - handed.stats.simulations,
              static_cast<int>(c.result.best_path.size()));
    EXPECT_EQ(again.stats.simulated_ticks - handed.stats.simulated_ticks, handed_ticks);
    EXPECT_EQ(handed.trajectory.q, again.trajectory.q);
    EXPECT_EQ(handed.trajectory.dq, again.trajectory.dq);
    EXPECT_EQ(handed.stats.raw_cost, again.stats.raw_cost);
    EXPECT_EQ(handed.stats.raw_duration, again.stats.raw_duration);
    EXPECT_EQ(resimulate_segments(f.sim, handed, c.problem.start), "");
  }
}

// The straight command a -> b, free in the fixture's scene.
PathStep free_straight_step(const PlanningProblem& p) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  const std::optional<PathStep> straight = direct_step(f.sim, ws, options(true, true).limits, p);
  if (!straight || !solves(f.sim, ws, *straight, p.goal)) return {};
  return *straight;
}

// A ball at the hand somewhere along a motion (state_at(fraction)), clear of the start and the
// goal.
bool block_motion(const PlanningProblem& p, const std::function<JointVector(double)>& state_at,
                  Obstructed& out) {
  const Fixture& f = fixture();
  for (double at : {0.5, 0.4, 0.6, 0.3, 0.7}) {
    for (double radius : {0.03, 0.02, 0.01}) {
      RobotData data(f.robot);
      forward_kinematics(f.robot, data, state_at(at));
      out.env = f.env;
      Obstacle ball;
      ball.name = "on-the-straight-line";
      ball.shape.type = ShapeType::Sphere;
      ball.shape.radius = radius;
      ball.pose.p = link_pose(f.robot, data, f.robot.tip_link()).p;
      out.env.obstacles.push_back(ball);
      out.collision = std::make_unique<CollisionModel>(build_collision_model(f.robot, out.env));
      out.sim = std::make_unique<Simulator>(f.robot, *out.collision, f.sim.options);
      SimulatorWorkspace ws(*out.sim);
      if (check_state(*out.sim, ws, p.start) == RolloutStatus::Valid &&
          check_state(*out.sim, ws, p.goal.q) == RolloutStatus::Valid)
        return true;
    }
  }
  return false;
}

// A ball on the straight command's simulated motion.
bool block_straight_motion(const PlanningProblem& p, const PathStep& straight, Obstructed& out) {
  const int n = fixture().robot.dof;
  const size_t rows = straight.outcome_rows.size() / (4 * n);
  return block_motion(
      p,
      [&](double at) {
        const size_t k = static_cast<size_t>(at * rows);
        return JointVector(Eigen::Map<const Eigen::VectorXd>(&straight.outcome_rows[k * 4 * n], n));
      },
      out);
}

// A ball on the joint-space line from the start to the goal, at one of the states the look
// checks (line_looks_free).
bool block_line(const PlanningProblem& p, Obstructed& out) {
  const JointVector span = p.goal.q - p.start;
  const int steps = static_cast<int>(std::ceil(span.norm() / kLineLookStep));
  return block_motion(
      p,
      [&](double at) {
        const int k = static_cast<int>(at * steps);
        return JointVector(p.start + span * (static_cast<double>(k) / steps));
      },
      out);
}

// The bundle planners try the straight command first: where it is free it is the answer (one
// simulation, no bundle edge) and the post-processing simulates nothing.
TEST(Execution, AFreeStraightCommandIsTheAnswer) {
  const Fixture& f = fixture();
  const PlanningProblem p = problem_to(f.a, f.b);
  ASSERT_TRUE(free_straight_step(p).outcome) << "a -> b is not free";
  SimulatorWorkspace ws(f.sim);
  for (const std::string planner : {"boe", "lazyboe", "lazysp"}) {
    SCOPED_TRACE(planner);
    const PlanResult r = plan(bundle_context(f.sim, f.view, f.index), ws, planner, {}, p);
    ASSERT_TRUE(r.success) << r.failure;
    EXPECT_EQ(r.found_by, "direct");
    EXPECT_EQ(r.counters.simulations, 1u);
    ASSERT_EQ(r.best_path.size(), 1u);
    EXPECT_EQ(r.best_path[0].bundle_edge, -1);
    const ExecutableTrajectory e =
        make_executable(f.sim, ws, p.start, r.best_path, p.goal, options(true, true), 1);
    EXPECT_EQ(e.stats.simulations, 0);
    EXPECT_EQ(e.stats.simulated_ticks, 0);
    EXPECT_EQ(resimulate_segments(f.sim, e, p.start), "");
    EXPECT_EQ(checker_verdict(f.sim, e.trajectory), "");
    expect_at_rest_ends(f.sim, e, p);
  }
}

// Where an obstacle blocks the straight command, they search.
TEST(Execution, ABlockedStraightCommandIsNotTheAnswer) {
  const Fixture& f = fixture();
  const PlanningProblem p = problem_to(f.a, f.b);
  const PathStep straight = free_straight_step(p);
  ASSERT_TRUE(straight.outcome) << "a -> b is not free";
  Obstructed o;
  ASSERT_TRUE(block_straight_motion(p, straight, o))
      << "no ball on the straight motion clears the start and the goal";
  SimulatorWorkspace ws(*o.sim);
  const std::optional<PathStep> hit = direct_step(*o.sim, ws, options(true, true).limits, p);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->outcome->status, RolloutStatus::EnvCollision);
  for (const std::string planner : {"boe", "lazysp"}) {
    SCOPED_TRACE(planner);
    const PlanResult r = plan(bundle_context(*o.sim, f.view, f.index), ws, planner, {}, p);
    EXPECT_NE(r.found_by, "direct");
    EXPECT_GT(r.counters.simulations, 1u);
    if (r.success) {
      EXPECT_NO_THROW(realize_path(*o.sim, ws, p.start, r.best_path, p.goal, 10));
      // Not the straight command (lazysp's path may begin with another one, of its shortcut).
      EXPECT_NE(r.best_path[0].knots, hit->knots);
    }
  }
}

// The look at a direct command's joint-space line: every kLineLookStep, the end included, on a
// free line; stopped at a state an obstacle on the line blocks.
TEST(Execution, TheLookAtALineFindsWhatBlocksIt) {
  const Fixture& f = fixture();
  const PlanningProblem p = problem_to(f.a, f.b);
  const uint64_t steps = static_cast<uint64_t>(std::ceil((f.b - f.a).norm() / kLineLookStep));
  ASSERT_GT(steps, 4u);
  SimulatorWorkspace ws(f.sim);
  uint64_t checks = 0;
  EXPECT_TRUE(line_looks_free(f.sim, ws, f.a, f.b, &checks));
  EXPECT_EQ(checks, steps);
  Obstructed o;
  ASSERT_TRUE(block_line(p, o)) << "no ball on the line clears the start and the goal";
  SimulatorWorkspace blocked(*o.sim);
  checks = 0;
  EXPECT_FALSE(line_looks_free(*o.sim, blocked, f.a, f.b, &checks));
  EXPECT_GT(checks, 0u);
  EXPECT_LT(checks, steps);
}

// Where the line to the goal is blocked (a path of several edges, as long_path's), the shortcut
// pass leaves out the candidates whose line is blocked without simulating them (fewer simulations
// than without the look), and both trajectories pass re-simulation and the independent checker in
// the scene.
TEST(Execution, TheShortcutPassLooksBeforeItSimulates) {
  const Fixture& f = fixture();
  const PlanningProblem p = problem_to(f.a, f.c);
  Obstructed o;
  ASSERT_TRUE(block_line(p, o)) << "no ball on the line clears the start and the goal";
  const PlanningContext context = bundle_context(*o.sim, f.view, f.index);
  SimulatorWorkspace ws(*o.sim);
  const PlanResult r = plan(context, ws, "boe", searching("boe"), p);
  ASSERT_TRUE(r.success) << r.failure;
  ASSERT_GE(r.best_path.size(), 2u);
  ExecutionOptions on = options(true, true), off = on;
  off.look = false;
  const ExecutableTrajectory with_look =
      make_executable(*o.sim, ws, p.start, r.best_path, p.goal, on, 1);
  const ExecutableTrajectory without =
      make_executable(*o.sim, ws, p.start, r.best_path, p.goal, off, 1);
  EXPECT_GE(with_look.stats.looked_blocked, 1);
  EXPECT_EQ(without.stats.looked_blocked, 0);
  EXPECT_LT(with_look.stats.simulations, without.stats.simulations);
  for (const ExecutableTrajectory* e : {&with_look, &without}) expect_executable(*o.sim, *e, p);
}

// A correction round adds the residual to the last knot of the corrected range only
// (correction_knots 1), so it goes on from the rollout's checkpoint before that knot: fewer ticks
// simulated than with the correction spread over the range (0), and both trajectories pass
// re-simulation and the independent checker, at rest in the goal.
TEST(Execution, ACorrectionRoundGoesOnFromBeforeTheLastKnot) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  ExecutionOptions late = options(true, true), spread = late;
  spread.correction_knots = 0;
  const ExecutableTrajectory a = execute(f.sim, c, late);
  const ExecutableTrajectory b = execute(f.sim, c, spread);
  EXPECT_GT(a.stats.resumed_ticks, b.stats.resumed_ticks);
  EXPECT_LT(a.stats.simulated_ticks, b.stats.simulated_ticks);
  for (const ExecutableTrajectory* e : {&a, &b}) expect_executable(f.sim, *e, c.problem);
}

// A round that a correction may follow stops where its command ends, and the settle's
// displacement is predicted (predict_settle): only a round whose predicted end needs no
// correction settles. Fewer ticks than settling every round, the same shortcuts and stops, and
// trajectories that pass re-simulation and the independent checker, at rest in the goal.
TEST(Execution, ARoundThatACorrectionFollowsDoesNotSettle) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  for (bool shortcut : {false, true}) {
    SCOPED_TRACE(shortcut ? "shortcuts and blends" : "blends");
    ExecutionOptions predicted = options(shortcut, true), settled = predicted;
    settled.predict_settle = false;
    const ExecutableTrajectory a = execute(f.sim, c, predicted);
    const ExecutableTrajectory b = execute(f.sim, c, settled);
    EXPECT_LT(a.stats.simulated_ticks, b.stats.simulated_ticks);
    EXPECT_EQ(a.stats.shortcuts, b.stats.shortcuts);
    EXPECT_EQ(a.stats.stops, b.stats.stops);
    for (const ExecutableTrajectory* e : {&a, &b}) expect_executable(f.sim, *e, c.problem);
  }
}

// The settle's displacement predicted where a command ends (settle_displacement) against the
// settle simulated from there, on bundle edges of the fixture (the prediction decides whether a
// round is corrected before its settle is simulated): within a fifth of the settle's own
// displacement, or 0.2 mrad, on every joint.
TEST(Execution, TheSettleIsPredictedWhereTheCommandEnds) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  RobotData scratch(f.robot);
  int compared = 0;
  for (uint32_t e = 0; e < 200 && compared < 40; e += 5) {
    const CommandProfile command = f.view.command(e);
    const int end = ticks_before(f.sim, command.duration);
    const std::vector<int> save_at = {end};
    std::vector<RolloutCheckpoint> saved;
    const JointVector q0 = Eigen::Map<const Eigen::VectorXd>(f.view.q0(e), f.robot.dof);
    const RolloutResult r = simulate(f.sim, ws, q0, command, {}, {nullptr, &save_at, &saved});
    if (!r.valid() || saved.size() != 1) continue;
    const RolloutCheckpoint& c = saved[0];
    const JointVector settle = r.qf - c.q;
    const JointVector error = c.q + settle_displacement(f.sim, scratch, c.q, c.dq) - r.qf;
    for (int i = 0; i < f.robot.dof; ++i)
      EXPECT_LE(std::abs(error[i]), std::max(0.2 * std::abs(settle[i]), 2e-4))
          << "edge " << e << ", joint " << i << ": settle " << settle[i];
    ++compared;
  }
  EXPECT_GE(compared, 20);
}

// A shortcut whose line looks free is taken without a simulation of its own: the blend pass
// simulates it as the first part of its segment. The same shortcuts, fewer ticks than simulating
// each shortcut first, and a trajectory that passes re-simulation and the independent checker.
TEST(Execution, ALookedShortcutIsSimulatedOnlyInItsSegment) {
  const Fixture& f = fixture();
  const PlanningProblem p = problem_to(f.b, f.c);
  Obstructed o;  // the line blocked: lazysp's path of a few edges, shortcut in part
  ASSERT_TRUE(block_line(p, o)) << "no ball on the line clears the start and the goal";
  const PlanningContext context = bundle_context(*o.sim, f.view, f.index);
  SimulatorWorkspace ws(*o.sim);
  // A new search after each rejected candidate: with look_again, lazysp finds a path here that
  // leaves the post-processing no shortcut to take.
  const PlanResult r = plan(context, ws, "lazysp", searching("lazysp", {{"look_again", 0}}), p);
  ASSERT_TRUE(r.success) << r.failure;
  ExecutionOptions looked = options(true, true), simulated = looked;
  simulated.looked_shortcuts = false;
  const ExecutableTrajectory a =
      make_executable(*o.sim, ws, p.start, r.best_path, p.goal, looked, 1);
  const ExecutableTrajectory b =
      make_executable(*o.sim, ws, p.start, r.best_path, p.goal, simulated, 1);
  EXPECT_GE(a.stats.shortcuts, 1);
  EXPECT_GE(a.stats.steps, 2);
  EXPECT_EQ(a.stats.shortcuts, b.stats.shortcuts);
  EXPECT_EQ(a.stats.steps, b.stats.steps);
  EXPECT_FALSE(a.stats.shortcuts_simulated_again);
  EXPECT_LT(a.stats.simulated_ticks, b.stats.simulated_ticks);
  for (const ExecutableTrajectory* e : {&a, &b}) expect_executable(*o.sim, *e, p);
}

// When an attempt at a segment with a looked shortcut fails, both passes run again with every
// shortcut simulated first: the trajectory is the one those passes give on their own. Here an
// end tolerance of 5e-4 rad, which the fixture's start-to-goal shortcut misses after its two
// corrections where the blended raw steps land (a tolerance that also fails those falls back to
// the raw chain in both).
TEST(Execution, AFailedLookedShortcutRunsThePassesAgainWithSimulations) {
  const Fixture& f = fixture();
  const PathCase& c = long_path();
  ASSERT_TRUE(c.result.success) << c.result.failure;
  ExecutionOptions looked = options(true, true);
  looked.end_tolerance = 5e-4;
  ExecutionOptions simulated = looked;
  simulated.looked_shortcuts = false;
  const ExecutableTrajectory a = execute(f.sim, c, looked);
  const ExecutableTrajectory b = execute(f.sim, c, simulated);
  EXPECT_TRUE(a.stats.shortcuts_simulated_again);
  EXPECT_FALSE(b.stats.shortcuts_simulated_again);
  EXPECT_GT(a.stats.simulations, b.stats.simulations);
  EXPECT_EQ(a.stats.shortcuts, b.stats.shortcuts);
  EXPECT_EQ(a.stats.looked_blocked, b.stats.looked_blocked);
  EXPECT_EQ(a.stats.stops, b.stats.stops);
  EXPECT_TRUE(a.trajectory.q == b.trajectory.q && a.trajectory.dq == b.trajectory.dq &&
              a.trajectory.cmd == b.trajectory.cmd);
  EXPECT_EQ(resimulate_segments(f.sim, a, c.problem.start), "");
  EXPECT_EQ(checker_verdict(f.sim, a.trajectory), "");
}

// lazysp (with precheck, its default) looks at the straight command's line first: where the
// line is blocked it spends no simulation on it, where precheck is off it simulates it. A budget
// that has ended when the search would begin leaves only that attempt to count.
TEST(Execution, LazySpLooksAtTheStraightCommandBeforeSimulatingIt) {
  const Fixture& f = fixture();
  PlanningProblem p = problem_to(f.a, f.b);
  Obstructed o;
  ASSERT_TRUE(block_line(p, o)) << "no ball on the line clears the start and the goal";
  p.termination.budget = 1e-9;
  const PlanningContext context = bundle_context(*o.sim, f.view, f.index);
  SimulatorWorkspace ws(*o.sim);
  const PlanResult looked = plan(context, ws, "lazysp", {}, p);
  const PlanResult blind = plan(context, ws, "lazysp", {{"precheck", 0}}, p);
  EXPECT_FALSE(looked.success);
  EXPECT_EQ(looked.counters.simulations, 0u);
  EXPECT_GT(looked.counters.collision_checks, 0u);
  EXPECT_EQ(blind.counters.simulations, 1u);
}

TEST(Execution, DirectCommandIsAStraightLineWithinTheCommandLimits) {
  const Fixture& f = fixture();
  const ExecutionOptions o = options(true, true);
  const JointVector d = f.c - f.a;
  std::vector<double> times, knots;
  ASSERT_TRUE(direct_command(f.robot, o.limits, d, f.sim.dt, times, knots));
  const int n = f.robot.dof;
  const CommandProfile p{knots.data(), static_cast<int>(times.size()), n, times.back(),
                         times.data()};
  JointVector v(n), a(n), offset(n);
  evaluate_command(p, p.duration, v.data(), a.data(), offset.data());
  EXPECT_LE((offset - d).cwiseAbs().maxCoeff(), 1e-12);  // the whole displacement
  for (double t = 0; t < p.duration; t += 0.01) {
    evaluate_command(p, t, v.data(), a.data(), offset.data());
    // Proportional to the displacement: a straight line in joint space.
    EXPECT_LE((offset - d * (offset.dot(d) / d.squaredNorm())).norm(), 1e-12);
    EXPECT_LE((v.array().abs() - o.limits.velocity_scale * f.robot.dq_max.array()).maxCoeff(),
              1e-12);
    EXPECT_LE((a.array().abs() - o.limits.limit_scale * f.robot.ddq_max.array()).maxCoeff(), 1e-9);
  }
  EXPECT_FALSE(direct_command(f.robot, o.limits, JointVector::Zero(n), f.sim.dt, times, knots));
}

// Straight commands through points, their junction blended into one command with knot times
// (lazysp's shortcut): one rollout, its rows handed over, so that the post-processing keeps it
// without a simulation; shorter than the two commands from rest to rest.
TEST(Execution, ABlendedStepThroughPointsIsOneSimulatedCommand) {
  const Fixture& f = fixture();
  const ExecutionOptions o = options(true, true);
  PlanningProblem p = problem_to(f.a, f.b);
  JointVector via = 0.5 * (f.a + f.b);
  via[0] += 0.3;  // off the line a -> b: a corner to blend
  SimulatorWorkspace ws(f.sim);
  ASSERT_EQ(check_state(f.sim, ws, via), RolloutStatus::Valid);
  int simulations = 0;
  const std::optional<PathStep> step =
      blended_step_through(f.sim, ws, o, {f.a, via, f.b}, p.goal, &simulations);
  ASSERT_TRUE(step && step->outcome);
  ASSERT_TRUE(solves(f.sim, ws, *step, p.goal)) << rollout_status_name(step->outcome->status);
  EXPECT_GE(simulations, 1);
  const std::vector<double>& times = step->knot_times;
  ASSERT_EQ(times.size() * f.robot.dof, step->knots.size());
  EXPECT_TRUE(std::is_sorted(times.begin(), times.end()));
  EXPECT_EQ(times.back(), step->command_duration);
  // The evenly spaced knots of the same command would be another command.
  PathStep even = *step;
  even.knot_times.clear();
  EXPECT_NE(simulate(f.sim, ws, f.a, even.profile(f.robot.dof)).qf, step->outcome->qf);

  // Its own rollout, tick for tick: the command with its times.
  std::vector<double> rows;
  const RolloutResult again =
      simulate(f.sim, ws, f.a, step->profile(f.robot.dof), {nullptr, nullptr, 0, &rows});
  EXPECT_EQ(again.qf, step->outcome->qf);
  EXPECT_EQ(rows, step->outcome_rows);

  // From rest to rest through `via`, within the junction room, it takes longer.
  CommandSampling room = o.limits;
  room.limit_scale *= kJunctionRoom;
  Goal near_via;
  near_via.q = via;
  near_via.tolerance = 0.05;
  const std::optional<PathStep> first = direct_step_to(f.sim, ws, room, f.a, via, &near_via);
  ASSERT_TRUE(first && first->outcome->valid());
  const std::optional<PathStep> second =
      direct_step_to(f.sim, ws, room, first->outcome->qf, f.b, &p.goal);
  ASSERT_TRUE(second && second->outcome->valid());
  EXPECT_LT(step->outcome->duration, first->outcome->duration + second->outcome->duration);

  // The post-processing keeps it as it is: nothing simulated.
  const ExecutableTrajectory e = make_executable(f.sim, ws, p.start, {*step}, p.goal, o, 1);
  EXPECT_EQ(e.stats.simulations, 0);
  EXPECT_EQ(e.stats.simulated_ticks, 0);
  ASSERT_EQ(e.segments.size(), 1u);
  EXPECT_FALSE(e.segments[0].uniform);
  expect_executable(f.sim, e, p);
  // The raw chain simulates it with its times too.
  const Trajectory raw = realize_path(f.sim, ws, p.start, {*step}, p.goal, 1);
  EXPECT_EQ(raw.q.back(), step->outcome->qf);

  // Coinciding points make no command.
  EXPECT_FALSE(blended_step_through(f.sim, ws, o, {f.a, f.a, f.b}, p.goal));
}

TEST(Execution, KnotTimesEvaluateAsEvenSpacing) {
  const std::vector<double> knots = {0, 0, 0.3, -0.2, -0.1, 0.4, 0, 0};
  const std::vector<double> times = {0, 0.2, 0.4, 0.6};
  const CommandProfile even{knots.data(), 4, 2, 0.6};
  const CommandProfile timed{knots.data(), 4, 2, 0.6, times.data()};
  for (double t = 0; t <= 0.7; t += 0.013) {
    double v1[2], a1[2], o1[2], v2[2], a2[2], o2[2];
    evaluate_command(even, t, v1, a1, o1);
    evaluate_command(timed, t, v2, a2, o2);
    double v3[2], a3[2];
    evaluate_command(timed, t, v3, a3, nullptr);  // without the offset, as the simulator asks
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(v1[i], v2[i], 1e-12) << t;
      EXPECT_NEAR(a1[i], a2[i], 1e-9) << t;
      EXPECT_NEAR(o1[i], o2[i], 1e-12) << t;
      EXPECT_EQ(v3[i], v2[i]) << t;
      EXPECT_EQ(a3[i], a2[i]) << t;
    }
  }
}

}  // namespace
}  // namespace lazyboe::test
