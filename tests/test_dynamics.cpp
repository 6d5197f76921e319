// Dynamics checked against independent formulations: the mass matrix from link Jacobians,
// Coriolis terms from Christoffel symbols of M(q), gravity from the potential energy, forward
// dynamics against inverse dynamics, energy conservation in free fall, a cart-pole chain with a
// closed-form model, and no heap allocation in the hot paths.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>

#include "alloc_counter.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/robot_config.h"
#include "test_util.h"

namespace lazyboe {
namespace {

struct State {
  JointVector q, dq, ddq;
};

State random_state(const RobotModel& robot, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  State s{JointVector(robot.dof), JointVector(robot.dof), JointVector(robot.dof)};
  for (int i = 0; i < robot.dof; ++i) {
    s.q[i] = robot.q_min[i] + u(rng) * (robot.q_max[i] - robot.q_min[i]);
    s.dq[i] = (2 * u(rng) - 1) * robot.dq_max[i];
    s.ddq[i] = (2 * u(rng) - 1) * robot.ddq_max[i];
  }
  return s;
}

RobotModel frictionless(RobotModel robot) {
  for (Joint& j : robot.joints) j.friction = Friction{};
  return robot;
}

// M(q) = sum_i m_i Jv_i^T Jv_i + Jw_i^T I_i Jw_i, with the Jacobians of each body's centre of
// mass built from the world joint axes: independent of the composite-rigid-body algorithm.
JointMatrix mass_matrix_from_jacobians(const RobotModel& robot, const JointVector& q) {
  RobotData data(robot);
  forward_kinematics(robot, data, q);
  const int n = robot.dof;
  JointMatrix M = JointMatrix::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    const BodyInertia& b = robot.bodies[i];
    const Eigen::Vector3d c = data.body_pose[i] * b.com;
    Eigen::MatrixXd Jv = Eigen::MatrixXd::Zero(3, n), Jw = Eigen::MatrixXd::Zero(3, n);
    for (int j = 0; j <= i; ++j) {
      const Eigen::Vector3d axis = data.body_pose[j].R * robot.joints[j].axis;
      const Eigen::Vector3d origin = data.body_pose[j].p;
      if (robot.joints[j].type == JointType::Revolute) {
        Jv.col(j) = axis.cross(c - origin);
        Jw.col(j) = axis;
      } else {
        Jv.col(j) = axis;
      }
    }
    const Eigen::Matrix3d I_world =
        data.body_pose[i].R * b.inertia_com * data.body_pose[i].R.transpose();
    M += b.mass * Jv.transpose() * Jv + Jw.transpose() * I_world * Jw;
  }
  return M;
}

TEST(Dynamics, MassMatrixMatchesJacobianFormulation) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const State s = random_state(robot, rng);
    const JointMatrix M = mass_matrix(robot, data, s.q);
    const JointMatrix reference = mass_matrix_from_jacobians(robot, s.q);
    EXPECT_LT((M - reference).norm(), 1e-10 * reference.norm());
    EXPECT_LT((M - M.transpose()).norm(), 1e-14);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<JointMatrix>(M).eigenvalues().minCoeff(), 0.0);
  }
}

// The dynamics read each body's inertia about its origin, which merge_inertia keeps: a payload
// merged into the hand after the model was read must change the mass matrix and the gravity
// torques as the centre-of-mass description says.
TEST(Dynamics, AMergedPayloadReachesTheDynamics) {
  RobotModel robot = test::panda();
  Eigen::Matrix3d box = Eigen::Matrix3d::Zero();
  box.diagonal() << 2e-3, 3e-3, 4e-3;
  merge_inertia(robot.bodies.back(), 1.5, Eigen::Vector3d(0.02, -0.01, 0.12), box);
  RobotData data(robot), unloaded(test::panda());
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 20; ++trial) {
    const State s = random_state(robot, rng);
    const JointMatrix reference = mass_matrix_from_jacobians(robot, s.q);
    EXPECT_LT((mass_matrix(robot, data, s.q) - reference).norm(), 1e-10 * reference.norm());
    dynamics_terms(robot, data, s.q, s.dq);
    EXPECT_LT((data.M - reference).norm(), 1e-10 * reference.norm());
    EXPECT_GT((data.M - mass_matrix(test::panda(), unloaded, s.q)).norm(), 1e-3);
    const JointVector g = gravity_torques(robot, data, s.q);  // Newton-Euler, from the com
    dynamics_terms(robot, data, s.q, s.dq);
    EXPECT_LT((data.gravity - g).norm(), 1e-10 * g.norm());
  }
}

