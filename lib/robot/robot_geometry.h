// The robot's collision geometry, apart from its kinematic and dynamic model (Pinocchio keeps
// a GeometryModel beside its Model the same way): per link the bodies the collision checks use
// (primitives, meshes or their fitted or convex stand-ins), the margin every check keeps, and
// the link pairs never checked. Read with the model from the robot config's "collision" section
// and the URDF's collision elements (robot_config.h); the collision layer builds its checks
// from it (collision_model.h).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lazyboe/robot/types.h"

namespace lazyboe {

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

struct RobotGeometry {
  std::vector<CollisionBody> bodies;
  double margin = 0;                               // m, kept by every check
  std::vector<std::pair<int, int>> allowed_pairs;  // link indices, first < second, sorted

  bool is_allowed_pair(int link_a, int link_b) const;
};

}  // namespace lazyboe
