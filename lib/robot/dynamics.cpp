#include "lazyboe/robot/dynamics.h"

#include <cmath>
#include <type_traits>

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

// The per-tick path below (dynamics_terms, mass_matrix, the Cholesky factor) works with
// inertias about body origins (OriginInertia) instead of about centres of mass, and uses that a
// joint axis is often exactly z (Joint::axis_is_z, as in update_joint_poses): a dot product with
// the axis is then one coordinate and a cross product two products.

// R v, written out (in add_child_inertia this gave fewer instructions than Eigen's product).
inline Eigen::Vector3d rotate(const Eigen::Matrix3d& R, const Eigen::Vector3d& v) {
  return Eigen::Vector3d(R(0, 0) * v.x() + R(0, 1) * v.y() + R(0, 2) * v.z(),
                         R(1, 0) * v.x() + R(1, 1) * v.y() + R(1, 2) * v.z(),
                         R(2, 0) * v.x() + R(2, 1) * v.y() + R(2, 2) * v.z());
}

// axis . v
inline double along_axis(const Joint& j, const Eigen::Vector3d& v) {
  return j.axis_is_z ? v.z() : j.axis.dot(v);
}

// axis x v
inline Eigen::Vector3d axis_cross(const Joint& j, const Eigen::Vector3d& v) {
  return j.axis_is_z ? Eigen::Vector3d(-v.y(), v.x(), 0.0) : Eigen::Vector3d(j.axis.cross(v));
}

// Adds `child` (about its own origin, in its frame; X = child frame in `into`'s frame) to
// `into`. With h' = R h_child and u = m_child p + h' (the first moment it adds):
//   I += R I_child R^T + (m |p|^2 + 2 p.h') 1 - u p^T - p h'^T,
// which is symmetric, so only the upper triangle is computed.
inline void add_child_inertia(OriginInertia& into, const OriginInertia& child, const Pose& X) {
  const Eigen::Matrix3d& R = X.R;
  const Eigen::Vector3d& p = X.p;
  const Eigen::Matrix3d& I = child.rotational;
  const double m = child.mass;
  const Eigen::Vector3d hr = rotate(R, child.first_moment);
  const Eigen::Vector3d u(m * p.x() + hr.x(), m * p.y() + hr.y(), m * p.z() + hr.z());
  const double shift = m * (p.x() * p.x() + p.y() * p.y() + p.z() * p.z()) +
                       2.0 * (p.x() * hr.x() + p.y() * hr.y() + p.z() * hr.z());
  double T[3][3];  // R I
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) T[r][k] = R(r, 0) * I(0, k) + R(r, 1) * I(1, k) + R(r, 2) * I(2, k);
  }
  Eigen::Matrix3d& J = into.rotational;
  for (int r = 0; r < 3; ++r) {
    for (int c = r; c < 3; ++c) {
      const double rir = T[r][0] * R(c, 0) + T[r][1] * R(c, 1) + T[r][2] * R(c, 2);
      const double value = J(r, c) + (rir - u[r] * p[c] - p[r] * hr[c] + (r == c ? shift : 0.0));
      J(r, c) = value;
      J(c, r) = value;
    }
  }
  into.mass += m;
  into.first_moment += u;
}

