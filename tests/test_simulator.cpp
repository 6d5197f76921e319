// The simulator: command profiles within the limits at 1 kHz, rollouts that start and end at
// rest, dynamics (not kinematics) deciding the end state, collision checks dense enough, limit
// violations caught, determinism, resumable generation, and no allocation per rollout.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

#include "alloc_counter.h"
#include "lazyboe/bundle/builder.h"
#include "lazyboe/common/error.h"
#include "lazyboe/sim/rollout_pool.h"
#include "lazyboe/sim/simulator.h"
#include "test_util.h"

namespace lazyboe {
namespace {

using test::Scene;

BuildSettings default_settings(const RobotModel& robot) {
  BuildSettings s;
  s.region_lower = robot.region.lower;
  s.region_upper = robot.region.upper;
  return s;
}

CommandProfile view(const EdgeAttempt& e, int dof) {
  return CommandProfile{e.knots.data(), static_cast<int>(e.knots.size() / dof), dof,
                        e.command_duration};
}

TEST(CommandProfile, StartsAndEndsAtRestWithinLimitsAtControlRate) {
  const RobotModel& robot = test::panda();
  const CommandSampling sampling;
  std::vector<double> knots;
  const double dt = 1.0 / robot.control_rate;
  for (uint64_t k = 0; k < 200; ++k) {
    Random rng(3, k);
    const double T = sample_command_profile(robot, sampling, rng, knots);
    ASSERT_GE(T, sampling.min_duration);
    ASSERT_LE(T, sampling.max_duration);
    const CommandProfile p{knots.data(), static_cast<int>(knots.size() / 7), 7, T};
    double v[7], a[7], off[7], v_prev[7] = {0}, a_prev[7] = {0}, integral[7] = {0};
    for (int i = 0; i < 7; ++i) {
      EXPECT_EQ(knots[i], 0.0);
      EXPECT_EQ(knots[(p.n_knots - 1) * 7 + i], 0.0);
    }
    const int ticks = static_cast<int>(T / dt) + 2;
    for (int tick = 0; tick <= ticks; ++tick) {
      // The position offset is the exact integral of the velocity: compare with a fine
      // trapezoid sum over this tick (error ~1e-9).
      if (tick > 0) {
        double vf[7], af[7], of[7], va[7];
        evaluate_command(p, (tick - 1) * dt, va, af, of);
        for (int sub = 1; sub <= 20; ++sub) {
          evaluate_command(p, (tick - 1 + sub / 20.0) * dt, vf, af, of);
          for (int i = 0; i < 7; ++i) {
            integral[i] += 0.5 * (va[i] + vf[i]) * dt / 20;
            va[i] = vf[i];
          }
        }
      }
      evaluate_command(p, tick * dt, v, a, off);
      double v_alone[7], a_alone[7];
      evaluate_command(p, tick * dt, v_alone, a_alone, nullptr);  // the simulator's call
      for (int i = 0; i < 7; ++i) {
        EXPECT_EQ(v_alone[i], v[i]);
        EXPECT_EQ(a_alone[i], a[i]);
        EXPECT_LE(std::abs(v[i]), robot.dq_max[i]);
        // Finite differences at 1 kHz, as the robot's controller checks the stream.
        const double acc = (v[i] - v_prev[i]) / dt, jerk = (acc - a_prev[i]) / dt;
        EXPECT_LE(std::abs(acc), sampling.limit_scale * robot.ddq_max[i] * 1.001)
            << "tick " << tick;
        EXPECT_LE(std::abs(jerk), sampling.limit_scale * robot.dddq_max[i] * 1.001)
            << "tick " << tick;
        EXPECT_NEAR(a[i], acc, robot.dddq_max[i] * dt);
        EXPECT_NEAR(off[i], integral[i], 1e-7);
        v_prev[i] = v[i];
        a_prev[i] = acc;
      }
    }
    for (int i = 0; i < 7; ++i) EXPECT_EQ(v[i], 0.0);
  }
}

TEST(Simulator, ValidRolloutsStartAndEndAtRestAndStayCollisionFree) {
  SimulationOptions options;
  options.sample_every = 1;  // every tick, to re-check them all below
  Scene scene("table", options);
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  int valid = 0;
  for (uint64_t a = 0; a < 60; ++a) {
    EdgeAttempt e;
    generate_edge(scene.sim, ws, settings, a, e);
    if (!e.valid()) continue;
    ++valid;
    const size_t rows = e.sample_q.size() / 7;
    ASSERT_GE(rows, 2u);
    for (int i = 0; i < 7; ++i) {
      EXPECT_EQ(e.sample_dq[i], 0.0f);  // starts at rest
      EXPECT_LE(std::abs(e.sample_dq[(rows - 1) * 7 + i]),
                scene.sim.options.settle_velocity * 1.0001);
      EXPECT_FLOAT_EQ(e.sample_q[(rows - 1) * 7 + i], static_cast<float>(e.qf[i]));
    }
    EXPECT_GT(e.duration, e.command_duration);  // includes settling
    // Every simulated tick is collision-free and within the limits: the sparse checks missed
    // nothing.
    for (size_t r = 0; r < rows; ++r) {
      JointVector q(7);
      for (int i = 0; i < 7; ++i) q[i] = e.sample_q[r * 7 + i];
      EXPECT_EQ(check_state(scene.sim, ws, q), RolloutStatus::Valid)
          << "attempt " << a << " row " << r;
    }
  }
  EXPECT_GT(valid, 40);
}

// A pool's rollouts are the simulator's, each in its own slot, whatever the thread count and
// however often the pool is reused; some of these attempts are invalid (collisions, limits), so
// early exits are mixed in.
TEST(RolloutPool, GivesEachTaskTheSimulatorsResultInItsSlot) {
  Scene scene("table");
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  std::vector<EdgeAttempt> attempts(24);
  std::vector<RolloutTask> tasks;
  for (size_t a = 0; a < attempts.size(); ++a) {
    generate_edge(scene.sim, ws, settings, a, attempts[a]);
    tasks.push_back({attempts[a].q0.data(), view(attempts[a], 7)});
  }
  std::vector<RolloutResult> expected;
  int invalid = 0;
  for (const RolloutTask& t : tasks) {
    expected.push_back(
        simulate(scene.sim, ws, Eigen::Map<const Eigen::VectorXd>(t.q0, 7), t.command));
    invalid += !expected.back().valid();
  }
  for (int threads : {1, 2, 5}) {
    SCOPED_TRACE(threads);
    RolloutPool pool(scene.sim, threads);
    // One pool, batch after batch (its workers wait between them), of several sizes.
    uint64_t run = 0;
    for (int count : {24, 1, 0, 7, 24, 2}) {
      SCOPED_TRACE(count);
      std::vector<RolloutResult> got(count);
      const size_t first = count == 24 ? 0 : 24 - count;  // the short batches: the last tasks
      pool.run(scene.sim, tasks.data() + first, got.data(), count);
      run += count;
      EXPECT_EQ(pool.rollouts(), run);
      for (int i = 0; i < count; ++i) {
        const size_t k = first + i;
        EXPECT_EQ(got[i].status, expected[k].status) << "task " << k;
        EXPECT_EQ(got[i].ticks, expected[k].ticks) << "task " << k;
        EXPECT_EQ(got[i].collision_checks, expected[k].collision_checks) << "task " << k;
        EXPECT_EQ(got[i].path_length, expected[k].path_length) << "task " << k;
        EXPECT_TRUE(got[i].qf == expected[k].qf) << "task " << k;
      }
    }
  }
  EXPECT_GT(invalid, 0) << "no invalid rollout among the tasks: early exits untested";
  EXPECT_THROW(RolloutPool(scene.sim, 0), Error);  // no threads
}

TEST(Simulator, EndStateComesFromTheDynamics) {
  Scene scene("empty");
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  EdgeAttempt e;
  uint64_t a = 0;
  do generate_edge(scene.sim, ws, settings, a++, e);
  while (!e.valid());
  const CommandProfile p = view(e, 7);
  double v[7], acc[7], off[7];
  evaluate_command(p, 1e9, v, acc, off);
  JointVector kinematic = e.q0;
  for (int i = 0; i < 7; ++i) kinematic[i] += off[i];
  // Not a kinematic integration of the commands...
  EXPECT_GT((e.qf - kinematic).norm(), 1e-4);
  // ...but close to it (the controller tracks the commands).
  EXPECT_LT((e.qf - kinematic).norm(), 0.1 * (e.qf - e.q0).norm());
  // The same commands from a shifted start do not simply shift the end state.
  JointVector shifted = e.q0;
  shifted[1] += 0.05;
  shifted[3] -= 0.05;
  const RolloutResult r = simulate(scene.sim, ws, shifted, p);
  ASSERT_TRUE(r.valid());
  const double nonlinear = ((r.qf - e.qf) - (shifted - e.q0)).norm();
  EXPECT_GT(nonlinear, 1e-6);
  EXPECT_LT(nonlinear, 0.05);
}

TEST(Simulator, ReplayingAStoredEdgeReproducesItExactly) {
  Scene scene("table");
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  for (uint64_t a = 0; a < 20; ++a) {
    EdgeAttempt e;
    generate_edge(scene.sim, ws, settings, a, e);
    const RolloutResult r = simulate(scene.sim, ws, e.q0, view(e, 7));
    EXPECT_EQ(r.status, e.status);
    if (e.valid()) {
      EXPECT_EQ(r.qf, e.qf);
      EXPECT_EQ(r.duration, e.duration);
    }
  }
}

// Resumes `other` from the checkpoint of `e`'s rollout at tick `at` and compares it with
// `other` simulated from the start: status, end, counters and every tick row. Counts the
// comparisons made and those whose full rollout is invalid.
void expect_resumed_is_full(const Simulator& sim, SimulatorWorkspace& ws, const JointVector& q0,
                            const CommandProfile& first, const CommandProfile& other, int at,
                            int& resumed, int& invalid_after) {
  std::vector<double> first_rows;
  const std::vector<int> save_at = {at / 2, at, at};  // a repeated tick is saved once
  std::vector<RolloutCheckpoint> saved;
  const RolloutResult r0 =
      simulate(sim, ws, q0, first, {nullptr, nullptr, 0, &first_rows}, {nullptr, &save_at, &saved});
  if (r0.ticks < at) return;  // it ended before: nothing to go on from
  ASSERT_EQ(saved.size(), 2u);
  ASSERT_EQ(saved[1].tick, at);
  const RolloutCheckpoint& checkpoint = saved[1];
  std::vector<double> full_rows,
      rows(first_rows.begin(), first_rows.begin() + checkpoint.tick_values);
  const RolloutResult full = simulate(sim, ws, q0, other, {nullptr, nullptr, 0, &full_rows});
  const RolloutResult r = simulate(sim, ws, q0, other, {nullptr, nullptr, 0, &rows}, {&checkpoint});
  EXPECT_EQ(r.status, full.status);
  EXPECT_EQ(r.qf, full.qf);
  EXPECT_EQ(r.ticks, full.ticks);
  EXPECT_EQ(r.collision_checks, full.collision_checks);
  EXPECT_EQ(r.path_length, full.path_length);
  EXPECT_EQ(rows, full_rows);
  ++resumed;
  invalid_after += !full.valid();
}

// A rollout that goes on from a checkpoint of another rollout, whose command agreed with its
// own before the checkpoint, is the full rollout bit for bit. Commands changed in their last
// moving knot (as a correction changes a command's last knots), some of them colliding or
// breaking a limit after the change; evenly spaced knots in the table scene, and uneven knot
// times with end-effector speed and acceleration limits (the tracker's state is carried too).
TEST(Simulator, ARolloutResumedFromACheckpointIsTheFullRollout) {
  Scene scene("table");
  EndEffectorLimits hand;
  hand.link = scene.robot.tip_link();
  hand.max_linear_speed = 0.6;          // m/s: some changed commands break it
  hand.max_linear_acceleration = 15.0;  // m/s^2
  const Simulator limited(scene.robot, scene.collision, scene.sim.options, hand);
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  int resumed[2] = {0, 0}, invalid_after[2] = {0, 0};
  for (uint64_t a = 0; a < 80; ++a) {
    SCOPED_TRACE("attempt " + std::to_string(a));
    EdgeAttempt e;
    generate_edge(scene.sim, ws, settings, a, e);
    if (!e.valid()) continue;
    const int knots = static_cast<int>(e.knots.size() / 7);
    const int changed = knots - 2;  // the last moving knot changes (knot 0 and the end rest)
    if (changed < 2) continue;
    EdgeAttempt other = e;
    for (int k = changed; k + 1 < knots; ++k)
      for (int i = 0; i < 7; ++i) other.knots[k * 7 + i] *= a % 3 == 0 ? 2.5 : 0.8;
    const double h = e.command_duration / (knots - 1);
    expect_resumed_is_full(scene.sim, ws, e.q0, view(e, 7), view(other, 7),
                           ticks_before(scene.sim, (changed - 1) * h), resumed[0],
                           invalid_after[0]);
    std::vector<double> times(knots);  // uneven: interior knots moved by up to 0.3 h
    for (int k = 0; k < knots; ++k)
      times[k] = k == 0 || k + 1 == knots ? k * h : (k + 0.3 * std::sin(3.0 * k + a)) * h;
    CommandProfile timed = view(e, 7), timed_other = view(other, 7);
    timed.times = timed_other.times = times.data();
    expect_resumed_is_full(limited, ws, e.q0, timed, timed_other,
                           ticks_before(limited, times[changed - 1]), resumed[1], invalid_after[1]);
  }
  for (int v = 0; v < 2; ++v) {
    EXPECT_GT(resumed[v], 10) << "variant " << v;
    EXPECT_GT(invalid_after[v], 0) << "variant " << v;  // violations after it are found too
  }
}

// A rollout stopped where its command ends (RolloutResume::stop_at, after the checkpoint due
// there) is valid so far and `stopped`, at that tick; going on from that checkpoint gives the
// full rollout bit for bit (the settle the post-processing predicts before it simulates it).
TEST(Simulator, ARolloutStoppedAtATickGoesOnToTheFullRollout) {
  Scene scene("table");
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  int compared = 0;
  for (uint64_t a = 0; a < 20; ++a) {
    SCOPED_TRACE("attempt " + std::to_string(a));
    EdgeAttempt e;
    generate_edge(scene.sim, ws, settings, a, e);
    if (!e.valid()) continue;
    const int end = ticks_before(scene.sim, e.command_duration);
    const std::vector<int> save_at = {end};
    std::vector<RolloutCheckpoint> saved;
    std::vector<double> rows, full_rows;
    const RolloutResult part =
        simulate(scene.sim, ws, e.q0, view(e, 7), {nullptr, nullptr, 0, &rows},
                 {nullptr, &save_at, &saved, end});
    EXPECT_TRUE(part.valid() && part.stopped);
    EXPECT_EQ(part.ticks, end);
    ASSERT_EQ(saved.size(), 1u);
    EXPECT_EQ(part.qf, saved[0].q);
    const RolloutResult full =
        simulate(scene.sim, ws, e.q0, view(e, 7), {nullptr, nullptr, 0, &full_rows});
    const RolloutResult rest =
        simulate(scene.sim, ws, e.q0, view(e, 7), {nullptr, nullptr, 0, &rows}, {&saved[0]});
    EXPECT_FALSE(full.stopped || rest.stopped);
    EXPECT_EQ(rest.status, full.status);
    EXPECT_EQ(rest.qf, full.qf);
    EXPECT_EQ(rest.ticks, full.ticks);
    EXPECT_EQ(rest.collision_checks, full.collision_checks);
    EXPECT_EQ(rows, full_rows);
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

TEST(Simulator, ViolationsAreCaught) {
  // Into the table: a start right above it and a command driving joint 2 forward.
  Scene scene("table");
  SimulatorWorkspace ws(scene.sim);
  JointVector q0(7);
  q0 << 0, 0.55, 0, -1.6, 0, 2.1, 0.8;
  ASSERT_EQ(check_state(scene.sim, ws, q0), RolloutStatus::Valid);
  std::vector<double> knots(5 * 7, 0.0);
  for (int k = 1; k < 4; ++k) knots[k * 7 + 1] = 0.8;  // shoulder forward
  const CommandProfile down{knots.data(), 5, 7, 1.2};
  EXPECT_EQ(simulate(scene.sim, ws, q0, down).status, RolloutStatus::EnvCollision);

  // Beyond the velocity limit: knots above dq_max on joint 1.
  Scene empty("empty");
  SimulatorWorkspace ws2(empty.sim);
  JointVector ready(7);
  ready << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  std::vector<double> fast(3 * 7, 0.0);
  fast[7 + 0] = 2.5;  // dq_max is 2.175
  const CommandProfile too_fast{fast.data(), 3, 7, 3.0};
  EXPECT_EQ(simulate(empty.sim, ws2, ready, too_fast).status, RolloutStatus::VelocityLimit);

  // A sudden step in the command breaks acceleration/jerk continuity.
  std::vector<double> step(3 * 7, 0.0);
  step[7 + 5] = 1.5;
  const CommandProfile abrupt{step.data(), 3, 7, 0.02};
  const RolloutStatus s = simulate(empty.sim, ws2, ready, abrupt).status;
  EXPECT_TRUE(s == RolloutStatus::JerkLimit || s == RolloutStatus::AccelerationLimit ||
              s == RolloutStatus::TorqueRateLimit)
      << rollout_status_name(s);

  // Torque limit: the same gentle motion with the wrist's effort limit cut to 0.01 Nm.
  RobotModel weak = test::panda();
  weak.tau_max[1] = 0.5;  // cannot hold the shoulder against gravity
  const Simulator weak_sim(weak, empty.collision, {});
  SimulatorWorkspace ws3(weak_sim);
  std::vector<double> gentle(3 * 7, 0.0);
  gentle[7 + 0] = 0.1;
  const CommandProfile slow{gentle.data(), 3, 7, 0.5};
  EXPECT_EQ(simulate(weak_sim, ws3, ready, slow).status, RolloutStatus::TorqueLimit);
}

TEST(Simulator, RolloutAllocatesNothingWithReservedSamples) {
  Scene scene("table");
  SimulatorWorkspace ws(scene.sim);
  const BuildSettings settings = default_settings(scene.robot);
  EdgeAttempt e;
  e.knots.reserve(64);
  e.sample_q.reserve(4096);
  e.sample_dq.reserve(4096);
  generate_edge(scene.sim, ws, settings, 0, e);  // warm-up sizes q0/qf
  LAZYBOE_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const long before = test::allocations.load();
  for (uint64_t a = 1; a < 20; ++a) generate_edge(scene.sim, ws, settings, a, e);
  EXPECT_EQ(test::allocations.load() - before, 0);
}

// The bundle's contents depend only on (seed, attempt): any thread count, and a build stopped
// and resumed, give the same edges.
TEST(Builder, DeterministicAcrossThreadsAndResumable) {
  Scene scene("table");
  BuildSettings settings = default_settings(scene.robot);
  settings.edges = 150;
  settings.seed = 9;
  auto build = [&](int threads, int stop_after_rounds) {
    Bundle b = new_bundle(scene.robot, scene.env, settings);
    BuildControl control;
    control.threads = threads;
    control.quiet = true;
    int polls = 0;
    control.stop_requested = [&] { return stop_after_rounds >= 0 && polls++ >= stop_after_rounds; };
    if (build_bundle(scene.sim, settings, b, control) == BuildOutcome::Interrupted) {
      EXPECT_FALSE(b.header.complete);
      EXPECT_LT(b.size(), settings.edges);
      control.stop_requested = nullptr;
      EXPECT_EQ(build_bundle(scene.sim, settings, b, control), BuildOutcome::Complete);
    }
    EXPECT_TRUE(b.header.complete);
    return b;
  };
  const Bundle one = build(1, -1), two = build(2, -1), resumed = build(2, 1);
  for (const Bundle* other : {&two, &resumed}) {
    ASSERT_EQ(other->size(), 150u);
    EXPECT_EQ(one.q0, other->q0);
    EXPECT_EQ(one.qf, other->qf);
    EXPECT_EQ(one.knots, other->knots);
    EXPECT_EQ(one.knot_offset, other->knot_offset);
    EXPECT_EQ(one.sample_q, other->sample_q);
    EXPECT_EQ(one.attempt, other->attempt);
    EXPECT_EQ(one.header.attempts, other->header.attempts);
    EXPECT_EQ(one.header.rejected, other->header.rejected);
    EXPECT_EQ(one.header.simulated_seconds, other->header.simulated_seconds);
  }
  // Stored edges replay to their stored end states.
  SimulatorWorkspace ws(scene.sim);
  for (size_t k = 0; k < one.size(); k += 10) {
    const JointVector q0 = Eigen::Map<const Eigen::VectorXd>(&one.q0[k * 7], 7);
    const CommandProfile p{&one.knots[one.knot_offset[k] * 7],
                           static_cast<int>(one.knot_offset[k + 1] - one.knot_offset[k]), 7,
                           one.command_duration[k]};
    const RolloutResult r = simulate(scene.sim, ws, q0, p);
    ASSERT_TRUE(r.valid());
    for (int i = 0; i < 7; ++i) EXPECT_EQ(r.qf[i], one.qf[k * 7 + i]);
  }
}

}  // namespace
}  // namespace lazyboe
