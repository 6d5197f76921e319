// Numerical inverse kinematics of one link: damped least squares on the geometric Jacobian
// (Wampler 1986; Buss, "Introduction to inverse kinematics with Jacobian transpose, pseudoinverse
// and damped least squares methods", 2004), within the joint limits. For pose goals: their
// reachability, and joint configurations a direct command can aim at.
#pragma once

#include "lazyboe/robot/kinematics.h"

namespace lazyboe {

// A pose for a link, in the base frame, to within tolerances. Orientation: none (a position
// goal), all of it, or all but the rotations about one base-frame axis (free_axis, e.g. any yaw
// about the vertical).
struct PoseTarget {
  int link = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool has_orientation = false;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  bool has_free_axis = false;
  Eigen::Vector3d free_axis = Eigen::Vector3d::UnitZ();  // unit, base frame
  double position_tolerance = 0.01;                      // m
  double orientation_tolerance = 0.05;                   // rad
};

struct PoseError {
  double position = 0;     // m
  double orientation = 0;  // rad: the smallest rotation onto an accepted orientation
  bool within(const PoseTarget& t) const {
    return position <= t.position_tolerance &&
           (!t.has_orientation || orientation <= t.orientation_tolerance);
  }
};

// The error of a link pose against the target.
PoseError pose_error(const PoseTarget& target, const Pose& pose);

// From q (the seed), moves q to a configuration strictly inside the joint limits whose link pose
// is within `fraction` of both tolerances; false when it does not get there in max_iterations.
bool solve_ik(const RobotModel& robot, RobotData& data, const PoseTarget& target, JointVector& q,
              double fraction = 0.2, int max_iterations = 200);

}  // namespace lazyboe
