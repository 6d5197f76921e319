// Small explicit types shared by the whole library: joint-space vectors with a fixed maximum
// size (stack storage, so the hot paths never allocate) and rigid poses.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lazyboe {

// Longest serial chain supported. Joint-space vectors live on the stack up to this size.
constexpr int kMaxDof = 12;

using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDof, 1>;
using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDof, kMaxDof>;
using JointVectorRef = Eigen::Ref<const Eigen::VectorXd>;

// A rigid transform x -> R x + p (child frame expressed in the parent frame).
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();

  Pose() = default;
  Pose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
      : R(rotation), p(translation) {}

  Pose operator*(const Pose& child) const { return Pose(R * child.R, R * child.p + p); }
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const { return R * point + p; }
  Pose inverse() const { return Pose(R.transpose(), -(R.transpose() * p)); }
  // Quaternion as [w, x, y, z].
  Eigen::Vector4d quaternion_wxyz() const {
    Eigen::Quaterniond qt(R);
    qt.normalize();
    if (qt.w() < 0) qt.coeffs() *= -1;  // one canonical sign for printing and comparing
    return Eigen::Vector4d(qt.w(), qt.x(), qt.y(), qt.z());
  }
};

// Roll-pitch-yaw as in URDF: R = Rz(yaw) * Ry(pitch) * Rx(roll).
inline Eigen::Matrix3d rotation_from_rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace lazyboe
