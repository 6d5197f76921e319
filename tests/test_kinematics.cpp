// Forward kinematics against the known Panda pose and an independent formulation: Craig's
// modified Denavit-Hartenberg parameters of the Panda, evaluated here without the URDF.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/sincos.h"
#include "test_util.h"

namespace lazyboe {
namespace {

JointVector random_q(const RobotModel& robot, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  JointVector q(robot.dof);
  for (int i = 0; i < robot.dof; ++i)
    q[i] = robot.q_min[i] + u(rng) * (robot.q_max[i] - robot.q_min[i]);
  return q;
}

// Modified DH: T = RotX(alpha) TransX(a) RotZ(theta) TransZ(d).
Eigen::Matrix4d mdh(double a, double d, double alpha, double theta) {
  const double ca = std::cos(alpha), sa = std::sin(alpha), ct = std::cos(theta),
               st = std::sin(theta);
  Eigen::Matrix4d T;
  T << ct, -st, 0, a, st * ca, ct * ca, -sa, -d * sa, st * sa, ct * sa, ca, d * ca, 0, 0, 0, 1;
  return T;
}

Eigen::Matrix4d panda_flange_dh(const JointVector& q) {
  const double a[] = {0, 0, 0, 0.0825, -0.0825, 0, 0.088, 0};
  const double d[] = {0.333, 0, 0.316, 0, 0.384, 0, 0, 0.107};
  const double alpha[] = {0, -M_PI / 2, M_PI / 2, M_PI / 2, -M_PI / 2, M_PI / 2, M_PI / 2, 0};
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 8; ++i) T = T * mdh(a[i], d[i], alpha[i], i < 7 ? q[i] : 0.0);
  return T;
}

TEST(Kinematics, FlangeAtZeroConfiguration) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  forward_kinematics(robot, data, JointVector::Zero(7));
  const Pose flange = link_pose(robot, data, robot.link_index("panda_link8"));
  EXPECT_NEAR(flange.p.x(), 0.088, 1e-12);
  EXPECT_NEAR(flange.p.y(), 0.0, 1e-12);
  EXPECT_NEAR(flange.p.z(), 0.926, 1e-12);
  // The flange points straight down at q = 0: its z axis is -z of the base.
  EXPECT_NEAR(flange.R.col(2).z(), -1.0, 1e-12);
  EXPECT_EQ(robot.tip_link(), robot.link_index("panda_link8"));
}

TEST(Kinematics, MatchesModifiedDenavitHartenberg) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const JointVector q = random_q(robot, rng);
    forward_kinematics(robot, data, q);
    const Pose flange = link_pose(robot, data, robot.tip_link());
    const Eigen::Matrix4d T = panda_flange_dh(q);
    EXPECT_LT((flange.p - T.block<3, 1>(0, 3)).norm(), 1e-12);
    EXPECT_LT((flange.R - T.block<3, 3>(0, 0)).norm(), 1e-12);
  }
}

TEST(Kinematics, EveryLinkFollowsItsParentJoint) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(3);
  const JointVector q = random_q(robot, rng);
  forward_kinematics(robot, data, q);
  // Joint i+1 moves link i+1 about its own z axis through the link's origin: the origin of
  // link i+1 does not depend on q[i].
  for (int i = 0; i < robot.dof; ++i) {
    JointVector q2 = q;
    q2[i] += 0.3;
    RobotData data2(robot);
    forward_kinematics(robot, data2, q2);
    const int link = robot.link_index("panda_link" + std::to_string(i + 1));
    EXPECT_LT((link_pose(robot, data, link).p - link_pose(robot, data2, link).p).norm(), 1e-12);
    const Eigen::Vector3d z1 = link_pose(robot, data, link).R.col(2);
    const Eigen::Vector3d z2 = link_pose(robot, data2, link).R.col(2);
    EXPECT_LT((z1 - z2).norm(), 1e-12);
  }
}

// The joint poses' inline sin and cos (robot/sincos.h) against libm, in units in the last place
// of libm's value: over every quadrant, at the quadrant boundaries, for tiny angles, and beyond
// the range where it falls back to libm.
TEST(Kinematics, JointSinCosIsWithinTwoUlpOfLibm) {
  std::vector<double> values = {0.0, -0.0, 1e-300, -1e-300, 1e-9, 0.5, 1e6, -3e7, 99999.9};
  for (int k = -16; k <= 16; ++k) {
    for (double d : {-1e-12, 0.0, 1e-12}) values.push_back(k * M_PI / 4 + d);
  }
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> angle(-12.0, 12.0);
  for (int trial = 0; trial < 100000; ++trial) values.push_back(angle(rng));
  auto ulps = [](double got, double expected) {
    const double ulp = std::nextafter(std::abs(expected), INFINITY) - std::abs(expected);
    return std::abs(got - expected) / ulp;
  };
  double worst = 0;
  for (double x : values) {
    double s, c;
    joint_sincos(x, s, c);
    worst = std::max({worst, ulps(s, std::sin(x)), ulps(c, std::cos(x))});
    ASSERT_LE(ulps(s, std::sin(x)), 2.0) << "sin " << x;
    ASSERT_LE(ulps(c, std::cos(x)), 2.0) << "cos " << x;
  }
  RecordProperty("worst_ulps", std::to_string(worst));
}

}  // namespace
}  // namespace lazyboe