TEST(Dynamics, InverseDynamicsEqualsMassMatrixTimesAccelerationPlusBias) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 100; ++trial) {
    const State s = random_state(robot, rng);
    const JointVector tau = inverse_dynamics(robot, data, s.q, s.dq, s.ddq);
    const JointVector h = inverse_dynamics(robot, data, s.q, s.dq, JointVector::Zero(7));
    const JointMatrix M = mass_matrix(robot, data, s.q);
    const JointVector expected = M * s.ddq + h;
    EXPECT_LT((tau - expected).norm(), 1e-10 * std::max(1.0, tau.norm()));
  }
}

TEST(Dynamics, CoriolisMatchesChristoffelSymbolsOfMassMatrix) {
  const RobotModel robot = frictionless(test::panda());
  RobotData data(robot);
  std::mt19937_64 rng(13);
  const int n = robot.dof;
  const double eps = 1e-6;
  for (int trial = 0; trial < 20; ++trial) {
    const State s = random_state(robot, rng);
    std::vector<JointMatrix> dM(n);  // dM[k] = dM/dq_k by central differences
    for (int k = 0; k < n; ++k) {
      JointVector qp = s.q, qm = s.q;
      qp[k] += eps;
      qm[k] -= eps;
      const JointMatrix Mp = mass_matrix(robot, data, qp);
      const JointMatrix Mm = mass_matrix(robot, data, qm);
      dM[k] = (Mp - Mm) / (2 * eps);
    }
    JointVector c = JointVector::Zero(n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          c[i] += (dM[k](i, j) - 0.5 * dM[i](j, k)) * s.dq[j] * s.dq[k];
        }
      }
    }
    const JointVector rnea_c = rnea(robot, data, s.q, s.dq, JointVector::Zero(n), false, false);
    EXPECT_LT((rnea_c - c).norm(), 1e-6 * std::max(1.0, c.norm())) << "trial " << trial;
  }
}

TEST(Dynamics, GravityIsGradientOfPotentialEnergy) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(14);
  const double eps = 1e-6;
  for (int trial = 0; trial < 50; ++trial) {
    const State s = random_state(robot, rng);
    const JointVector g = gravity_torques(robot, data, s.q);
    for (int k = 0; k < robot.dof; ++k) {
      JointVector qp = s.q, qm = s.q;
      qp[k] += eps;
      qm[k] -= eps;
      const double dV =
          (potential_energy(robot, data, qp) - potential_energy(robot, data, qm)) / (2 * eps);
      EXPECT_NEAR(g[k], dV, 1e-6 * std::max(1.0, std::abs(dV)));
    }
  }
}

TEST(Dynamics, ForwardDynamicsInvertsInverseDynamics) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(15);
  for (int trial = 0; trial < 200; ++trial) {
    const State s = random_state(robot, rng);
    const JointVector tau = inverse_dynamics(robot, data, s.q, s.dq, s.ddq);
    const JointVector ddq = forward_dynamics(robot, data, s.q, s.dq, tau);
    EXPECT_LT((ddq - s.ddq).norm(), 1e-9 * std::max(1.0, s.ddq.norm()));
  }
}

TEST(Dynamics, FrictionFollowsGazModel) {
  const RobotModel& robot = test::panda();
  const Friction& f = robot.joints[3].friction;  // joint 4: FI = 1.2794, 5.5903, 0.036194
  ASSERT_EQ(f.model, FrictionModel::Sigmoid);
  EXPECT_DOUBLE_EQ(friction_torque(f, 0.0), 0.0);
  const double dq = 0.5;
  const double expected = 1.2794 / (1 + std::exp(-5.5903 * (dq + 0.036194))) -
                          1.2794 / (1 + std::exp(-5.5903 * 0.036194));
  EXPECT_NEAR(friction_torque(f, dq), expected, 1e-15);
  // Inverse dynamics adds exactly the friction torque.
  RobotData data(robot);
  std::mt19937_64 rng(16);
  const State s = random_state(robot, rng);
  const JointVector with = rnea(robot, data, s.q, s.dq, s.ddq, true, true);
  const JointVector without = rnea(robot, data, s.q, s.dq, s.ddq, true, false);
  for (int i = 0; i < robot.dof; ++i) {
    EXPECT_NEAR(with[i] - without[i], friction_torque(robot.joints[i].friction, s.dq[i]), 1e-12);
  }
}

