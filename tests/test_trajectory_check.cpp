// The trajectory checker: real simulated trajectories from the small bundle pass, planted faults
// (a jerk spike, a velocity jump, a position jump, a torque over the limit, a configuration
// inside the table, a start or end not at rest) are caught at the right sample and joint, and
// lazyboe-robot validate-trajectory reports them, or a malformed file, in one line.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "alloc_counter.h"
#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/io/query_io.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/sim/trajectory_check.h"
#include "planning_fixture.h"

namespace lazyboe::test {
namespace {

struct Fixture : PlanningFixture {
  Fixture() : Fixture(build_small_bundles()) {}
  explicit Fixture(const SmallBundles& built)
      : PlanningFixture(built.perturbed,
                        BundleView::from_memory(built.perturbed, "the small bundle (in memory)")),
        checker(robot, collision) {}
  TrajectoryChecker checker;
};

const Fixture& fixture() { return shared_fixture<Fixture>(); }

// A trajectory as flat arrays, as the checker takes it.
struct Samples {
  int dof = 0;
  std::vector<double> t, q, dq;
  int size() const { return static_cast<int>(t.size()); }
  TrajectoryView view() const { return {size(), dof, t.data(), q.data(), dq.data()}; }
  double& qi(int k, int i) { return q[k * dof + i]; }
  double& dqi(int k, int i) { return dq[k * dof + i]; }
};

Samples samples_of(const Trajectory& traj) {
  Samples s;
  s.dof = static_cast<int>(traj.q[0].size());
  for (size_t k = 0; k < traj.t.size(); ++k) {
    s.t.push_back(traj.t[k]);
    for (int i = 0; i < s.dof; ++i) {
      s.q.push_back(traj.q[k][i]);
      s.dq.push_back(traj.dq[k][i]);
    }
  }
  return s;
}

Trajectory trajectory_of(const Samples& s) {
  Trajectory traj;
  for (int k = 0; k < s.size(); ++k) {
    traj.t.push_back(s.t[k]);
    traj.q.push_back(Eigen::Map<const Eigen::VectorXd>(&s.q[k * s.dof], s.dof));
    traj.dq.push_back(Eigen::Map<const Eigen::VectorXd>(&s.dq[k * s.dof], s.dof));
  }
  return traj;
}

TrajectoryCheckResult check(const Samples& s, const TrajectoryChecker& checker) {
  TrajectoryCheckWorkspace ws(checker);
  return check_trajectory(checker, ws, s.view());
}
TrajectoryCheckResult check(const Samples& s) { return check(s, fixture().checker); }

std::string text(const TrajectoryCheckResult& r) {
  return r.valid ? "valid" : describe_violation(fixture().checker, r.violation);
}

// One command simulated from q0 at rest, sampled at every control tick (as realize_path samples
// a path with --sample-interval 0.001: the exact start, float32 samples, the exact end).
Samples simulate_at_control_rate(const JointVectorRef& q0, const CommandProfile& profile) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  std::vector<float> sq, sdq;
  const RolloutResult r = simulate(f.sim, ws, q0, profile, {&sq, &sdq, 1});
  if (!r.valid()) throw std::runtime_error(std::string("rollout ") + rollout_status_name(r.status));
  Samples s;
  s.dof = f.robot.dof;
  const int rows = static_cast<int>(sq.size()) / s.dof;
  for (int k = 0; k < rows; ++k) {
    s.t.push_back(k * f.sim.dt);
    for (int i = 0; i < s.dof; ++i) {
      s.q.push_back(k == 0 ? q0[i] : k + 1 == rows ? r.qf[i] : sq[k * s.dof + i]);
      s.dq.push_back(k == 0 ? 0.0 : sdq[k * s.dof + i]);
    }
  }
  return s;
}

// Paths planned by lazysp between the fixture's states, realized at 1 kHz.
struct PlannedPath {
  std::vector<PathStep> steps;
  JointVector start;
  Trajectory trajectory;
};
const std::vector<PlannedPath>& planned_paths() {
  static const std::vector<PlannedPath> paths = [] {
    const Fixture& f = fixture();
    const PlanningContext context = bundle_context(f.sim, f.view, f.index);
    SimulatorWorkspace ws(f.sim);
    std::vector<PlannedPath> out;
    const std::vector<std::pair<JointVector, JointVector>> problems = {
        {f.a, f.b}, {f.b, f.a}, {f.a, f.c}, {f.c, f.a}, {f.b, f.c}, {f.c, f.b}};
    for (const auto& [start, goal] : problems) {
      PlanningProblem p;
      p.start = start;
      p.goal.kind = Goal::Kind::Joint;
      p.goal.q = goal;
      p.goal.tolerance = kTolerance;
      p.termination.budget = 5 * time_scale();  // the sanitizers slow the planners
      p.seed = 1;
      const PlanResult r = plan(context, ws, "lazysp", searching("lazysp"), p);
      if (!r.success) continue;
      out.push_back({r.best_path, start, realize_path(f.sim, ws, start, r.best_path, p.goal, 1)});
    }
    if (out.size() < 4) throw std::runtime_error("lazysp solved fewer than 4 easy problems");
    return out;
  }();
  return paths;
}

// A long real edge sampled at 1 kHz, for planting faults in.
const Samples& real_edge() {
  static const Samples s = [] {
    const PlannedPath& p = planned_paths()[0];
    const PathStep& step = p.steps[0];
    const int n = fixture().robot.dof;
    return simulate_at_control_rate(p.start, step.profile(n));
  }();
  return s;
}

// ------------------------------------------------------------------------------------------
// Real trajectories
// ------------------------------------------------------------------------------------------

TEST(TrajectoryCheck, EveryEdgeOfPlannedPathsPassesAtTheControlRate) {
  const Fixture& f = fixture();
  const int n = f.robot.dof;
  int edges = 0;
  for (const PlannedPath& p : planned_paths()) {
    JointVector q = p.start;
    for (const PathStep& step : p.steps) {
      const CommandProfile profile = step.profile(n);
      const Samples s = simulate_at_control_rate(q, profile);
      const TrajectoryCheckResult r = check(s);
      EXPECT_TRUE(r.valid) << "edge " << step.bundle_edge << ": " << text(r);
      // Real motion, not a trivial pass: the edges use a good part of the acceleration limit.
      EXPECT_GT(r.peak_fraction[static_cast<int>(TrajectoryLimit::Acceleration)], 0.05);
      EXPECT_GT(r.collision_checks, 1);
      q = Eigen::Map<const Eigen::VectorXd>(&s.q[(s.size() - 1) * n], n);
      ++edges;
    }
  }
  EXPECT_GE(edges, 8);
}

TEST(TrajectoryCheck, TwoHundredBundleEdgesResimulatedAtTheControlRatePass) {
  const Fixture& f = fixture();
  double peak_acceleration = 0;
  for (size_t e = 0; e < 200; ++e) {
    const TrajectoryCheckResult r =
        check(simulate_at_control_rate(f.edge_start(e), f.view.command(e)));
    EXPECT_TRUE(r.valid) << "edge " << e << ": " << text(r);
    peak_acceleration = std::max(peak_acceleration,
                                 r.peak_fraction[static_cast<int>(TrajectoryLimit::Acceleration)]);
  }
  EXPECT_GT(peak_acceleration, 0.3);
}

// The raw chain realized by realize_path restarts every edge from exact rest, while its
// junction sample keeps the previous edge's residual velocity (below the settle velocity,
// 1e-3 rad/s): the samples show that velocity vanishing in one tick, a torque step beyond the
// torque-rate limit for the heavy joints (docs/execution.md). Wherever a chain fails, it is
// there, and nowhere else.
TEST(TrajectoryCheck, RawChainsFailOnlyAtTheirJunctions) {
  const Fixture& f = fixture();
  for (const PlannedPath& p : planned_paths()) {
    const Samples s = samples_of(p.trajectory);
    const TrajectoryCheckResult r = check(s);
    if (r.valid) continue;
    std::vector<int> junctions;  // sample of each edge's end
    double t_end = 0;
    SimulatorWorkspace ws(f.sim);
    JointVector q = p.start;
    for (size_t k = 0; k + 1 < p.steps.size(); ++k) {
      const PathStep& step = p.steps[k];
      const CommandProfile profile = step.profile(7);
      const RolloutResult rr = simulate(f.sim, ws, q, profile);
      q = rr.qf;
      t_end += rr.duration;
      junctions.push_back(static_cast<int>(std::lround(t_end / f.sim.dt)));
    }
    bool at_junction = false;
    for (int j : junctions) at_junction |= std::abs(r.violation.sample - j) <= 1;
    EXPECT_TRUE(at_junction) << text(r);
    EXPECT_EQ(r.violation.limit, TrajectoryLimit::TorqueRate) << text(r);
  }
}

// The diagnosis: with a settle velocity small enough that the residual velocity can be stopped
// within one tick's torque-rate budget (|M dq| <= dtau_max dt^2, about 2.8e-4 rad/s for the
// Panda's heavy joints), the same chains pass.
TEST(TrajectoryCheck, RawChainsPassWithASettleVelocityWithinTheTorqueRateBudget) {
  const Fixture& f = fixture();
  SimulationOptions options = f.sim.options;
  options.settle_velocity = 2.5e-4;
  const Simulator strict(f.robot, f.collision, options);
  SimulatorWorkspace ws(strict);
  Goal anywhere;
  anywhere.kind = Goal::Kind::Joint;
  anywhere.q = f.a;
  anywhere.tolerance = 1e9;  // the ends move a little with the settle velocity
  int chains = 0;
  for (const PlannedPath& p : planned_paths()) {
    if (p.steps.size() < 2) continue;
    const Trajectory traj = realize_path(strict, ws, p.start, p.steps, anywhere, 1);
    const TrajectoryCheckResult r = check(samples_of(traj));
    EXPECT_TRUE(r.valid) << text(r);
    ++chains;
  }
  EXPECT_GE(chains, 1);
}

TEST(TrajectoryCheck, RefusesAnotherSpacingTooFewSamplesOrAnotherDof) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  const PlannedPath& p = planned_paths()[0];
  Goal goal;
  goal.kind = Goal::Kind::Joint;
  goal.q = p.trajectory.q.back();
  goal.tolerance = 1e-6;
  const Samples every_20ms = samples_of(realize_path(f.sim, ws, p.start, p.steps, goal, 20));
  EXPECT_EQ(first_bad_spacing(f.checker, every_20ms.view()), 1);
  try {
    check(every_20ms);
    ADD_FAILURE() << "a 20 ms spacing was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not the control period"), std::string::npos) << e.what();
  }
  Samples one = real_edge();
  one.t.resize(1);
  EXPECT_THROW(check(one), Error);
  Samples other = real_edge();
  other.dof = 6;
  EXPECT_THROW(check(other), Error);
}

