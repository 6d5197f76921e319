// The FCL side of CollisionModel and CollisionData, kept out of the installed headers so that
// <fcl/fcl.h> does not reach everything that includes the simulator. Only the library's
// collision code includes this header.
#pragma once

#include <fcl/fcl.h>

#include <memory>
#include <vector>

#include "lazyboe/collision/collision_model.h"

namespace lazyboe {

// Built once with the model, then read-only. What the pair tests read is packed here, apart
// from the names and poses they do not read: first the bounds that cull most pairs, then what
// the narrow phase needs. The robot record is 24 bytes, the stride of the per-thread sphere
// centres, so one index computation serves both.
struct CollisionShapes {
  struct Robot {                                        // as CollisionModel::robot
    double sphere_radius = 0;                           // CollisionModel::RobotShape::sphere_radius
    const fcl::CollisionGeometryd* inflated = nullptr;  // grown by the margin; none for a mesh
    const fcl::CollisionGeometryd* exact = nullptr;
  };
  struct alignas(64) Obstacle {  // as CollisionModel::obstacles
    Eigen::Vector3d box_min;     // CollisionModel::ObstacleShape's bounding box
    const fcl::CollisionGeometryd* geometry = nullptr;
    Eigen::Vector3d box_max;
    bool primitive = true;       // a convex primitive (GJK), not a mesh or an octree
    fcl::Transform3d transform;  // in the base frame
  };
  static_assert(sizeof(Obstacle) == 192, "an obstacle's record stays three cache lines");
  double margin = 0;  // CollisionModel::margin
  std::vector<Robot> robot;
  std::vector<double> env_radius;             // sphere_radius + margin, per robot shape
  std::vector<const fcl::Capsuled*> capsule;  // the exact shape, when it is a capsule
  std::vector<Obstacle> obstacles;
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> owned;  // keeps the geometry alive
};

// A mesh as FCL's bounding volume hierarchy (oriented boxes with swept spheres, for collision
// and distance alike): obstacles, exact robot links, and the fitted shapes' gap measure.
std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> mesh_geometry(const TriangleMesh& mesh);

// Per-thread FCL state of the exact-distance queries, and of the collision queries against
// meshes and octrees (fcl::collide: their result's contact list keeps its capacity).
struct CollisionScratch {
  fcl::DistanceRequestd distance_request;
  fcl::DistanceResultd distance_result;
  fcl::CollisionRequestd collision_request;
  fcl::CollisionResultd collision_result;
};

}  // namespace lazyboe
