// The robot description: a serial chain read from a URDF plus a robot config file (JSON) that
// adds what URDF cannot hold (read by robot_config.h's load_robot). Built once, then read-only
// and shared by every thread; per-thread scratch lives in RobotData (kinematics.h).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lazyboe/robot/robot_geometry.h"
#include "lazyboe/robot/types.h"

namespace lazyboe {

enum class JointType { Revolute, Prismatic };

// Joint friction torque as a function of joint velocity.
//   Sigmoid (Gaz et al. 2019): a/(1+exp(-b(dq+c))) - a/(1+exp(-b c))
//   ViscousCoulomb: a*tanh(dq/c) + b*dq   (a = Coulomb, b = viscous, c = smoothing velocity)
enum class FrictionModel { None, Sigmoid, ViscousCoulomb };
struct Friction {
  FrictionModel model = FrictionModel::None;
  double a = 0, b = 0, c = 0;
  double offset = 0;  // Sigmoid: a/(1+exp(-b c)), precomputed so that tau_f(0) = 0
};

// The default position range of a continuous joint, rad: [-2 pi, 2 pi].
constexpr double kContinuousRange = 6.283185307179586;

struct Joint {
  std::string name;
  JointType type = JointType::Revolute;
  Pose origin;                                      // parent body frame -> joint frame at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, in the joint (= child body) frame
  bool axis_is_z = true;                            // the common case, with a cheaper rotation
  double lower = 0, upper = 0;                      // position limits (rad or m)
  // A URDF `continuous` joint: a revolute joint planned within lower..upper, the config's
  // position_range (default kContinuousRange); no wrap-around (q and q + 2 pi are two states).
  bool continuous = false;
  double max_velocity = 0, max_acceleration = 0, max_jerk = 0;
  double max_effort = 0, max_torque_rate = 0;
  Friction friction;
};

// Inertia of a rigid body (or of a body with everything it carries) about the body's origin, in
// the body frame: what the composite-rigid-body pass merges and the Newton-Euler pass multiplies
// with. About the origin, merging needs no centre-of-mass shifts (spatial inertia as in
// Featherstone, "Rigid Body Dynamics Algorithms", 2008, ch. 2).
struct OriginInertia {
  double mass = 0;
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();  // mass times centre of mass
  Eigen::Matrix3d rotational = Eigen::Matrix3d::Zero();    // about the origin; symmetric
};

// Inertia of one moving body (its link plus every link fixed to it), in the body frame. Written
// only through merge_inertia, which keeps `about_origin` (what the dynamics use every tick) in
// step with the other three.
struct BodyInertia {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_com = Eigen::Matrix3d::Zero();  // about the centre of mass
  OriginInertia about_origin;                             // the same, about the body's origin
};

// "revolute", "continuous" or "prismatic", as the URDF says.
inline const char* joint_type_name(const Joint& j) {
  if (j.type == JointType::Prismatic) return "prismatic";
  return j.continuous ? "continuous" : "revolute";
}

// Adds a rigid body (mass, centre of mass, inertia about it; all in `into`'s frame) to `into`.
void merge_inertia(BodyInertia& into, double mass, const Eigen::Vector3d& com,
                   const Eigen::Matrix3d& inertia_com);

struct Link {
  std::string name;
  int body = -1;  // moving body the link is fixed to; -1 for the base
  Pose in_body;   // link frame in the body frame
};

// Joint-level controller used to simulate the robot following joint-velocity commands: a
// velocity-tracking law with model feed-forward,
//   tau = g(q) + [tau_f(v_cmd)] + ka a_cmd + kv (v_cmd - dq).
// There is deliberately no position loop: the end state is where the dynamics take the robot,
// not the integral of the commands, so it depends on the start state through the dynamics.
struct ControllerGains {
  bool present = false;  // the config has a "controller" section
  JointVector kv;        // velocity gain, Nm s/rad
  JointVector ka;        // acceleration feed-forward (a nominal joint inertia), kg m^2
  bool friction_feedforward = true;
};

// The files a robot was read from (the config, the URDF and its resources are its identity: a
// bundle's robot_hash).
struct RobotFiles {
  std::string config;                     // the robot config
  std::string urdf;                       // the URDF it names
  std::vector<std::string> resources;     // files the URDF names (meshes)
  std::vector<std::string> package_path;  // config "package_path", resolved: package:// folders
};

// The default box of start states for the edge bundle (config "sampling_region"; the joint
// limits when the config has none): what lazyboe-build samples and the sampling planners
// draw from unless told otherwise.
struct SamplingRegion {
  JointVector lower, upper;
};

// The model: the chain's kinematics, dynamics and limits, with what the robot config adds for
// the layers above it, each part in its own type: the collision geometry (collision layer), the
// controller gains (simulator), the sampling region (bundle build), and the files.
struct RobotModel {
  std::string name;
  RobotFiles files;
  int dof = 0;
  Eigen::Vector3d gravity{0, 0, -9.81};
  double control_rate = 1000;  // Hz

  std::vector<Joint> joints;               // chain order; joint i moves body i
  std::vector<BodyInertia> bodies;         // size dof
  std::vector<Link> links;                 // every link of the chain, base first
  std::vector<std::string> ignored_links;  // side branches behind moving joints

  RobotGeometry geometry;  // collision bodies, margin, allowed pairs (robot_geometry.h)

  ControllerGains controller;  // the simulator's joint controller
  SamplingRegion region;

  // Limits gathered as vectors for the validity checks.
  JointVector q_min, q_max, dq_max, ddq_max, dddq_max, tau_max, dtau_max;

  int link_index(const std::string& link_name) const;  // -1 when unknown
  // "unknown link 'x'" with the closest name ("did you mean") or else the links there are.
  std::string unknown_link(const std::string& link_name) const;
  int tip_link() const { return static_cast<int>(links.size()) - 1; }
};

}  // namespace lazyboe