TEST(TrajectoryCheck, AllocatesNothing) {
  const Samples& s = real_edge();
  TrajectoryCheckWorkspace ws(fixture().checker);
  LAZYBOE_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const long before = test::allocations.load();
  const TrajectoryCheckResult r = check_trajectory(fixture().checker, ws, s.view());
  EXPECT_EQ(test::allocations.load() - before, 0);
  EXPECT_TRUE(r.valid);
}

// ------------------------------------------------------------------------------------------
// Planted faults
// ------------------------------------------------------------------------------------------

// A sample k in the middle of the edge whose joint i accelerates gently around it.
int quiet_sample(const Samples& s, int i, double max_acceleration) {
  const double dt = fixture().sim.dt;
  for (int k = s.size() / 3; k + 2 < s.size(); ++k) {
    const Samples& c = s;
    const double a0 = (c.dq[k * c.dof + i] - c.dq[(k - 1) * c.dof + i]) / dt;
    const double a1 = (c.dq[(k + 1) * c.dof + i] - c.dq[k * c.dof + i]) / dt;
    if (std::abs(a0) < max_acceleration && std::abs(a1) < max_acceleration) return k;
  }
  return -1;
}

TEST(TrajectoryCheck, CatchesAJerkSpike) {
  const Fixture& f = fixture();
  const int i = 0;
  Samples s = real_edge();
  const int k = quiet_sample(s, i, 2.0);
  ASSERT_GT(k, 0);
  // A bump of 1.5 jerk-limit dt^2 in one velocity sample: the acceleration changes by 1.5
  // jerk-limit dt (11 of 15 rad/s^2 for joint 1) within one period, 1.5 times the jerk limit.
  s.dqi(k, i) += 1.5 * f.robot.dddq_max[i] * f.sim.dt * f.sim.dt;
  const TrajectoryCheckResult r = check(s);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::Jerk) << text(r);
  EXPECT_EQ(r.violation.joint, i) << text(r);
  EXPECT_EQ(r.violation.sample, k - 1) << text(r);
  EXPECT_DOUBLE_EQ(r.violation.time, s.t[k - 1]);
  EXPECT_GT(r.violation.value, 1.2 * f.robot.dddq_max[i]);
  EXPECT_EQ(r.violation.bound, f.robot.dddq_max[i]);
}