// Free fall without friction conserves kinetic plus potential energy (RK4, 0.1 ms steps).
TEST(Dynamics, FrictionlessFreeFallConservesEnergy) {
  const RobotModel robot = frictionless(test::panda());
  RobotData data(robot);
  std::mt19937_64 rng(17);
  const int n = robot.dof;
  const JointVector zero = JointVector::Zero(n);
  for (int trial = 0; trial < 3; ++trial) {
    State s = random_state(robot, rng);
    s.dq *= 0.3;
    auto energy = [&](const JointVector& q, const JointVector& dq) {
      return kinetic_energy(robot, data, q, dq) + potential_energy(robot, data, q);
    };
    const double e0 = energy(s.q, s.dq);
    const double dt = 1e-4;
    JointVector q = s.q, dq = s.dq;
    double max_drift = 0;
    for (int step = 0; step < 5000; ++step) {
      const JointVector k1q = dq, k1v = forward_dynamics(robot, data, q, dq, zero);
      const JointVector k2q = dq + 0.5 * dt * k1v;
      const JointVector k2v = forward_dynamics(robot, data, q + 0.5 * dt * k1q, k2q, zero);
      const JointVector k3q = dq + 0.5 * dt * k2v;
      const JointVector k3v = forward_dynamics(robot, data, q + 0.5 * dt * k2q, k3q, zero);
      const JointVector k4q = dq + dt * k3v;
      const JointVector k4v = forward_dynamics(robot, data, q + dt * k3q, k4q, zero);
      q += dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      dq += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      if (step % 500 == 0) max_drift = std::max(max_drift, std::abs(energy(q, dq) - e0));
    }
    // The arm falls for real: it gains kinetic energy of several joules.
    EXPECT_GT(kinetic_energy(robot, data, q, dq), 0.5);
    EXPECT_LT(max_drift, 1e-6) << "trial " << trial;
  }
}

// A cart on a rail (prismatic x) carrying a pendulum (revolute about y): closed-form
// M = [[m1+m2, m2 l cos(th)], [m2 l cos(th), m2 l^2 + I]], g = [0, m2 g l sin(th)].
TEST(Dynamics, CartPoleMatchesClosedForm) {
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="cartpole">
  <link name="world"/>
  <link name="cart"><inertial><origin xyz="0 0 0"/><mass value="2.0"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="pole"><inertial><origin xyz="0 0 -0.5"/><mass value="0.5"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.001"/></inertial>
    <collision><origin xyz="0 0 -0.5"/><geometry><cylinder radius="0.02" length="1.0"/></geometry></collision></link>
  <link name="tip"><inertial><origin xyz="0 0 0"/><mass value="0.25"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <joint name="rail" type="prismatic"><parent link="world"/><child link="cart"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" velocity="2" effort="100"/></joint>
  <joint name="hinge" type="revolute"><parent link="cart"/><child link="pole"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" velocity="5" effort="50"/></joint>
  <joint name="tip_mount" type="fixed"><parent link="pole"/><child link="tip"/>
    <origin xyz="0 0 -1.0"/></joint>
</robot>)";
  const std::string config = R"({"schema_version": 1, "name": "cartpole", "urdf": "cartpole.urdf",
    "joints": [
      {"name": "rail", "max_acceleration": 5, "max_jerk": 100, "max_torque_rate": 1000, "friction": {"model": "none"}},
      {"name": "hinge", "max_acceleration": 5, "max_jerk": 100, "max_torque_rate": 1000,
       "friction": {"model": "viscous_coulomb", "coulomb": 0.1, "viscous": 0.05, "smoothing_velocity": 0.01}}],
    "collision": {"margin": 0.0}})";
  test::write_temp_file("cartpole/cartpole.urdf", urdf);
  const RobotModel robot = load_robot(test::write_temp_file("cartpole/cartpole.json", config));
  ASSERT_EQ(robot.dof, 2);
  // The tip is fixed to the pole, so its mass merges into the pole's body.
  const double m1 = 2.0, m2 = 0.75;
  EXPECT_NEAR(robot.bodies[1].mass, m2, 1e-15);
  const double l = (0.5 * 0.5 + 0.25 * 1.0) / m2;  // pole body's centre of mass below the hinge
  EXPECT_NEAR(robot.bodies[1].com.z(), -l, 1e-15);
  // Inertia of the pole body about the hinge axis (y), by parallel axes.
  const double I_hinge = 0.02 + 0.5 * 0.25 + 0.001 + 0.25 * 1.0;

  RobotData data(robot);
  for (double th : {-1.2, 0.0, 0.4, 2.0}) {
    JointVector q(2);
    q << 0.3, th;
    const JointMatrix M = mass_matrix(robot, data, q);
    EXPECT_NEAR(M(0, 0), m1 + m2, 1e-12);
    // Pole hangs along -z; rotating +th about +y swings it towards -x.
    EXPECT_NEAR(M(0, 1), -m2 * l * std::cos(th), 1e-12);
    EXPECT_NEAR(M(1, 1), I_hinge, 1e-12);
    const JointVector g = gravity_torques(robot, data, q);
    EXPECT_NEAR(g[0], 0.0, 1e-12);
    EXPECT_NEAR(g[1], m2 * 9.81 * l * std::sin(th), 1e-12);
    // Centripetal force on the rail from the swinging pole: m2 l sin(th) dth^2.
    JointVector dq(2);
    dq << 0.0, 2.0;
    const JointVector c = rnea(robot, data, q, dq, JointVector::Zero(2), false, false);
    EXPECT_NEAR(c[0], m2 * l * std::sin(th) * 4.0, 1e-12);
    EXPECT_NEAR(c[1], 0.0, 1e-12);
    const JointVector tau = inverse_dynamics(robot, data, q, dq, JointVector::Zero(2));
    EXPECT_NEAR(tau[1] - g[1], 0.1 * std::tanh(2.0 / 0.01) + 0.05 * 2.0, 1e-12);
  }
}

