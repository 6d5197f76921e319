// A static environment: named obstacles with poses, read from a JSON file or given inline
// (schemas/environment.schema.json): primitives, triangle meshes, and occupancy octrees (from a
// point cloud voxelised at a resolution, or an OctoMap file).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lazyboe/collision/mesh.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

enum class ObstacleType { Primitive, Mesh, Octree };

struct Obstacle {
  std::string name;
  ObstacleType type = ObstacleType::Primitive;
  Shape shape;                                   // Primitive
  std::shared_ptr<const TriangleMesh> mesh;      // Mesh: in the obstacle's frame, scaled
  std::shared_ptr<const octomap::OcTree> cells;  // Octree: occupied cells, obstacle's frame
  Pose pose;                                     // in the robot's base frame
  std::vector<std::string> allowed_links;        // robot links allowed to touch this obstacle
};

struct Environment {
  std::string name;
  std::string path;    // the file it was read from; empty for a scene given inline
  std::string origin;  // the file, or where an inline scene stands ("line 3: scene"): for errors
  std::string description;
  std::vector<Obstacle> obstacles;
  std::vector<std::string> files;  // files the obstacles were read from (meshes, clouds, maps)
  // Content identity: a hash of the parsed description (whitespace, key order and number
  // spelling do not count) and of the files it names, so the same scene from a file or inline
  // is the same scene.
  std::string identity;
};

// `path` itself when it exists; else, for a bare name without folder or extension ("shelf"),
// the bundled scene of that name in data_dir()/environments. Throws Error naming `path` and
// listing the bundled scenes when neither exists; a path with a folder or an extension is
// returned as it is (a missing file is its own error, never silently another file).
std::string resolve_environment_path(const std::string& path);

// Throws Error naming the file and field for anything missing or malformed. `path` may be a
// bundled scene's name (resolve_environment_path).
Environment load_environment(const std::string& path);
// The same for an environment object held in memory (a query's inline scene); `path`: the file
// it came from, or empty. Files the objects name are relative to the file's folder (to the
// current directory for an inline scene).
Environment environment_from_json(const JsonField& root, const std::string& path);

std::string default_environment_path();  // the bundled table.json

}  // namespace lazyboe