TEST(TrajectoryCheck, CatchesAVelocityJumpAsTheAccelerationItTakes) {
  const Fixture& f = fixture();
  const int i = 3;
  Samples s = real_edge();
  const int k = s.size() / 2;
  for (int m = k; m < s.size(); ++m) s.dqi(m, i) += 0.05;  // 0.05 rad/s in one tick: 50 rad/s^2
  const TrajectoryCheckResult r = check(s);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::Acceleration) << text(r);
  EXPECT_EQ(r.violation.joint, i) << text(r);
  EXPECT_EQ(r.violation.sample, k - 1) << text(r);
  EXPECT_NEAR(r.violation.value, 50.0, f.robot.ddq_max[i]);
}

TEST(TrajectoryCheck, CatchesAPositionJumpAsTheVelocityItTakes) {
  const Fixture& f = fixture();
  const int i = 1;
  Samples s = real_edge();
  const int k = s.size() / 2;
  for (int m = k; m < s.size(); ++m) s.qi(m, i) += 0.004;  // 4 mrad in one tick: 4 rad/s
  const TrajectoryCheckResult r = check(s);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::Velocity) << text(r);
  EXPECT_EQ(r.violation.joint, i) << text(r);
  EXPECT_EQ(r.violation.sample, k - 1) << text(r);
  EXPECT_GT(std::abs(r.violation.value), f.robot.dq_max[i]);
}

