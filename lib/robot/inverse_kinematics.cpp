#include "lazyboe/robot/inverse_kinematics.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace lazyboe {

namespace {

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The link axis that must map onto free_axis (the accepted rotations keep it there).
Eigen::Vector3d held_axis(const PoseTarget& t) { return t.rotation.transpose() * t.free_axis; }

// The rotation (axis times angle, base frame) that takes the link's orientation R onto the
// nearest accepted one: for a free axis, the smallest rotation taking R b onto the axis.
Eigen::Vector3d orientation_residual(const PoseTarget& t, const Eigen::Matrix3d& R) {
  if (!t.has_free_axis) {
    const Eigen::AngleAxisd d(t.rotation * R.transpose());
    return d.angle() * d.axis();
  }
  const Eigen::Vector3d v = R * held_axis(t);
  const Eigen::Vector3d c = v.cross(t.free_axis);
  const double s = c.norm();
  if (s < 1e-12) {  // aligned, or opposite: any perpendicular axis
    if (v.dot(t.free_axis) > 0) return Eigen::Vector3d::Zero();
    return M_PI * v.unitOrthogonal();
  }
  return angle_between(v, t.free_axis) * c / s;
}

}  // namespace

PoseError pose_error(const PoseTarget& t, const Pose& pose) {
  PoseError e;
  e.position = (pose.p - t.position).norm();
  if (!t.has_orientation) return e;
  e.orientation = t.has_free_axis ? angle_between(pose.R * held_axis(t), t.free_axis)
                                  : Eigen::AngleAxisd(t.rotation.transpose() * pose.R).angle();
  return e;
}

bool solve_ik(const RobotModel& robot, RobotData& data, const PoseTarget& t, JointVector& q,
              double fraction, int max_iterations) {
  const int n = robot.dof, rows = t.has_orientation ? 6 : 3;
  const int body = robot.links[t.link].body;
  // Orientation rows in metres: a radian of error weighs as much as this many metres.
  const double weight = t.position_tolerance / t.orientation_tolerance;
  constexpr double kDamping = 0.05, kMaxStep = 0.3;  // m, rad per iteration
  const double inset = 1e-6;
  // rows x n (3 rows for a position target): fixed capacity, no allocation.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, kMaxDof> J(rows, n);
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> e(rows);
  for (int it = 0; it < max_iterations; ++it) {
    forward_kinematics(robot, data, q);
    const Pose pose = link_pose(robot, data, t.link);
    const PoseError err = pose_error(t, pose);
    if (err.position <= fraction * t.position_tolerance &&
        (!t.has_orientation || err.orientation <= fraction * t.orientation_tolerance))
      return true;
    J.setZero();
    for (int i = 0; i <= body; ++i) {
      const Pose& joint = data.body_pose[i];
      const Eigen::Vector3d a = joint.R * robot.joints[i].axis;
      const bool prismatic = robot.joints[i].type == JointType::Prismatic;
      J.block<3, 1>(0, i) = prismatic ? a : Eigen::Vector3d(a.cross(pose.p - joint.p));
      if (rows == 6 && !prismatic) J.block<3, 1>(3, i) = weight * a;
    }
    e.head<3>() = t.position - pose.p;
    if (rows == 6) e.tail<3>() = weight * orientation_residual(t, pose.R);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> A = J * J.transpose();
    A.diagonal().array() += kDamping * kDamping;
    JointVector step(n);
    step.noalias() = J.transpose() * A.llt().solve(e);
    const double longest = step.cwiseAbs().maxCoeff();
    if (longest > kMaxStep) step *= kMaxStep / longest;
    q += step;
    for (int i = 0; i < n; ++i)
      q[i] = std::clamp(q[i], robot.q_min[i] + inset, robot.q_max[i] - inset);
  }
  return false;
}

}  // namespace lazyboe
