// Geometry read from files for collision: triangle meshes (STL, OBJ, COLLADA, PLY, through
// Assimp) and point clouds (PLY, through Assimp; or given inline) voxelised into an OctoMap
// octree, and OctoMap's own .bt / .ot files. Shared by environments (obstacles given as meshes,
// point clouds, octrees) and, later, robot links with mesh geometry. Errors name the file.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace octomap {
class OcTree;
}

namespace lazyboe {

// Triangles in the frame of the object they belong to, scaled.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;  // vertex indices
};

// Every triangle of every mesh of the file, with its node transforms applied, each vertex
// scaled by `scale` (per axis). Throws Error naming the file when it is missing, unreadable,
// not a format Assimp reads, or has no triangle.
TriangleMesh load_mesh(const std::string& path, const Eigen::Vector3d& scale);

// Axis-aligned bounds of the vertices, in the mesh's frame (the mesh has at least one vertex).
void mesh_bounds(const TriangleMesh& mesh, Eigen::Vector3d& lower, Eigen::Vector3d& upper);
// The largest distance of a vertex from the mesh frame's origin: a bounding sphere's radius.
double farthest_vertex(const TriangleMesh& mesh);

// The vertices of a point cloud file (PLY, ASCII or binary; any file Assimp reads: its
// vertices). Throws Error naming the file when it cannot be read or has no point; a point
// that is not finite is an error (`where` names it).
std::vector<Eigen::Vector3d> load_point_cloud(const std::string& path);

// The occupied cells of `points`, an octree of cells `resolution` m wide (OctoMap's OcTree, the
// map of ROS's octomap_server). Throws Error(`where`: ...) for a resolution that is not
// positive and finite, no point, or a point that is not finite.
std::shared_ptr<const octomap::OcTree> voxelise(const std::vector<Eigen::Vector3d>& points,
                                                double resolution, const std::string& where);

// An OctoMap file: .bt (binary, occupied or free) or .ot (full). Throws Error naming the file
// when it is missing or not an octree of occupancy.
std::shared_ptr<const octomap::OcTree> load_octree(const std::string& path);

// Axis-aligned bounds of an octree's occupied cells, in its frame; false when none is occupied.
bool occupied_bounds(const octomap::OcTree& tree, Eigen::Vector3d& lower, Eigen::Vector3d& upper);
size_t occupied_cells(const octomap::OcTree& tree);

}  // namespace lazyboe