TEST(TrajectoryCheck, CatchesAStartOrAnEndNotAtRest) {
  const Samples& full = real_edge();
  const int n = full.dof, drop = full.size() / 4;
  Samples late = full;  // starts a quarter into the motion
  late.t.erase(late.t.begin(), late.t.begin() + drop);
  late.q.erase(late.q.begin(), late.q.begin() + drop * n);
  late.dq.erase(late.dq.begin(), late.dq.begin() + drop * n);
  TrajectoryCheckResult r = check(late);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::StartAtRest) << text(r);
  EXPECT_EQ(r.violation.sample, 0);
  int moving = 0;
  while (std::abs(late.dq[moving]) <= 1e-3) ++moving;
  EXPECT_EQ(r.violation.joint, moving);

  Samples early = full;  // stops being sampled half way
  const int keep = full.size() / 2;
  early.t.resize(keep);
  early.q.resize(keep * n);
  early.dq.resize(keep * n);
  r = check(early);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::EndAtRest) << text(r);
  EXPECT_EQ(r.violation.sample, keep - 1);
}

// Rest to rest by the minimum-jerk polynomial, sampled exactly at the control rate.
Samples min_jerk_motion(const JointVector& q0, const JointVector& q1, double duration) {
  const double dt = fixture().sim.dt;
  Samples s;
  s.dof = static_cast<int>(q0.size());
  const int ticks = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k <= ticks; ++k) {
    const double x = static_cast<double>(k) / ticks;
    const double p = x * x * x * (10 - 15 * x + 6 * x * x);
    const double v = 30 * x * x * (1 - x) * (1 - x) / duration;
    s.t.push_back(k * dt);
    for (int i = 0; i < s.dof; ++i) {
      s.q.push_back(q0[i] + p * (q1[i] - q0[i]));
      s.dq.push_back(v * (q1[i] - q0[i]));
    }
  }
  return s;
}

