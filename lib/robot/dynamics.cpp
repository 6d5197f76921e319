#include "robot/dynamics.h"

#include <cmath>

namespace lazyboe {
namespace {

// RNEA over the joint poses already in data.joint_pose; writes data.tau.
void rnea_from_poses(const RobotModel& model, RobotData& data, const JointVectorRef& dq,
                     const JointVectorRef& ddq, bool with_gravity, bool with_friction) {
  const int n = model.dof;
  Eigen::Vector3d w_parent = Eigen::Vector3d::Zero();
  Eigen::Vector3d dw_parent = Eigen::Vector3d::Zero();
  // Gravity enters as an upward acceleration of the base.
  Eigen::Vector3d a_parent =
      with_gravity ? Eigen::Vector3d(-model.gravity) : Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Joint& j = model.joints[i];
    const Pose& X = data.joint_pose[i];
    const BodyInertia& body = model.bodies[i];
    const Eigen::Matrix3d Rt = X.R.transpose();
    const Eigen::Vector3d w_in = Rt * w_parent;
    Eigen::Vector3d w = w_in, dw = Rt * dw_parent;
    Eigen::Vector3d a =
        Rt * (a_parent + dw_parent.cross(X.p) + w_parent.cross(w_parent.cross(X.p)));
    const Eigen::Vector3d s_dq = j.axis * dq[i];
    if (j.type == JointType::Revolute) {
      w += s_dq;
      dw += w_in.cross(s_dq) + j.axis * ddq[i];
    } else {
      a += 2.0 * w.cross(s_dq) + j.axis * ddq[i];
    }
    const Eigen::Vector3d acc_com = a + dw.cross(body.com) + w.cross(w.cross(body.com));
    data.force[i] = body.mass * acc_com;
    data.moment[i] = body.inertia_com * dw + w.cross(body.inertia_com * w);
    data.omega[i] = w;
    data.domega[i] = dw;
    data.acc[i] = a;
    w_parent = w;
    dw_parent = dw;
    a_parent = a;
  }
  Eigen::Vector3d f_child = Eigen::Vector3d::Zero(), n_child = Eigen::Vector3d::Zero();
  for (int i = n - 1; i >= 0; --i) {
    const BodyInertia& body = model.bodies[i];
    // Wrench of the subtree at body i's origin; the child wrench is moved from its origin.
    Eigen::Vector3d f = data.force[i];
    Eigen::Vector3d m = data.moment[i] + body.com.cross(data.force[i]);
    if (i + 1 < n) {
      const Pose& Xc = data.joint_pose[i + 1];
      const Eigen::Vector3d fc = Xc.R * f_child;
      f += fc;
      m += Xc.R * n_child + Xc.p.cross(fc);
    }
    const Joint& j = model.joints[i];
    data.tau[i] = j.type == JointType::Revolute ? j.axis.dot(m) : j.axis.dot(f);
    f_child = f;
    n_child = m;
  }
  if (with_friction) {
    for (int i = 0; i < n; ++i) data.tau[i] += friction_torque(model.joints[i].friction, dq[i]);
  }
}

// Composite-rigid-body algorithm over the joint poses already in data.joint_pose.
void crba_from_poses(const RobotModel& model, RobotData& data) {
  const int n = model.dof;
  for (int i = n - 1; i >= 0; --i) {
    data.composite[i] = model.bodies[i];
    if (i + 1 < n) {
      const Pose& Xc = data.joint_pose[i + 1];
      const BodyInertia& c = data.composite[i + 1];
      merge_inertia(data.composite[i], c.mass, Xc * c.com, Xc.R * c.inertia_com * Xc.R.transpose());
    }
  }
  for (int i = 0; i < n; ++i) {
    const Joint& ji = model.joints[i];
    const BodyInertia& c = data.composite[i];
    // Wrench at body i's origin that gives the subtree a unit acceleration of joint i.
    Eigen::Vector3d f, m;
    if (ji.type == JointType::Revolute) {
      f = c.mass * ji.axis.cross(c.com);
      const Eigen::Matrix3d inertia_origin =
          c.inertia_com +
          c.mass * (c.com.squaredNorm() * Eigen::Matrix3d::Identity() - c.com * c.com.transpose());
      m = inertia_origin * ji.axis;
      data.M(i, i) = ji.axis.dot(m);
    } else {
      f = c.mass * ji.axis;
      m = c.mass * c.com.cross(ji.axis);
      data.M(i, i) = ji.axis.dot(f);
    }
    for (int k = i; k > 0; --k) {
      const Pose& X = data.joint_pose[k];
      f = X.R * f;
      m = X.R * m + X.p.cross(f);
      const Joint& jk = model.joints[k - 1];
      const double value = jk.type == JointType::Revolute ? jk.axis.dot(m) : jk.axis.dot(f);
      data.M(k - 1, i) = value;
      data.M(i, k - 1) = value;
    }
  }
}

}  // namespace

