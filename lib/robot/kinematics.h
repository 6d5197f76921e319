// Forward kinematics and the per-thread workspace of the robot algorithms.
#pragma once

#include <vector>

#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

// Scratch space for one thread: sized once from the model, then reused without allocating.
struct RobotData {
  explicit RobotData(const RobotModel& model);

  std::vector<Pose> joint_pose;  // body i in body i-1 (the base for i = 0), at the last q
  std::vector<Pose> body_pose;   // body i in the base frame (after forward_kinematics)

  // Recursive Newton-Euler, in body frames.
  std::vector<Eigen::Vector3d> omega, domega, acc, force, moment;
  // Composite rigid bodies for the mass matrix and the gravity torques: body i and everything
  // it carries.
  std::vector<OriginInertia> composite;

  JointVector tau, gravity, friction, ddq, h;
  JointMatrix M;
  // Cholesky factor of M from dynamics_terms: M = U^T U with U upper triangular (the strictly
  // lower part is not used), and the inverses of U's diagonal.
  JointMatrix llt_upper;
  JointVector llt_inv_diagonal;
};

// Pose of each joint's body relative to its parent (data.joint_pose); no world poses.
void update_joint_poses(const RobotModel& model, RobotData& data, const JointVectorRef& q);

// World pose of every moving body (data.body_pose); also updates data.joint_pose.
void forward_kinematics(const RobotModel& model, RobotData& data, const JointVectorRef& q);

// Pose of a link in the base frame, from the body poses of the last forward_kinematics.
Pose link_pose(const RobotModel& model, const RobotData& data, int link);

// Linear velocity of a link's origin in the base frame for joint velocities dq, from the body
// poses of the last forward_kinematics (the geometric Jacobian's upper rows times dq).
Eigen::Vector3d link_linear_velocity(const RobotModel& model, const RobotData& data, int link,
                                     const JointVectorRef& dq);

}  // namespace lazyboe