TEST(TrajectoryCheck, CatchesAConfigurationInsideTheTable) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  // Lean forward (joint 2) from the fixture's start until the arm is well inside the table.
  JointVector inside = f.a;
  while (check_state(f.sim, ws, inside) != RolloutStatus::EnvCollision) {
    inside[1] += 0.02;
    ASSERT_LT(inside[1], f.robot.q_max[1]) << "the arm never reaches the table";
  }
  inside[1] += 0.1;
  const Samples s = min_jerk_motion(f.a, inside, 2.0);

  // Within every limit: with no obstacles the motion is valid.
  const CollisionModel no_obstacles = build_collision_model(f.robot, Environment{});
  const TrajectoryChecker free_checker(f.robot, no_obstacles);
  const TrajectoryCheckResult free = check(s, free_checker);
  ASSERT_TRUE(free.valid) << describe_violation(free_checker, free.violation);

  const TrajectoryCheckResult r = check(s);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::EnvCollision) << text(r);
  EXPECT_LT(r.violation.value, f.collision.margin);
  const std::string message = text(r);
  EXPECT_NE(message.find("obstacle '"), std::string::npos) << message;
  EXPECT_NE(message.find("panda_link"), std::string::npos) << message;
  // No sample before the first one in collision is reported, and that one is found within the
  // check spacing (at most one margin of motion later).
  int first = 0;
  while (check_state(f.sim, ws, Eigen::Map<const Eigen::VectorXd>(&s.q[first * 7], 7)) ==
         RolloutStatus::Valid)
    ++first;
  EXPECT_GE(r.violation.time, s.t[first - 1]) << message;
  EXPECT_LE(r.violation.time, s.t[first] + 0.1) << message;
}

TEST(TrajectoryCheck, CatchesATorqueOverTheLimit) {
  const Fixture& f = fixture();
  // The arm stretched out with joint 2 near -1.5 rad: gravity and the accelerations of every
  // joint within their limits, each in the direction that loads joint 2, need more than its
  // 87 Nm. A smooth ramp into those accelerations (well within the jerk and torque-rate limits)
  // passes 87 Nm on joint 2 before anything else breaks.
  const int n = f.robot.dof;
  JointVector q0(n);
  q0 << -0.528, -1.503, 2.734, -0.600, 0.474, 2.277, 0.775;
  RobotData rd(f.robot);
  mass_matrix(f.robot, rd, q0);
  const JointMatrix M = rd.M;
  const double g2 = gravity_torques(f.robot, rd, q0)[1];
  JointVector A(n);
  for (int j = 0; j < n; ++j) A[j] = (M(1, j) * g2 >= 0 ? 1 : -1) * 0.95 * f.robot.ddq_max[j];
  const double T = 0.15, dt = f.sim.dt;
  Samples s;
  s.dof = n;
  for (int k = 0; k <= 200; ++k) {
    const double t = k * dt, x = std::min(t / T, 1.0), rest = std::max(t - T, 0.0);
    const double v_ramp = T * (x * x * x - x * x * x * x / 2);
    const double p_ramp = T * T * (x * x * x * x / 4 - x * x * x * x * x / 10);
    s.t.push_back(t);
    for (int i = 0; i < n; ++i) {
      s.q.push_back(q0[i] + A[i] * (p_ramp + v_ramp * rest + rest * rest / 2));
      s.dq.push_back(A[i] * (v_ramp + rest));
    }
  }
  TrajectoryCheckOptions no_collision;
  no_collision.check_collision = false;  // the stretched arm is not what this test is about
  const TrajectoryChecker checker(f.robot, f.collision, no_collision);
  const TrajectoryCheckResult r = check(s, checker);
  ASSERT_FALSE(r.valid);
  EXPECT_EQ(r.violation.limit, TrajectoryLimit::Torque) << describe_violation(checker, r.violation);
  EXPECT_EQ(r.violation.joint, 1);
  // The torque of the period, recomputed with the reference inverse dynamics (Newton-Euler,
  // friction included) at the period's middle state and mean acceleration.
  const int k = r.violation.sample;
  auto at = [&](const std::vector<double>& v, int m) {
    return Eigen::Map<const Eigen::VectorXd>(&v[m * n], n);
  };
  const JointVector tau =
      inverse_dynamics(f.robot, rd, (at(s.q, k) + at(s.q, k + 1)) / 2,
                       (at(s.dq, k) + at(s.dq, k + 1)) / 2, (at(s.dq, k + 1) - at(s.dq, k)) / dt);
  EXPECT_NEAR(r.violation.value, tau[1], 1e-9);
  EXPECT_GT(std::abs(tau[1]), f.robot.tau_max[1]);
  const JointVector before =
      inverse_dynamics(f.robot, rd, (at(s.q, k - 1) + at(s.q, k)) / 2,
                       (at(s.dq, k - 1) + at(s.dq, k)) / 2, (at(s.dq, k) - at(s.dq, k - 1)) / dt);
  EXPECT_LE(std::abs(before[1]), f.robot.tau_max[1]);
}

