// One box as every kind of obstacle file (issue 26): a triangle mesh (OBJ, binary STL, COLLADA), a
// point cloud filling its volume (PLY, ASCII or binary; the points themselves) and an OctoMap .bt
// of those points; for the tests that check they all block alike.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "lazyboe/collision/mesh.h"

namespace lazyboe::test {

struct BoxFiles {
  Eigen::Vector3d centre, size;  // m, base frame
  double resolution = 0.01;      // of the voxelised points, m
  std::string name;              // file names start with it, under temp_dir()

  TriangleMesh mesh() const;                    // centred on the box's frame
  std::vector<Eigen::Vector3d> points() const;  // base frame, every half resolution
  std::string obj() const;
  std::string binary_stl() const;
  std::string collada() const;  // Z_UP, in metres
  std::string ply(bool binary) const;
  std::string bt() const;
};

}  // namespace lazyboe::test
