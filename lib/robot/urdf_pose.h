// A URDF pose as ours: shared by the URDF readers of the robot and of its collision geometry.
#pragma once

#include <urdf_model/pose.h>

#include "lazyboe/robot/types.h"

namespace lazyboe {

inline Pose pose_from_urdf(const urdf::Pose& pose) {
  Eigen::Quaterniond rotation(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  return Pose(rotation.normalized().toRotationMatrix(),
              Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z));
}

}  // namespace lazyboe