// ------------------------------------------------------------------------------------------
// lazyboe-robot validate-trajectory
// ------------------------------------------------------------------------------------------

// The trajectories here are planned in the bundled table scene (named by name); `extra` may name
// another.
CommandResult validate_cli(const std::string& csv, const std::string& extra = "--env table") {
  return run(quote(tool_path("lazyboe-robot")) + " validate-trajectory --in " + quote(csv) + " " +
             extra);
}

TEST(ValidateTrajectoryCli, PrintsValidWithASummaryForARealEdge) {
  const std::string csv = fresh_dir("valid") + "/edge.csv";
  write_trajectory_csv(csv, trajectory_of(real_edge()));
  const CommandResult r = validate_cli(csv);
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(count_lines(r.out), 1) << describe(r);
  EXPECT_TRUE(contains(r.out, "; scene table")) << describe(r);
  EXPECT_TRUE(contains(r.out, "valid: " + std::to_string(real_edge().size()) + " samples"))
      << describe(r);
  for (const char* limit : {"position", "velocity", "acceleration", "jerk", "torque rate"})
    EXPECT_TRUE(contains(r.out, limit)) << describe(r);
}

TEST(ValidateTrajectoryCli, ReadsFurtherColumns) {
  const std::string dir = fresh_dir("columns");
  const std::string plain = dir + "/plain.csv", wide = dir + "/wide.csv";
  write_trajectory_csv(plain, trajectory_of(real_edge()));
  std::ifstream in(plain);
  std::ofstream out(wide);
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    out << line;
    for (int i = 1; i <= 7; ++i) out << (header ? ",ddq" + std::to_string(i) : ",0");
    for (int i = 1; i <= 7; ++i) out << (header ? ",cmd" + std::to_string(i) : ",0.5");
    out << "\n";
    header = false;
  }
  out.close();
  const CommandResult r = validate_cli(wide);
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "valid: ")) << describe(r);
}

TEST(ValidateTrajectoryCli, PrintsTheFirstViolationWithTimeAndJointAndFails) {
  const Fixture& f = fixture();
  Samples s = real_edge();
  const int k = quiet_sample(s, 0, 2.0);
  ASSERT_GT(k, 0);
  s.dqi(k, 0) += 1.5 * f.robot.dddq_max[0] * f.sim.dt * f.sim.dt;
  const std::string csv = fresh_dir("jerk") + "/jerk.csv";
  write_trajectory_csv(csv, trajectory_of(s));
  const CommandResult r = validate_cli(csv);
  EXPECT_EQ(r.exit_code, 3) << describe(r);
  EXPECT_EQ(count_lines(r.out), 1) << describe(r);
  char time[32];
  std::snprintf(time, sizeof time, "t = %.6g s", s.t[k - 1]);
  for (const std::string& needle :
       {std::string("invalid: jerk_limit"), std::string(time), std::string("joint 1"),
        std::string("panda_joint1"), "line " + std::to_string(k + 1)})
    EXPECT_TRUE(contains(r.out, needle)) << "no '" << needle << "' in " << describe(r);
}

TEST(ValidateTrajectoryCli, NamesTheTableAndTheLinkOfACollision) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  JointVector inside = f.a;
  while (check_state(f.sim, ws, inside) != RolloutStatus::EnvCollision) inside[1] += 0.02;
  const std::string csv = fresh_dir("collision") + "/table.csv";
  write_trajectory_csv(csv, trajectory_of(min_jerk_motion(f.a, inside, 2.0)));
  const CommandResult r = validate_cli(csv);
  EXPECT_EQ(r.exit_code, 3) << describe(r);
  EXPECT_TRUE(contains(r.out, "invalid: env_collision")) << describe(r);
  EXPECT_TRUE(contains(r.out, "obstacle '")) << describe(r);
  // The same motion with no obstacles is valid.
  const CommandResult free =
      validate_cli(csv, "--env " + quote(source_path("data/environments/empty.json")));
  EXPECT_EQ(free.exit_code, 0) << describe(free);
}

