// Self- and environment collision of the robot with FCL. The FCL shapes and the list of pairs
// to test are built once (CollisionModel, read-only, shared by threads); a query only moves
// transforms in a per-thread CollisionData. Bounding spheres (robot) and boxes (obstacles)
// cull most pairs, and for a robot capsule or sphere against an obstacle box or cylinder a
// separating axis (a face normal of the obstacle's own box, or the capsule's direction crossed
// with one) most of the rest, before FCL's narrow phase.
//
// Margin: a configuration is in collision when any tested pair is closer than the robot's
// collision margin. One side of each pair is inflated by the margin, which is exact for
// spheres and capsules and conservative for boxes and cylinders; a pair with a robot mesh in it
// (a link kept exact) compares FCL's distance with the margin instead.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/kinematics.h"

namespace lazyboe {

// The FCL shapes and query state, defined in the library's private fcl_shapes.h.
struct CollisionShapes;
struct CollisionScratch;

// Transforms are Eigen::Isometry3d, which is fcl::Transform3d: FCL takes them as they are.
struct CollisionModel {
  struct RobotShape {
    std::string name;
    int link = 0;
    int body = -1;  // -1: fixed to the base
    Pose in_body;
    double sphere_radius = 0;  // bounding sphere about the shape's origin (exact shape)
  };
  struct ObstacleShape {
    std::string name;
    Eigen::Isometry3d transform;
    Pose pose;
    Eigen::Vector3d box_min, box_max;  // axis-aligned bounding box in the base frame
  };

  double margin = 0;
  std::vector<RobotShape> robot;
  std::vector<ObstacleShape> obstacles;
  std::vector<std::pair<int, int>> self_pairs;    // robot shape indices
  std::vector<std::pair<int, int>> env_pairs;     // (robot shape, obstacle)
  std::shared_ptr<const CollisionShapes> shapes;  // FCL geometry of robot and obstacles
};

struct CollisionOptions {
  bool ignore_allowed_pairs = false;  // test every pair of links on different bodies
};

// The name that stands for the robot's base in an obstacle's allowed_links: every link fixed to
// the base (the chain's root body) and every link of the first moving body, which stands on the
// base (the Panda's link1 capsule reaches down to it), whatever the robot calls them, so that
// one environment serves any robot (a floor the base stands on).
inline const char* const kBaseLinks = "@base";

// The links an obstacle lets touch it: each link it names, and for "@base" the links of the
// base and of the first moving body. Throws Error("<where>: object '<name>': allowed link 'x' is
// not a link of robot 'r'") for a name the robot lacks.
std::vector<int> allowed_links_of(const RobotModel& robot, const Obstacle& obstacle,
                                  const std::string& where);

// Throws Error when the environment names a link the robot does not have.
CollisionModel build_collision_model(const RobotModel& robot, const Environment& env,
                                     const CollisionOptions& options = {});

// Per-thread scratch.
struct CollisionData {
  explicit CollisionData(const CollisionModel& model);
  ~CollisionData();
  CollisionData(const CollisionData& other);
  CollisionData& operator=(const CollisionData& other);
  CollisionData(CollisionData&&) noexcept;
  CollisionData& operator=(CollisionData&&) noexcept;

  std::vector<Eigen::Isometry3d> transform;    // robot shapes in the base frame
  std::vector<Eigen::Vector3d> sphere_centre;  // bounding-sphere centres in the base frame
  std::unique_ptr<CollisionScratch> scratch;   // FCL state of min_distance
};

struct CollisionReport {
  bool self_collision = false;
  bool env_collision = false;
  int first_a = -1, first_b = -1;  // first colliding pair found (robot shape, shape/obstacle)
  bool any() const { return self_collision || env_collision; }
};

struct DistanceReport {
  double self_distance = std::numeric_limits<double>::infinity();
  double env_distance = std::numeric_limits<double>::infinity();
  double min() const { return std::min(self_distance, env_distance); }
};

// Places the robot shapes from the body poses of the last forward_kinematics(robot_data).
void update_collision_transforms(const CollisionModel& model, CollisionData& data,
                                 const RobotData& robot_data);

// True when any tested pair is closer than the margin. Stops at the first one found.
bool in_collision(const CollisionModel& model, CollisionData& data);

// Both flags (self and environment), each search stopping at its first hit.
CollisionReport check_collision(const CollisionModel& model, CollisionData& data);

// Exact distances (no margin) over the tested pairs; 0 for touching or overlapping shapes.
DistanceReport min_distance(const CollisionModel& model, CollisionData& data);

// Collision of one specific pair (used by the allowed-pair derivation).
bool self_pair_collides(const CollisionModel& model, CollisionData& data, int shape_a, int shape_b);

// The obstacle whose solid holds `point` (base frame), or -1: for goals inside an obstacle.
// Meshes are surfaces, so only their surface counts for them.
int obstacle_at(const CollisionModel& model, CollisionData& data, const Eigen::Vector3d& point);

}  // namespace lazyboe
