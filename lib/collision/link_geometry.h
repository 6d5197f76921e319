// The robot's collision geometry from its URDF <collision> elements: spheres, boxes, cylinders
// (a cylinder capped by two spheres of its radius, the usual URDF spelling of a capsule, becomes
// one capsule) and triangle meshes (STL, COLLADA, OBJ, PLY through Assimp), each mesh either
// fitted with a capsule or kept exact (MeshRepresentation).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "lazyboe/robot/robot_model.h"

namespace urdf {
class Link;
class Geometry;
}  // namespace urdf

namespace lazyboe {

// The robot config's collision.meshes: a representation for every mesh link, and exceptions.
struct MeshSettings {
  MeshRepresentation representation = MeshRepresentation::Fitted;
  std::vector<std::pair<std::string, MeshRepresentation>> per_link;  // link name -> its own
  MeshRepresentation of(const std::string& link) const;
};

// Appends the collision bodies of `link` (model link `link_index`) to model.geometry.bodies
// and the mesh files it read to model.files.resources; mesh URIs are resolved from
// model.files.urdf and model.files.package_path (resource_path.h). Throws Error("<urdf>: link 'l'
// collision k: ...") for a missing, unreadable, empty, flat or non-mesh file, a package that is
// not on the path, and a primitive without size.
void add_link_collision_bodies(RobotModel& model, const urdf::Link& link, int link_index,
                               const MeshSettings& meshes);

// The shape of a URDF sphere, box or cylinder element (also a <visual>'s); throws
// Error(`where`: ...) for a size that is not > 0 or another geometry type.
Shape urdf_primitive_shape(const urdf::Geometry& geometry, const std::string& where);

}  // namespace lazyboe