double friction_torque(const Friction& friction, double dq) {
  switch (friction.model) {
    case FrictionModel::None:
      return 0;
    case FrictionModel::Sigmoid:
      return friction.a / (1 + std::exp(-friction.b * (dq + friction.c))) - friction.offset;
    case FrictionModel::ViscousCoulomb:
      return friction.a * std::tanh(dq / friction.c) + friction.b * dq;
  }
  return 0;
}

const JointVector& rnea(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                        const JointVectorRef& dq, const JointVectorRef& ddq, bool with_gravity,
                        bool with_friction) {
  update_joint_poses(model, data, q);
  rnea_from_poses(model, data, dq, ddq, with_gravity, with_friction);
  return data.tau;
}

const JointVector& inverse_dynamics(const RobotModel& model, RobotData& data,
                                    const JointVectorRef& q, const JointVectorRef& dq,
                                    const JointVectorRef& ddq) {
  return rnea(model, data, q, dq, ddq, true, true);
}

const JointMatrix& mass_matrix(const RobotModel& model, RobotData& data, const JointVectorRef& q) {
  update_joint_poses(model, data, q);
  crba_from_poses(model, data);
  return data.M;
}

const JointVector& gravity_torques(const RobotModel& model, RobotData& data,
                                   const JointVectorRef& q) {
  data.ddq.setZero();
  rnea(model, data, q, data.ddq, data.ddq, true, false);
  data.gravity = data.tau;
  return data.gravity;
}

const JointVector& friction_torques(const RobotModel& model, RobotData& data,
                                    const JointVectorRef& dq) {
  for (int i = 0; i < model.dof; ++i) {
    data.friction[i] = friction_torque(model.joints[i].friction, dq[i]);
  }
  return data.friction;
}

const JointVector& forward_dynamics(const RobotModel& model, RobotData& data,
                                    const JointVectorRef& q, const JointVectorRef& dq,
                                    const JointVectorRef& tau) {
  update_joint_poses(model, data, q);
  data.ddq.setZero();
  rnea_from_poses(model, data, dq, data.ddq, true, true);  // h = C dq + g + tau_f
  data.h = tau - data.tau;
  crba_from_poses(model, data);
  data.llt.compute(data.M);
  data.ddq = data.llt.solve(data.h);
  return data.ddq;
}

void dynamics_terms(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                    const JointVectorRef& dq) {
  update_joint_poses(model, data, q);
  crba_from_poses(model, data);
  data.llt.compute(data.M);
  // Gravity torque of joint i: the weight of everything it carries, at the subtree's centre of
  // mass (data.composite, in body i's frame), about the joint axis.
  Eigen::Vector3d g = model.gravity;  // gravity in the current body frame
  for (int i = 0; i < model.dof; ++i) {
    const Joint& j = model.joints[i];
    g = data.joint_pose[i].R.transpose() * g;
    const BodyInertia& c = data.composite[i];
    data.gravity[i] = j.type == JointType::Revolute ? -j.axis.dot(c.com.cross(c.mass * g))
                                                    : -j.axis.dot(c.mass * g);
  }
  data.ddq.setZero();
  rnea_from_poses(model, data, dq, data.ddq, false, true);
  data.h = data.tau;
}

const JointVector& forward_dynamics_from_terms(RobotData& data, const JointVectorRef& tau) {
  data.ddq = data.llt.solve(tau - data.gravity - data.h);
  return data.ddq;
}

double kinetic_energy(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                      const JointVectorRef& dq) {
  const JointMatrix& M = mass_matrix(model, data, q);
  return 0.5 * dq.dot(M * dq);
}

double potential_energy(const RobotModel& model, RobotData& data, const JointVectorRef& q) {
  forward_kinematics(model, data, q);
  double energy = 0;
  for (int i = 0; i < model.dof; ++i) {
    energy -= model.bodies[i].mass * model.gravity.dot(data.body_pose[i] * model.bodies[i].com);
  }
  return energy;
}

}  // namespace lazyboe