TEST(Dynamics, HotPathsDoNotAllocate) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(18);
  const State s = random_state(robot, rng);
  JointVector tau(7);
  LAZYBOE_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const long before = test::allocations.load();
  for (int k = 0; k < 10; ++k) {
    forward_kinematics(robot, data, s.q);
    tau = inverse_dynamics(robot, data, s.q, s.dq, s.ddq);
    mass_matrix(robot, data, s.q);
    gravity_torques(robot, data, s.q);
    forward_dynamics(robot, data, s.q, s.dq, tau);
  }
  EXPECT_EQ(test::allocations.load() - before, 0);
}

}  // namespace
}  // namespace lazyboe

namespace lazyboe {
namespace {

// The simulator's shared pass gives the same gravity, mass matrix and accelerations as the
// separate algorithms.
TEST(Dynamics, SharedTermsMatchSeparateAlgorithms) {
  const RobotModel& robot = test::panda();
  RobotData shared(robot), separate(robot);
  std::mt19937_64 rng(19);
  for (int trial = 0; trial < 100; ++trial) {
    const State s = random_state(robot, rng);
    JointVector tau(7);
    for (int i = 0; i < 7; ++i)
      tau[i] = std::uniform_real_distribution<double>(-1, 1)(rng) * robot.tau_max[i];
    dynamics_terms(robot, shared, s.q, s.dq);
    const JointVector g = gravity_torques(robot, separate, s.q);
    EXPECT_LT((shared.gravity - g).norm(), 1e-12 * std::max(1.0, g.norm()));
    EXPECT_LT((shared.M - mass_matrix(robot, separate, s.q)).norm(), 1e-14);
    const JointVector a = forward_dynamics_from_terms(shared, tau);
    const JointVector b = forward_dynamics(robot, separate, s.q, s.dq, tau);
    EXPECT_LT((a - b).norm(), 1e-9 * std::max(1.0, b.norm()));
  }
}

}  // namespace
}  // namespace lazyboe

