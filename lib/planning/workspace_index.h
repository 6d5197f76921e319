// The edge-to-workspace index of a bundle, in the spirit of the Dynamic Roadmap (Leven and
// Hutchinson, IJRR 2002; Kallmann and Mataric, ICRA 2004): for every edge, the workspace cells
// each moving link of the robot sweeps along the edge's stored trajectory samples, inverted (per
// cell and link, the edges that sweep it) so that a new scene's occupied cells give, in
// milliseconds, the edges it may block. Stored beside the bundle in "<bundle>.ws-index"
// (schemas/bundle.md, "workspace index"), memory-mapped, and used only when it belongs to the
// bundle (its edge states' checksums) and to the robot (its moving links).
//
// Conservative for the stored motion: a link's cells are those within its shape's radius
// (capsules and spheres exactly, cylinders as their capsule, boxes as their bounding sphere)
// plus the collision margin, half a cell's diagonal and half its motion to the neighbouring
// samples. So an edge whose stored motion comes closer to an obstacle than the margin is marked
// (the test_workspace_index tests check it). Links fixed to the base are not indexed (an obstacle
// touching them blocks every configuration; validate_problem refuses the start), and a link an
// obstacle allows (`allowed_links`) is not marked by it. Edges applied shifted in joint space
// (lazysp, LazyBoE's transfer) move the links: then the marks only steer (docs/bundle.md).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

// A regular grid of cubic cells; cell (0, 0, 0) has its lower corner at `origin`.
struct WorkspaceGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double cell = 0;  // side, m
  std::array<int, 3> dims{{0, 0, 0}};

  size_t cells() const {
    return static_cast<size_t>(dims[0]) * static_cast<size_t>(dims[1]) *
           static_cast<size_t>(dims[2]);
  }
  size_t id(int x, int y, int z) const {
    return (static_cast<size_t>(z) * static_cast<size_t>(dims[1]) + static_cast<size_t>(y)) *
               static_cast<size_t>(dims[0]) +
           static_cast<size_t>(x);
  }
  Eigen::Vector3d centre(int x, int y, int z) const {
    return origin + cell * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
  }
  // The cells overlapping the box [lower, upper], clipped to the grid, as inclusive ranges;
  // false when the box is outside it.
  bool cell_range(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper,
                  std::array<int, 3>& first, std::array<int, 3>& last) const;
};

struct WorkspaceIndexOptions {
  double cell =
      0.07;         // m: measured against size, marking time and false positives (docs/bundle.md)
  int threads = 0;  // 0: all cores (the file does not depend on it)
  // Called from the calling thread with the edges done so far, at most every 256 edges.
  std::function<void(size_t done)> progress;
};

class WorkspaceIndex {
 public:
  // The index file beside `bundle` (memory-mapped, or read). Throws Error naming the file and
  // why it cannot be used: not an index, damaged, of other edge states, of another robot.
  static std::shared_ptr<const WorkspaceIndex> open(const BundleView& bundle,
                                                    const RobotModel& robot, bool memory_map);

  const std::string& path() const { return path_; }
  const WorkspaceGrid& grid() const { return grid_; }
  // The links indexed (the robot's moving links with collision shapes), as RobotModel links.
  const std::vector<int>& links() const { return links_; }
  size_t edges() const { return edges_; }
  size_t file_bytes() const { return file_bytes_; }

  // Sets, in `bits` (one per edge), the bit of every edge whose indexed link `link` sweeps
  // grid cell `cell`.
  void mark(size_t cell, int link, uint64_t* bits) const;

 private:
  WorkspaceIndex() = default;
  std::string path_;
  WorkspaceGrid grid_;
  std::vector<int> links_;
  size_t edges_ = 0, file_bytes_ = 0;
  std::shared_ptr<const void> storage_;
  const uint64_t* offsets_ = nullptr;  // cells x links + 1, into data_
  const uint8_t* data_ = nullptr;      // per list: the edge ids, delta-coded as LEB128 varints
};

std::string workspace_index_path(const std::string& bundle_path);

// The workspace index beside a bundle, when it belongs to it (as a session loads it).
struct WorkspaceIndexLoad {
  std::shared_ptr<const WorkspaceIndex> index;  // null: none, or not usable
  std::string source;  // "mapped from PATH", "read from PATH", or why there is none in use
};
WorkspaceIndexLoad load_workspace_index(const BundleView& bundle, const RobotModel& robot,
                                        bool memory_map);
// One line on the workspace index beside the bundle (--inspect): its path, size and grid and
// whether planning uses it, or why not.
std::string workspace_index_status(const BundleView& bundle);

struct WorkspaceIndexSummary {
  WorkspaceGrid grid;
  size_t links = 0;
  uint64_t entries = 0;  // (cell, link, edge) triples
  uint64_t bytes = 0;    // of the file
};

// Sweeps every edge's stored samples and writes workspace_index_path(bundle.path()) atomically.
// Throws Error naming the bundle when it has no stored samples, or the index when it cannot be
// written.
WorkspaceIndexSummary write_workspace_index(const BundleView& bundle, const RobotModel& robot,
                                            const WorkspaceIndexOptions& options);

// The edges a scene may block: bit e set when edge e's stored motion may come closer to one of
// its obstacles than the collision margin.
struct EdgeMarks {
  std::vector<uint64_t> bits;
  size_t marked = 0;          // edges marked
  size_t occupied_cells = 0;  // (cell, obstacle) pairs found occupied
  double seconds = 0;         // to find the cells and mark the edges

  bool may_collide(size_t edge) const { return (bits[edge >> 6] >> (edge & 63)) & 1u; }
};

// Marks the edges of `index` that the obstacles of `env` (with `collision`, its collision model
// for the same robot) may block. Obstacle cells outside the index's grid are ones no edge reaches.
// Obstacles of `known` (the scene the bundle was built in, whose obstacles its edges avoid as
// stored: same primitive, pose and allowed links) do not mark; null: every obstacle marks.
EdgeMarks mark_edges(const WorkspaceIndex& index, const RobotModel& robot, const Environment& env,
                     const CollisionModel& collision, const Environment* known = nullptr);

}  // namespace lazyboe