TEST(ValidateTrajectoryCli, AMalformedFileGetsOneLineNamingFileAndLine) {
  const std::string dir = fresh_dir("malformed");
  const std::string good = dir + "/good.csv";
  write_trajectory_csv(good, trajectory_of(real_edge()));
  std::vector<std::string> lines;
  {
    std::ifstream in(good);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  auto variant = [&](const std::string& name, int line_index, const std::string& replacement) {
    std::vector<std::string> v = lines;
    v[line_index] = replacement;
    std::string bytes;
    for (const std::string& l : v) bytes += l + "\n";
    write_bytes(dir + "/" + name, bytes);
    return dir + "/" + name;
  };
  std::string row5 = lines[4];
  row5.replace(row5.find(','), 1, ",abc,");  // one cell too many
  std::string text5 = lines[4];
  const size_t q1 = text5.find(',') + 1;
  text5.replace(q1, text5.find(',', q1) - q1, "x");  // q1 is not a number
  const std::string text_cell = variant("text.csv", 4, text5);
  expect_one_line_error(validate_cli(text_cell), {text_cell + ":5", "not a number"});
  const std::string wide_row = variant("row.csv", 4, row5);
  expect_one_line_error(validate_cli(wide_row), {wide_row + ":5", "columns"});
  const std::string header = variant("header.csv", 0, "t,q1,q2,q3,q4,q5,q6,q7,v1,v2");
  expect_one_line_error(validate_cli(header), {header + ":1", "t,q1,"});
  // A sample 20 ms after the one before instead of 1 ms.
  const std::string gap = variant("gap.csv", 10, "0.029" + lines[10].substr(lines[10].find(',')));
  expect_one_line_error(validate_cli(gap), {gap + ":11", "control period"});
  expect_one_line_error(validate_cli(dir + "/missing.csv"), {dir + "/missing.csv"});
  // The scene is named, never guessed (issue 30: a shelf trajectory passed against the table).
  expect_one_line_error(validate_cli(gap, ""), {"--env", "name the scene"});
  write_bytes(dir + "/empty.csv", "");
  expect_one_line_error(validate_cli(dir + "/empty.csv"), {dir + "/empty.csv", "empty"});
}

// lazyboe-query's own CSV at --sample-interval 0.001 is what the checker reads: a one-edge
// path passes, and a chain fails, if at all, at the torque rate of a junction (see above).
TEST(ValidateTrajectoryCli, ChecksLazyboeQueryOutputAtOneKilohertz) {
  const Fixture& f = fixture();
  const std::string dir = fresh_dir("query");
  write_bundle(dir + "/bundle.h5", f.data);
  std::string queries;
  const std::vector<std::pair<JointVector, JointVector>> problems = {{f.a, f.b}, {f.a, f.c}};
  for (size_t i = 0; i < problems.size(); ++i) {
    queries += "{\"id\": \"q" + std::to_string(i) +
               "\", \"planner\": \"lazysp\", \"start\": " + str(problems[i].first) +
               ", \"goal\": {\"q\": " + str(problems[i].second) +
               ", \"tolerance\": " + std::to_string(kTolerance) + "}, \"seed\": 1}\n";
  }
  write_bytes(dir + "/queries.jsonl", queries);
  const CommandResult q = run(
      quote(tool_path("lazyboe-query")) + " --bundle " + quote(dir + "/bundle.h5") + " --queries " +
      quote(dir + "/queries.jsonl") + " --out " + quote(dir + "/results.jsonl") +
      " --trajectories csv " + "--trajectory-dir " + quote(dir) + " --sample-interval 0.001");
  ASSERT_EQ(q.exit_code, 0) << describe(q);
  for (size_t i = 0; i < problems.size(); ++i) {
    const std::string csv = dir + "/q" + std::to_string(i) + ".csv";
    const CommandResult r = validate_cli(csv);
    EXPECT_EQ(count_lines(r.out), 1) << describe(r);
    if (r.exit_code == 0) continue;
    EXPECT_EQ(r.exit_code, 3) << describe(r);
    EXPECT_TRUE(contains(r.out, "invalid: torque_rate_limit")) << describe(r);
  }
}

}  // namespace
}  // namespace lazyboe::test
