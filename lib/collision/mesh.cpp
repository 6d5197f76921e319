#include "lazyboe/collision/mesh.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <octomap/OcTree.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"

namespace lazyboe {
namespace {

// Assimp's scene of a file, or Error naming it with Assimp's reason.
const aiScene* read_scene(Assimp::Importer& importer, const std::string& path, unsigned flags) {
  require_input_file(path);
  const aiScene* scene = importer.ReadFile(path, flags);
  if (!scene || !scene->mRootNode) {
    const std::string why = importer.GetErrorString();
    fail(path, "cannot read it as a mesh or point cloud" + (why.empty() ? "" : " (" + why + ")"));
  }
  return scene;
}

void add_node(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
              const Eigen::Vector3d& scale, TriangleMesh& out) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    const int first = static_cast<int>(out.vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      out.vertices.emplace_back(p.x * scale.x(), p.y * scale.y(), p.z * scale.z());
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines have no area
      out.triangles.emplace_back(first + static_cast<int>(face.mIndices[0]),
                                 first + static_cast<int>(face.mIndices[1]),
                                 first + static_cast<int>(face.mIndices[2]));
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    add_node(scene, *node.mChildren[c], transform, scale, out);
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, const Eigen::Vector3d& scale) {
  Assimp::Importer importer;
  // A COLLADA file's vertices as written (z up, as ROS, RViz and MoveIt read them): Assimp
  // would otherwise turn a Z_UP file to y up. Its <unit> still scales.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene =
      read_scene(importer, path,
                 aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  TriangleMesh mesh;
  add_node(*scene, *scene->mRootNode, aiMatrix4x4(), scale, mesh);
  if (mesh.triangles.empty()) fail(path, "has no triangle (not a mesh)");
  for (const Eigen::Vector3d& v : mesh.vertices)
    if (!v.allFinite()) fail(path, "has a vertex that is not a finite number");
  return mesh;
}

void mesh_bounds(const TriangleMesh& mesh, Eigen::Vector3d& lower, Eigen::Vector3d& upper) {
  lower = upper = mesh.vertices.front();
  for (const Eigen::Vector3d& v : mesh.vertices) {
    lower = lower.cwiseMin(v);
    upper = upper.cwiseMax(v);
  }
}

double farthest_vertex(const TriangleMesh& mesh) {
  double r = 0;
  for (const Eigen::Vector3d& v : mesh.vertices) r = std::max(r, v.norm());
  return r;
}

std::vector<Eigen::Vector3d> load_point_cloud(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = read_scene(importer, path, 0);
  std::vector<Eigen::Vector3d> points;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      points.emplace_back(p.x, p.y, p.z);
      if (!points.back().allFinite())
        fail(path, "point " + std::to_string(points.size() - 1) + " is not a finite number");
    }
  }
  if (points.empty()) fail(path, "has no point");
  return points;
}

std::shared_ptr<const octomap::OcTree> voxelise(const std::vector<Eigen::Vector3d>& points,
                                                double resolution, const std::string& where) {
  if (!(resolution > 0) || !std::isfinite(resolution)) fail(where, "resolution must be > 0");
  if (points.empty()) fail(where, "no point");
  auto tree = std::make_shared<octomap::OcTree>(resolution);
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& p = points[k];
    if (!p.allFinite()) fail(where, "point " + std::to_string(k) + " is not a finite number");
    octomap::OcTreeKey key;
    if (!tree->coordToKeyChecked(p.x(), p.y(), p.z(), key))
      fail(where, "point " + std::to_string(k) + " is outside the octree's range");
    tree->updateNode(key, true, true);  // lazy: inner nodes once, below
  }
  tree->updateInnerOccupancy();
  return tree;
}

std::shared_ptr<const octomap::OcTree> load_octree(const std::string& path) {
  require_input_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file");
  const bool binary = path.size() >= 3 && path.compare(path.size() - 3, 3, ".bt") == 0;
  std::shared_ptr<octomap::OcTree> tree;
  if (binary) {
    tree = std::make_shared<octomap::OcTree>(0.1);
    // OctoMap prints its reasons to stderr: keep the tool's one line.
    std::stringstream quiet;
    std::streambuf* old = std::cerr.rdbuf(quiet.rdbuf());
    const bool ok = tree->readBinary(in);
    std::cerr.rdbuf(old);
    if (!ok) fail(path, "not an OctoMap binary file (.bt)");
  } else {
    std::stringstream quiet;
    std::streambuf* old = std::cerr.rdbuf(quiet.rdbuf());
    octomap::AbstractOcTree* read = octomap::AbstractOcTree::read(in);
    std::cerr.rdbuf(old);
    tree.reset(dynamic_cast<octomap::OcTree*>(read));
    if (!tree) {
      delete read;
      fail(path, "not an OctoMap occupancy octree (.ot of an OcTree, or .bt)");
    }
  }
  if (tree->size() == 0 || occupied_cells(*tree) == 0) fail(path, "has no occupied cell");
  return tree;
}

bool occupied_bounds(const octomap::OcTree& tree, Eigen::Vector3d& lower, Eigen::Vector3d& upper) {
  lower = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  upper = -lower;
  bool any = false;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const double half = it.getSize() / 2;
    const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
    lower = lower.cwiseMin(c - Eigen::Vector3d::Constant(half));
    upper = upper.cwiseMax(c + Eigen::Vector3d::Constant(half));
    any = true;
  }
  return any;
}

size_t occupied_cells(const octomap::OcTree& tree) {
  size_t n = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) n += tree.isNodeOccupied(*it);
  return n;
}

}  // namespace lazyboe
