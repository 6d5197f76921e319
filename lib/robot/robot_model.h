// The robot description: a serial chain read from a URDF plus a robot config file (JSON) that
// adds what URDF cannot hold (read by robot_config.h's load_robot). Built once, then read-only
// and shared by every thread; per-thread scratch lives in RobotData (kinematics.h).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

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

// Inertia of one moving body (its link plus every link fixed to it), in the body frame.
struct BodyInertia {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_com = Eigen::Matrix3d::Zero();  // about the centre of mass
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

struct TriangleMesh;  // lazyboe/collision/mesh.h

enum class ShapeType { Sphere, Box, Cylinder, Capsule, Mesh };
struct Shape {
  ShapeType type = ShapeType::Sphere;
  double radius = 0;                               // sphere, cylinder, capsule
  double length = 0;                               // cylinder, capsule: along local z
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // box: full extents
  std::shared_ptr<const TriangleMesh> mesh;        // mesh: triangles about the shape's frame
  bool convex = false;  // mesh: a convex hull, checked as one convex shape (GJK), not a BVH
};
const char* shape_type_name(ShapeType type);

// How a link whose URDF collision geometry is a mesh is checked: a capsule fitted around the
// mesh (the fast primitive checks; conservative by its over-approximation), the mesh itself
// (FCL's bounding volume hierarchy: exact, slower), or its convex hull (Qhull; one convex shape
// for GJK: exact for a convex part, never less conservative than the mesh, and fast).
enum class MeshRepresentation { Fitted, Exact, Convex };
const char* mesh_representation_name(MeshRepresentation representation);
// The inverse; throws Error("<where>: unknown mesh representation '<name>' (expected fitted,
// exact or convex)").
MeshRepresentation parse_mesh_representation(const std::string& name, const std::string& where);

struct CollisionBody {
  std::string name;
  int link = 0;  // index into RobotModel::links
  Shape shape;
  Pose in_link;  // shape frame in the link frame
  // For URDF mesh geometry: the file, how it is represented, and for a fitted shape the
  // largest distance from its surface to the mesh (m).
  std::string mesh_file;
  MeshRepresentation representation = MeshRepresentation::Fitted;
  double over_approximation = 0;
  // A fitted or convex mesh link: the mesh as read (scaled) and its frame in the link, which the
  // viewer draws, whatever stands for it in the checks.
  std::shared_ptr<const TriangleMesh> source_mesh;
  Pose source_in_link;
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

struct RobotModel {
  std::string name;
  std::string config_path;
  std::string urdf_path;
  std::vector<std::string> resource_files;  // files the URDF names (meshes): part of its identity
  std::vector<std::string> package_path;    // config "package_path", resolved: package:// folders
  int dof = 0;
  Eigen::Vector3d gravity{0, 0, -9.81};
  double control_rate = 1000;  // Hz

  std::vector<Joint> joints;               // chain order; joint i moves body i
  std::vector<BodyInertia> bodies;         // size dof
  std::vector<Link> links;                 // every link of the chain, base first
  std::vector<std::string> ignored_links;  // side branches behind moving joints
  std::vector<CollisionBody> collision_bodies;
  double collision_margin = 0;
  std::vector<std::pair<int, int>> allowed_pairs;  // link indices, first < second, sorted

  ControllerGains controller;

  // Default box of start states for the edge bundle (config "sampling_region"; the joint
  // limits when the config has none).
  JointVector region_lower, region_upper;

  // Limits gathered as vectors for the validity checks.
  JointVector q_min, q_max, dq_max, ddq_max, dddq_max, tau_max, dtau_max;

  int link_index(const std::string& link_name) const;  // -1 when unknown
  // "unknown link 'x'" with the closest name ("did you mean") or else the links there are.
  std::string unknown_link(const std::string& link_name) const;
  int tip_link() const { return static_cast<int>(links.size()) - 1; }
  bool is_allowed_pair(int link_a, int link_b) const;
};

}  // namespace lazyboe
