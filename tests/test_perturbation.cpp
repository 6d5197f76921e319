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
  ASSERT_GT(distance, scene.robot.collision_margin);
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
  settings.region_lower = scene.robot.region_lower;
  settings.region_upper = scene.robot.region_upper;
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
    for (size_t e = 0; e < one.max_error.size(); ++e) {
      EXPECT_TRUE(one.max_error[e] == other->max_error[e] ||
                  (std::isnan(one.max_error[e]) && std::isnan(other->max_error[e])));
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