// Columns of M from the composite inertias (the composite-rigid-body algorithm): the wrench
// that gives subtree i a unit acceleration of joint i, carried back to each ancestor joint.
//
// With with_gravity, also the gravity torques (data.gravity): joint i holds the weight of its
// subtree, m g at the centre of mass, so g_i = -(a x h) . g for a revolute joint and -m a . g
// for a prismatic one (h the composite's first moment, a the axis, g gravity, in one frame).
// That is minus the column's force f dotted with gravity, and f is already carried to body 1's
// frame, where gravity is rotated once.
void mass_matrix_from_composites(const RobotModel& model, RobotData& data, bool with_gravity) {
  const int n = model.dof;
  if (n == 0) return;
  JointMatrix& M = data.M;
  const Eigen::Vector3d g0 = data.joint_pose[0].R.transpose() * model.gravity;
  const Eigen::Vector3d g1 = n > 1 ? Eigen::Vector3d(data.joint_pose[1].R.transpose() * g0) : g0;
  // Row 0 is taken in body 1's frame: with X = joint_pose[1] and a = joint 0's axis, the
  // wrench (f, m) at body 1's origin gives a . (R m + p x R f) = m . R^T a + f . R^T (a x p)
  // about a revolute joint 0, and f . R^T a along a prismatic one. That saves the last
  // transform of every column.
  Eigen::Vector3d top_m = Eigen::Vector3d::Zero(), top_f = Eigen::Vector3d::Zero();
  if (n > 1) {
    const Joint& j0 = model.joints[0];
    const Pose& X = data.joint_pose[1];
    if (j0.type == JointType::Revolute) {
      top_m = X.R.transpose() * j0.axis;
      top_f = X.R.transpose() * j0.axis.cross(X.p);
    } else {
      top_f = X.R.transpose() * j0.axis;
    }
  }
  for (int i = 0; i < n; ++i) {
    const Joint& ji = model.joints[i];
    const OriginInertia& c = data.composite[i];
    Eigen::Vector3d f, m;  // force, and moment about body i's origin
    if (ji.type == JointType::Revolute) {
      f = axis_cross(ji, c.first_moment);
      m = ji.axis_is_z ? Eigen::Vector3d(c.rotational.col(2))
                       : Eigen::Vector3d(c.rotational * ji.axis);
      M(i, i) = along_axis(ji, m);
    } else {
      f = c.mass * ji.axis;
      m = c.first_moment.cross(ji.axis);
      M(i, i) = along_axis(ji, f);
    }
    for (int k = i; k > 1; --k) {
      const Pose& X = data.joint_pose[k];
      f = X.R * f;
      m = X.R * m + X.p.cross(f);
      const Joint& jk = model.joints[k - 1];
      const double value = jk.type == JointType::Revolute ? along_axis(jk, m) : along_axis(jk, f);
      M(k - 1, i) = value;
      M(i, k - 1) = value;
    }
    if (i > 0) {
      const double value = top_m.dot(m) + top_f.dot(f);
      M(0, i) = value;
      M(i, 0) = value;
    }
    if (with_gravity) data.gravity[i] = -f.dot(i > 0 ? g1 : g0);
  }
}

// Composite inertias alone (for mass_matrix).
void composite_inertias(const RobotModel& model, RobotData& data) {
  const int n = model.dof;
  for (int i = n - 1; i >= 0; --i) {
    data.composite[i] = model.bodies[i].about_origin;
    if (i + 1 < n)
      add_child_inertia(data.composite[i], data.composite[i + 1], data.joint_pose[i + 1]);
  }
}

// One pass over the joint poses for dynamics_terms. Forward: velocities and the accelerations
// they cause with ddq = 0 and no gravity, and each body's wrench about its origin,
//   f = m a + dw x h + w x (w x h),  n = I_O dw + w x (I_O w) + h x a.
// Backward: the composite inertias and the joint torques of the accumulated wrenches
// (data.h = C(q, dq) dq + tau_f(dq)).
void velocity_terms_and_composites(const RobotModel& model, RobotData& data,
                                   const JointVectorRef& dq) {
  const int n = model.dof;
  Eigen::Vector3d w_parent = Eigen::Vector3d::Zero();
  Eigen::Vector3d dw_parent = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_parent = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Joint& j = model.joints[i];
    const Pose& X = data.joint_pose[i];
    const Eigen::Matrix3d Rt = X.R.transpose();
    Eigen::Vector3d w_in, w, dw, a;
    if (i == 0) {  // the base is at rest (gravity is not part of these terms)
      w_in.setZero();
      w.setZero();
      dw.setZero();
      a.setZero();
    } else {
      w_in = Rt * w_parent;
      w = w_in;
      dw = Rt * dw_parent;
      a = Rt * (dw_parent.cross(X.p) + w_parent.cross(w_parent.cross(X.p)) + a_parent);
    }
    if (j.type == JointType::Revolute) {
      if (j.axis_is_z) {
        w.z() += dq[i];
        dw.x() += w_in.y() * dq[i];
        dw.y() -= w_in.x() * dq[i];
      } else {
        w += j.axis * dq[i];
        dw += w_in.cross(j.axis * dq[i]);
      }
    } else {
      a += 2.0 * w.cross(j.axis * dq[i]);
    }
    OriginInertia& body = data.composite[i];
    body = model.bodies[i].about_origin;
    const Eigen::Vector3d& h = body.first_moment;
    const Eigen::Matrix3d& I = body.rotational;
    data.force[i] = body.mass * a + dw.cross(h) + w.cross(w.cross(h));
    data.moment[i] = I * dw + w.cross(I * w) + h.cross(a);
    w_parent = w;
    dw_parent = dw;
    a_parent = a;
  }
  Eigen::Vector3d f_child = Eigen::Vector3d::Zero(), n_child = Eigen::Vector3d::Zero();
  for (int i = n - 1; i >= 0; --i) {
    Eigen::Vector3d f = data.force[i];
    Eigen::Vector3d m = data.moment[i];
    OriginInertia& c = data.composite[i];
    if (i + 1 < n) {
      const Pose& Xc = data.joint_pose[i + 1];
      const Eigen::Vector3d fc = Xc.R * f_child;
      f += fc;
      m += Xc.R * n_child + Xc.p.cross(fc);
      add_child_inertia(c, data.composite[i + 1], Xc);
    }
    const Joint& j = model.joints[i];
    data.h[i] = (j.type == JointType::Revolute ? along_axis(j, m) : along_axis(j, f)) +
                friction_torque(j.friction, dq[i]);
    f_child = f;
    n_child = m;
  }
}

