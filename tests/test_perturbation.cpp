// The perturbation analysis: an analytic case where the end-state error equals the start
// perturbation, edges next to and far from obstacles, determinism across threads, and
// extending p.
#include <gtest/gtest.h>

#include <cmath>

#include "lazyboe/bundle/builder.h"
#include "lazyboe/bundle/perturbation.h"
#include "lazyboe/common/error.h"
#include "test_util.h"

namespace lazyboe {
namespace {

using test::Scene;

const JointVector& ready() {
  static const JointVector q = (JointVector(7) << 0, -0.785, 0, -2.356, 0, 1.571, 0.785).finished();
  return q;
}

// A bundle of edges whose command is zero: the robot holds still, so an edge ends where it
// starts, and so does every perturbed copy.
Bundle resting_edges(Scene& scene, const std::vector<JointVector>& starts) {
  BuildSettings settings;
  settings.region_lower = scene.robot.q_min;
  settings.region_upper = scene.robot.q_max;
  Bundle b = new_bundle(scene.robot, scene.env, settings);
  SimulatorWorkspace ws(scene.sim);
  const std::vector<double> zero(3 * 7, 0.0);
  for (const JointVector& q0 : starts) {
    const RolloutResult r = simulate(scene.sim, ws, q0, CommandProfile{zero.data(), 3, 7, 0.3});
    EXPECT_TRUE(r.valid()) << rollout_status_name(r.status);
    b.q0.insert(b.q0.end(), q0.data(), q0.data() + 7);
    b.qf.insert(b.qf.end(), r.qf.data(), r.qf.data() + 7);
    b.duration.push_back(r.duration);
    b.command_duration.push_back(0.3);
    b.attempt.push_back(b.attempt.size());
    b.knots.insert(b.knots.end(), zero.begin(), zero.end());
    b.knot_offset.push_back(b.knots.size() / 7);
    b.sample_offset.push_back(0);
  }
  b.header.complete = true;
  return b;
}

PerturbControl quiet(int threads = 1) {
  PerturbControl c;
  c.threads = threads;
  c.quiet = true;
  return c;
}

TEST(Perturbation, OffsetsHaveNormsUniformInZeroToTheta) {
  PerturbSettings s;
  s.theta = 0.3;
  double sum = 0, below_half = 0;
  const int count = 4000;
  for (int j = 0; j < count; ++j) {
    const double r = perturbation_offset(s, 7, 5, j).norm();
    ASSERT_GT(r, 0.0);
    ASSERT_LE(r, s.theta);
    sum += r;
    below_half += r < s.theta / 2;
  }
  EXPECT_NEAR(sum / count, s.theta / 2, 0.01);
  EXPECT_NEAR(below_half / count, 0.5, 0.03);
}

// Zero command: the end-state error of perturbation j is exactly |d_j|, so P_lazy_prop is the
// share of perturbations with |d| < theta/2 (0.5 in expectation) and the maximum error is the
// largest |d|.
TEST(Perturbation, AnalyticCaseErrorEqualsThePerturbation) {
  Scene scene("empty");
  Bundle b = resting_edges(scene, {ready()});
  // Holds still (gravity compensated, no friction at rest), up to round-off.
  for (size_t i = 0; i < b.q0.size(); ++i) ASSERT_NEAR(b.qf[i], b.q0[i], 1e-15);
  PerturbSettings s;
  s.theta = 0.2;
  s.perturbations = 400;
  prepare_perturbation(b, s, false, "test");
  ASSERT_EQ(run_perturbation(scene.sim, b, s, quiet()), PerturbOutcome::Complete);
  const Perturbation& p = b.perturbation;
  uint64_t expected_lazy = 0;
  double expected_max = 0;
  for (uint64_t j = 0; j < s.perturbations; ++j) {
    const double r = perturbation_offset(s, 7, 0, j).norm();
    expected_lazy += r < s.theta / 2;
    expected_max = std::max(expected_max, r);
  }
  EXPECT_EQ(p.done[0], 400u);
  EXPECT_EQ(p.valid[0], 400u);  // the ready pose is far from everything
  EXPECT_EQ(p.collision[0], 0u);
  EXPECT_EQ(p.lazy[0], expected_lazy);
  EXPECT_NEAR(p.max_error[0], expected_max, 1e-12);
  EXPECT_DOUBLE_EQ(p.p_lazy_prop[0], static_cast<double>(expected_lazy) / 400);
  EXPECT_NEAR(p.p_lazy_prop[0], 0.5, 0.1);
  EXPECT_EQ(p.p_collision[0], 0.0);
  EXPECT_TRUE(p.complete);
  // Every perturbed copy also holds still: it ends where it started, at qf + d, so the
  // transfer prediction is exact up to round-off.
  ASSERT_TRUE(p.has_transfer);
  EXPECT_EQ(p.transfer_lazy[0], 400u);
  EXPECT_LT(p.transfer_max_error[0], 1e-9);
  EXPECT_EQ(p.p_lazy_prop_transfer[0], 1.0);
}

TEST(Perturbation, EdgeNextToAnObstacleCollidesFarEdgeDoesNot) {
  Scene scene("table");
  SimulatorWorkspace ws(scene.sim);
  // Lean forward from the ready pose until the arm is about 3 cm from the table.
  JointVector near = ready();
  double distance = 1;
  while (distance > 0.03 && near[1] < 1.5) {
    near[1] += 0.01;
    forward_kinematics(scene.robot, ws.robot, near);
    update_collision_transforms(scene.collision, ws.collision, ws.robot);
    distance = min_distance(scene.collision, ws.collision).env_distance;
  }
  ASSERT_LT(distance, 0.03);
  ASSERT_GT(distance, scene.robot.geometry.margin);
  Bundle b = resting_edges(scene, {near, ready()});
  PerturbSettings s;
  s.theta = 0.1;
  s.perturbations = 64;
  prepare_perturbation(b, s, false, "test");
  run_perturbation(scene.sim, b, s, quiet());
  EXPECT_GT(b.perturbation.p_collision[0], 0.0);
  EXPECT_LT(b.perturbation.p_collision[0], 1.0);
  EXPECT_EQ(b.perturbation.p_collision[1], 0.0);
  EXPECT_EQ(b.perturbation.valid[1], 64u);
}

Bundle small_bundle(Scene& scene, size_t edges) {
  BuildSettings settings;
  settings.region_lower = scene.robot.region.lower;
  settings.region_upper = scene.robot.region.upper;
  settings.edges = edges;
  settings.simulation.sample_every = 0;
  Bundle b = new_bundle(scene.robot, scene.env, settings);
  BuildControl control;
  control.quiet = true;
  build_bundle(scene.sim, settings, b, control);
  return b;
}

TEST(Perturbation, SameResultForAnyThreadCountAndWhenExtended) {
  Scene scene("table");
  const Bundle base = small_bundle(scene, 40);
  PerturbSettings s;
  s.perturbations = 6;
  auto run = [&](int threads, std::vector<uint64_t> steps) {
    Bundle b = base;
    for (uint64_t p : steps) {
      s.perturbations = p;
      prepare_perturbation(b, s, false, "test");
      EXPECT_EQ(run_perturbation(scene.sim, b, s, quiet(threads)), PerturbOutcome::Complete);
    }
    return b.perturbation;
  };
  const Perturbation one = run(1, {6}), two = run(2, {6}), extended = run(2, {3, 6});
  for (const Perturbation* other : {&two, &extended}) {
    EXPECT_EQ(one.done, other->done);
    EXPECT_EQ(one.valid, other->valid);
    EXPECT_EQ(one.lazy, other->lazy);
    EXPECT_EQ(one.collision, other->collision);
    EXPECT_EQ(one.p_lazy_prop, other->p_lazy_prop);
    EXPECT_EQ(one.p_collision, other->p_collision);
    EXPECT_TRUE(other->has_transfer);
    EXPECT_EQ(one.transfer_lazy, other->transfer_lazy);
    EXPECT_EQ(one.p_lazy_prop_transfer, other->p_lazy_prop_transfer);
    for (size_t e = 0; e < one.max_error.size(); ++e) {
      EXPECT_TRUE(one.max_error[e] == other->max_error[e] ||
                  (std::isnan(one.max_error[e]) && std::isnan(other->max_error[e])));
      EXPECT_TRUE(
          one.transfer_max_error[e] == other->transfer_max_error[e] ||
          (std::isnan(one.transfer_max_error[e]) && std::isnan(other->transfer_max_error[e])));
    }
  }
  uint64_t valid = 0, done = 0;
  for (size_t e = 0; e < one.done.size(); ++e) {
    valid += one.valid[e];
    done += one.done[e];
    EXPECT_LE(one.valid[e] + one.collision[e], one.done[e]);
    EXPECT_GE(one.p_lazy_prop[e], 0.0);
    EXPECT_LE(one.p_lazy_prop[e], 1.0);
  }
  EXPECT_GT(valid, done / 2);
}

// The transfer statistics are those of the sampled rollouts themselves: fresh simulations from
// q0 + d_j (a new workspace, the simulator called directly) end within the stored bound of
// qf + d_j, and their counts and maximum give back the stored numbers exactly.
TEST(Perturbation, TransferStatisticsAreThoseOfFreshRollouts) {
  Scene scene("table");
  Bundle b = small_bundle(scene, 24);
  PerturbSettings s;
  s.perturbations = 6;
  prepare_perturbation(b, s, false, "test");
  ASSERT_EQ(run_perturbation(scene.sim, b, s, quiet(2)), PerturbOutcome::Complete);
  const Perturbation& p = b.perturbation;
  ASSERT_TRUE(p.has_transfer);
  SimulatorWorkspace ws(scene.sim);
  const int n = b.dof();
  double sum_stored = 0, sum_transfer = 0;
  size_t with_valid = 0;
  for (size_t e = 0; e < b.size(); ++e) {
    SCOPED_TRACE("edge " + std::to_string(e));
    const JointVector q0 = Eigen::Map<const Eigen::VectorXd>(&b.q0[e * n], n);
    const JointVector qf = Eigen::Map<const Eigen::VectorXd>(&b.qf[e * n], n);
    const CommandProfile command{&b.knots[b.knot_offset[e] * n],
                                 static_cast<int>(b.knot_offset[e + 1] - b.knot_offset[e]), n,
                                 b.command_duration[e]};
    uint64_t valid = 0, lazy = 0;
    double max = 0;
    for (uint64_t j = 0; j < s.perturbations; ++j) {
      const JointVector d = perturbation_offset(s, n, e, j);
      const RolloutResult r = simulate(scene.sim, ws, q0 + d, command);
      const PerturbationSample sample = perturb_sample(scene.sim, ws, b, e, s, j);
      ASSERT_EQ(sample.status, r.status);
      if (!r.valid()) continue;
      const double residual = (r.qf - (qf + d)).norm();
      EXPECT_EQ(sample.transfer_error, residual);
      EXPECT_EQ(sample.error, (r.qf - qf).norm());
      EXPECT_LE(residual, p.transfer_max_error[e]);
      max = valid ? std::max(max, residual) : residual;
      ++valid;
      lazy += residual < s.theta / 2;
    }
    ASSERT_EQ(valid, p.valid[e]);
    EXPECT_EQ(lazy, p.transfer_lazy[e]);
    EXPECT_EQ(p.p_lazy_prop_transfer[e], valid ? static_cast<double>(lazy) / valid : 0.0);
    if (valid) {
      EXPECT_EQ(max, p.transfer_max_error[e]);
      sum_stored += p.max_error[e];
      sum_transfer += p.transfer_max_error[e];
      ++with_valid;
    } else {
      EXPECT_TRUE(std::isnan(p.transfer_max_error[e]));
    }
  }
  // The physics the statistics are for: the transfer predicts the end far better than the
  // stored end does (the stored-end error is about |d| itself).
  ASSERT_GT(with_valid, b.size() / 2);
  EXPECT_LT(sum_transfer, 0.2 * sum_stored);
}

// An analysis written before the transfer statistics (none stored) is kept when complete with
// the same settings, refused when it would have to be extended (never redone in place), and
// redone with --replace to the numbers of a straight run; what is refused for any analysis is
// still refused.
TEST(Perturbation, AnalysisWithoutTransferIsKeptOrReplaced) {
  Scene scene("table");
  const Bundle base = small_bundle(scene, 16);
  PerturbSettings s;
  s.perturbations = 4;
  Bundle straight = base;
  EXPECT_FALSE(prepare_perturbation(straight, s, false, "test"));
  run_perturbation(scene.sim, straight, s, quiet(2));
  for (const uint64_t p : {4, 6}) {
    SCOPED_TRACE("to p = " + std::to_string(p));
    Bundle old = straight;
    Perturbation& q = old.perturbation;
    q.has_transfer = false;
    q.transfer_lazy.clear();
    q.transfer_max_error.clear();
    q.p_lazy_prop_transfer.clear();
    PerturbSettings fewer = s;
    fewer.perturbations = 2;
    EXPECT_THROW(prepare_perturbation(old, fewer, false, "x.h5"), Error);
    EXPECT_FALSE(old.perturbation.has_transfer);
    PerturbSettings more = s;
    more.perturbations = p;
    if (p == s.perturbations) {
      const Perturbation kept = q;
      EXPECT_TRUE(prepare_perturbation(old, more, false, "x.h5"));  // it lacks them
      EXPECT_TRUE(q.complete);
      EXPECT_FALSE(q.has_transfer);
      EXPECT_EQ(q.done, kept.done);
      EXPECT_EQ(q.p_lazy_prop, kept.p_lazy_prop);
    } else {
      EXPECT_THROW(prepare_perturbation(old, more, false, "x.h5"), Error);
      EXPECT_FALSE(q.has_transfer);
    }
    EXPECT_FALSE(prepare_perturbation(old, more, true, "x.h5"));  // --replace
    EXPECT_TRUE(q.has_transfer);
    EXPECT_FALSE(q.complete);
    EXPECT_EQ(q.done, std::vector<uint64_t>(old.size(), 0));
    EXPECT_EQ(q.simulated_seconds, 0.0);
    ASSERT_EQ(run_perturbation(scene.sim, old, more, quiet(2)), PerturbOutcome::Complete);
    Bundle fresh = base;
    prepare_perturbation(fresh, more, false, "test");
    run_perturbation(scene.sim, fresh, more, quiet(1));
    const Perturbation& f = fresh.perturbation;
    EXPECT_EQ(q.done, f.done);
    EXPECT_EQ(q.valid, f.valid);
    EXPECT_EQ(q.lazy, f.lazy);
    EXPECT_EQ(q.collision, f.collision);
    EXPECT_EQ(q.transfer_lazy, f.transfer_lazy);
    EXPECT_EQ(q.p_lazy_prop, f.p_lazy_prop);
    EXPECT_EQ(q.p_lazy_prop_transfer, f.p_lazy_prop_transfer);
    for (size_t e = 0; e < old.size(); ++e) {
      EXPECT_TRUE(q.transfer_max_error[e] == f.transfer_max_error[e] ||
                  (std::isnan(q.transfer_max_error[e]) && std::isnan(f.transfer_max_error[e])));
    }
  }
}

TEST(Perturbation, OtherSettingsNeedReplace) {
  Scene scene("empty");
  Bundle b = resting_edges(scene, {ready()});
  PerturbSettings s;
  s.theta = 0.2;
  s.perturbations = 4;
  prepare_perturbation(b, s, false, "x.h5");
  run_perturbation(scene.sim, b, s, quiet());
  auto refused = [&](PerturbSettings other, const std::string& needle) {
    try {
      prepare_perturbation(b, other, false, "x.h5");
      ADD_FAILURE() << "expected a refusal mentioning " << needle;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  PerturbSettings other = s;
  other.theta = 0.3;
  refused(other, "--replace");
  other = s;
  other.seed = 2;
  refused(other, "--seed");
  other = s;
  other.perturbations = 2;
  refused(other, "--replace");
  other.theta = 0.3;
  prepare_perturbation(b, other, true, "x.h5");  // --replace starts afresh
  EXPECT_EQ(b.perturbation.done[0], 0u);
  EXPECT_EQ(b.perturbation.theta, 0.3);
}

}  // namespace
}  // namespace lazyboe
