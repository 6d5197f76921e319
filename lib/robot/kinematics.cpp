#include "lazyboe/robot/kinematics.h"

#include <cmath>

#include "lazyboe/robot/sincos.h"

namespace lazyboe {

RobotData::RobotData(const RobotModel& model)
    : joint_pose(model.dof),
      body_pose(model.dof),
      omega(model.dof),
      domega(model.dof),
      acc(model.dof),
      force(model.dof),
      moment(model.dof),
      composite(model.dof),
      tau(JointVector::Zero(model.dof)),
      gravity(JointVector::Zero(model.dof)),
      friction(JointVector::Zero(model.dof)),
      ddq(JointVector::Zero(model.dof)),
      h(JointVector::Zero(model.dof)),
      M(JointMatrix::Zero(model.dof, model.dof)),
      llt_upper(JointMatrix::Zero(model.dof, model.dof)),
      llt_inv_diagonal(JointVector::Zero(model.dof)) {}

void update_joint_poses(const RobotModel& model, RobotData& data, const JointVectorRef& q) {
  for (int i = 0; i < model.dof; ++i) {
    const Joint& j = model.joints[i];
    Pose& X = data.joint_pose[i];
    if (j.type == JointType::Revolute && j.axis_is_z) {
      // origin.R * Rz(q): only the first two columns mix.
      double s, c;
      joint_sincos(q[i], s, c);
      X.R.col(0) = c * j.origin.R.col(0) + s * j.origin.R.col(1);
      X.R.col(1) = c * j.origin.R.col(1) - s * j.origin.R.col(0);
      X.R.col(2) = j.origin.R.col(2);
      X.p = j.origin.p;
    } else if (j.type == JointType::Revolute) {
      X.R.noalias() = j.origin.R * Eigen::AngleAxisd(q[i], j.axis).toRotationMatrix();
      X.p = j.origin.p;
    } else {
      X.R = j.origin.R;
      X.p = j.origin.p + j.origin.R * (j.axis * q[i]);
    }
  }
}

void forward_kinematics(const RobotModel& model, RobotData& data, const JointVectorRef& q) {
  update_joint_poses(model, data, q);
  data.body_pose[0] = data.joint_pose[0];
  for (int i = 1; i < model.dof; ++i)
    data.body_pose[i] = data.body_pose[i - 1] * data.joint_pose[i];
}

Pose link_pose(const RobotModel& model, const RobotData& data, int link) {
  const Link& l = model.links[link];
  return l.body < 0 ? l.in_body : data.body_pose[l.body] * l.in_body;
}

Eigen::Vector3d link_linear_velocity(const RobotModel& model, const RobotData& data, int link,
                                     const JointVectorRef& dq) {
  const Eigen::Vector3d p = link_pose(model, data, link).p;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int i = 0; i <= model.links[link].body; ++i) {
    const Pose& joint = data.body_pose[i];
    const Eigen::Vector3d axis = joint.R * model.joints[i].axis;
    v += dq[i] * (model.joints[i].type == JointType::Prismatic ? axis : axis.cross(p - joint.p));
  }
  return v;
}

}  // namespace lazyboe