// M = U^T U (Cholesky, replacing Eigen's dynamic-size LLT), column by column of U so that the inner
// products run over contiguous memory; `stride` is the column stride of M and U. N is the number of
// joints: a compile-time size lets the compiler unroll the short loops (see the dispatch in
// cholesky()).
template <int N>
void cholesky_fixed(const double* __restrict M, double* __restrict U,
                    double* __restrict inv_diagonal, int stride) {
#pragma GCC unroll 12
  for (int j = 0; j < N; ++j) {
    const double* uj = U + j * stride;
#pragma GCC unroll 12
    for (int i = 0; i < j; ++i) {
      const double* ui = U + i * stride;
      double s = M[i + j * stride];
#pragma GCC unroll 12
      for (int k = 0; k < i; ++k) s -= ui[k] * uj[k];
      U[i + j * stride] = s * inv_diagonal[i];
    }
    double d = M[j + j * stride];
#pragma GCC unroll 12
    for (int k = 0; k < j; ++k) d -= uj[k] * uj[k];
    U[j + j * stride] = std::sqrt(d);
    inv_diagonal[j] = 1.0 / U[j + j * stride];
  }
}

// Solves U^T U x = b in place.
template <int N>
void cholesky_solve_fixed(const double* __restrict U, const double* __restrict inv_diagonal,
                          int stride, double* __restrict x) {
#pragma GCC unroll 12
  for (int i = 0; i < N; ++i) {  // U^T y = b
    const double* ui = U + i * stride;
    double s = x[i];
#pragma GCC unroll 12
    for (int k = 0; k < i; ++k) s -= ui[k] * x[k];
    x[i] = s * inv_diagonal[i];
  }
#pragma GCC unroll 12
  for (int i = N - 1; i >= 0; --i) {  // U x = y, column by column
    const double* ui = U + i * stride;
    x[i] *= inv_diagonal[i];
#pragma GCC unroll 12
    for (int k = 0; k < i; ++k) x[k] -= ui[k] * x[i];
  }
}

// Calls f(std::integral_constant<int, n>) for 1 <= n <= kMaxDof.
template <typename F>
void with_fixed_size(int n, F&& f) {
  static_assert(kMaxDof == 12, "extend the cases below");
  switch (n) {
    case 1:
      return f(std::integral_constant<int, 1>());
    case 2:
      return f(std::integral_constant<int, 2>());
    case 3:
      return f(std::integral_constant<int, 3>());
    case 4:
      return f(std::integral_constant<int, 4>());
    case 5:
      return f(std::integral_constant<int, 5>());
    case 6:
      return f(std::integral_constant<int, 6>());
    case 7:
      return f(std::integral_constant<int, 7>());
    case 8:
      return f(std::integral_constant<int, 8>());
    case 9:
      return f(std::integral_constant<int, 9>());
    case 10:
      return f(std::integral_constant<int, 10>());
    case 11:
      return f(std::integral_constant<int, 11>());
    case 12:
      return f(std::integral_constant<int, 12>());
    default:
      return;
  }
}

// data.llt_upper and data.llt_inv_diagonal from data.M.
void cholesky(RobotData& data, int n) {
  with_fixed_size(n, [&](auto size) {
    cholesky_fixed<decltype(size)::value>(data.M.data(), data.llt_upper.data(),
                                          data.llt_inv_diagonal.data(), n);
  });
}

void cholesky_solve(const RobotData& data, int n, double* x) {
  with_fixed_size(n, [&](auto size) {
    cholesky_solve_fixed<decltype(size)::value>(data.llt_upper.data(), data.llt_inv_diagonal.data(),
                                                n, x);
  });
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
  composite_inertias(model, data);
  mass_matrix_from_composites(model, data, false);
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
  dynamics_terms(model, data, q, dq);
  return forward_dynamics_from_terms(data, tau);
}

void dynamics_terms(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                    const JointVectorRef& dq) {
  update_joint_poses(model, data, q);
  velocity_terms_and_composites(model, data, dq);
  mass_matrix_from_composites(model, data, true);
  cholesky(data, model.dof);
}

const JointVector& forward_dynamics_from_terms(RobotData& data, const JointVectorRef& tau) {
  const int n = static_cast<int>(data.ddq.size());
  for (int i = 0; i < n; ++i) data.ddq[i] = tau[i] - data.gravity[i] - data.h[i];
  cholesky_solve(data, n, data.ddq.data());
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