namespace lazyboe {
namespace {

// The Panda with some joints changed so that every branch of the dynamics runs: revolute
// joints about axes other than z, and prismatic joints (about z and not).
RobotModel mixed_chain() {
  RobotModel robot = test::panda();
  auto set_axis = [&](int i, JointType type, const Eigen::Vector3d& axis) {
    robot.joints[i].type = type;
    robot.joints[i].axis = axis.normalized();
    robot.joints[i].axis_is_z = false;
  };
  set_axis(1, JointType::Revolute, Eigen::Vector3d(0.3, -0.5, 0.8));
  set_axis(2, JointType::Prismatic, Eigen::Vector3d(1, 2, -0.5));
  set_axis(4, JointType::Revolute, Eigen::Vector3d(0, -1, 0));
  robot.joints[5].type = JointType::Prismatic;  // along z, with axis_is_z
  for (int i : {2, 5}) {
    robot.q_min[i] = robot.joints[i].lower = -0.2;
    robot.q_max[i] = robot.joints[i].upper = 0.2;
  }
  return robot;
}

// dynamics_terms and forward_dynamics_from_terms against independent reference paths: M from
// the link Jacobians, gravity and the velocity terms from recursive Newton-Euler, and ddq from
// Eigen's Cholesky solve of those. For the Panda and for a chain with general axes and
// prismatic joints, including a first joint that is prismatic, and a five-joint chain.
TEST(Dynamics, DynamicsTermsMatchReferencePaths) {
  RobotModel prismatic_first = mixed_chain();
  prismatic_first.joints[0].type = JointType::Prismatic;
  prismatic_first.joints[0].axis = Eigen::Vector3d(0.6, 0, 0.8);
  prismatic_first.joints[0].axis_is_z = false;
  prismatic_first.q_min[0] = prismatic_first.joints[0].lower = -0.3;
  prismatic_first.q_max[0] = prismatic_first.joints[0].upper = 0.3;
  RobotModel five_joints = mixed_chain();  // a chain of another length than seven
  five_joints.dof = 5;
  five_joints.joints.resize(5);
  five_joints.bodies.resize(5);
  std::mt19937_64 rng(20);
  for (const RobotModel& robot : {test::panda(), mixed_chain(), prismatic_first, five_joints}) {
    RobotData terms(robot), reference(robot);
    const int n = robot.dof;
    for (int trial = 0; trial < 200; ++trial) {
      const State s = random_state(robot, rng);
      JointVector tau(n);
      for (int i = 0; i < n; ++i)
        tau[i] = std::uniform_real_distribution<double>(-1, 1)(rng) * robot.tau_max[i];
      dynamics_terms(robot, terms, s.q, s.dq);
      const JointVector& ddq = forward_dynamics_from_terms(terms, tau);

      const JointMatrix M = mass_matrix_from_jacobians(robot, s.q);
      const JointVector g = gravity_torques(robot, reference, s.q);
      const JointVector h = rnea(robot, reference, s.q, s.dq, JointVector::Zero(n), false, true);
      const JointVector expected = Eigen::MatrixXd(M).llt().solve(tau - g - h);

      EXPECT_LT((terms.M - M).norm(), 1e-10 * M.norm()) << "trial " << trial;
      EXPECT_LT((terms.M - terms.M.transpose()).norm(), 1e-14);
      EXPECT_LT((terms.gravity - g).norm(), 1e-10 * std::max(1.0, g.norm())) << "trial " << trial;
      EXPECT_LT((terms.h - h).norm(), 1e-10 * std::max(1.0, h.norm())) << "trial " << trial;
      EXPECT_LT((ddq - expected).norm(), 1e-10 * std::max(1.0, expected.norm()))
          << "trial " << trial;
      // The factor reproduces M.
      const JointMatrix U = terms.llt_upper.triangularView<Eigen::Upper>();
      EXPECT_LT((U.transpose() * U - terms.M).norm(), 1e-12 * M.norm());
      // The one-call forms agree with the shared pass.
      EXPECT_LT((mass_matrix(robot, reference, s.q) - terms.M).norm(), 1e-12 * M.norm());
      const JointVector ddq_again = forward_dynamics(robot, reference, s.q, s.dq, tau);
      EXPECT_LT((ddq_again - ddq).norm(), 1e-12 * std::max(1.0, ddq.norm()));
      // And inverse dynamics inverts them.
      const JointVector tau_back = inverse_dynamics(robot, reference, s.q, s.dq, ddq);
      EXPECT_LT((tau_back - tau).norm(), 1e-9 * std::max(1.0, tau.norm())) << "trial " << trial;
    }
  }
}

// A one-joint chain: the smallest size of the fixed-size Cholesky.
TEST(Dynamics, SingleJointChain) {
  RobotModel robot = test::panda();
  robot.dof = 1;
  robot.joints.resize(1);
  robot.bodies.resize(1);
  RobotData data(robot);
  JointVector q(1), dq(1), tau(1);
  q << 0.4;
  dq << 0.7;
  tau << 2.0;
  dynamics_terms(robot, data, q, dq);
  const JointVector ddq = forward_dynamics_from_terms(data, tau);
  const JointMatrix M = mass_matrix_from_jacobians(robot, q);
  const JointVector g = gravity_torques(robot, data, q);
  const JointVector h = rnea(robot, data, q, dq, JointVector::Zero(1), false, true);
  EXPECT_NEAR(ddq[0], (tau[0] - g[0] - h[0]) / M(0, 0), 1e-12 * std::abs(ddq[0]));
}

TEST(Dynamics, SharedTermsDoNotAllocate) {
  const RobotModel& robot = test::panda();
  RobotData data(robot);
  std::mt19937_64 rng(21);
  const State s = random_state(robot, rng);
  const JointVector tau = JointVector::Constant(7, 1.0);
  LAZYBOE_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const long before = test::allocations.load();
  for (int k = 0; k < 10; ++k) {
    dynamics_terms(robot, data, s.q, s.dq);
    forward_dynamics_from_terms(data, tau);
  }
  EXPECT_EQ(test::allocations.load() - before, 0);
}

}  // namespace
}  // namespace lazyboe
