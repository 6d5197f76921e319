// Marking a scene's edges with the workspace index (workspace_index.h): the grid cells each
// obstacle occupies, then the edges listed for them.
#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "lazyboe/collision/fcl_shapes.h"
#include "lazyboe/collision/mesh.h"
#include "lazyboe/planning/workspace_index.h"

namespace lazyboe {
namespace {

// A cell counts as occupied when it may hold a point of the obstacle; boxes grown by this much
// so that a surface on a cell boundary occupies the cells on both sides.
constexpr double kTouch = 1e-9;

// Every cell the box [lower, upper] overlaps.
template <typename F>
void for_cells_in_box(const WorkspaceGrid& grid, const Eigen::Vector3d& lower,
                      const Eigen::Vector3d& upper, F&& f) {
  std::array<int, 3> first, last;
  const Eigen::Vector3d touch = Eigen::Vector3d::Constant(kTouch);
  if (!grid.cell_range(lower - touch, upper + touch, first, last)) return;
  for (int z = first[2]; z <= last[2]; ++z)
    for (int y = first[1]; y <= last[1]; ++y)
      for (int x = first[0]; x <= last[0]; ++x) f(x, y, z);
}

// A primitive: the cells of its bounding box that FCL finds touching it.
template <typename F>
void primitive_cells(const WorkspaceGrid& grid, const CollisionShapes::Obstacle& o, F&& f) {
  const double side = grid.cell + 2 * kTouch;
  const fcl::Boxd box(side, side, side);
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  for_cells_in_box(grid, o.box_min, o.box_max, [&](int x, int y, int z) {
    fcl::Transform3d at = fcl::Transform3d::Identity();
    at.translation() = grid.centre(x, y, z);
    result.clear();
    if (fcl::collide(&box, at, o.geometry, o.transform, request, result) > 0) f(grid.id(x, y, z));
  });
}

// A mesh (FCL tests its surface): the cells of each triangle's bounding box whose centre lies
// within half a diagonal of the triangle's plane.
template <typename F>
void mesh_cells(const WorkspaceGrid& grid, const Obstacle& o, F&& f) {
  const double half_diagonal = grid.cell * std::sqrt(3.0) / 2;
  for (const Eigen::Vector3i& t : o.mesh->triangles) {
    Eigen::Vector3d v[3];
    for (int k = 0; k < 3; ++k) v[k] = o.pose.R * o.mesh->vertices[t[k]] + o.pose.p;
    Eigen::Vector3d normal = (v[1] - v[0]).cross(v[2] - v[0]);
    const double area2 = normal.norm();
    if (area2 > 0) normal /= area2;
    const Eigen::Vector3d lower = v[0].cwiseMin(v[1]).cwiseMin(v[2]);
    const Eigen::Vector3d upper = v[0].cwiseMax(v[1]).cwiseMax(v[2]);
    for_cells_in_box(grid, lower, upper, [&](int x, int y, int z) {
      if (area2 == 0 || std::abs((grid.centre(x, y, z) - v[0]).dot(normal)) <= half_diagonal)
        f(grid.id(x, y, z));
    });
  }
}

// An octree: the cells overlapping each occupied leaf's box.
template <typename F>
void octree_cells(const WorkspaceGrid& grid, const Obstacle& o, F&& f) {
  const octomap::OcTree& tree = *o.cells;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const octomap::point3d c = it.getCoordinate();
    const Eigen::Vector3d centre = o.pose.R * Eigen::Vector3d(c.x(), c.y(), c.z()) + o.pose.p;
    const Eigen::Vector3d half = o.pose.R.cwiseAbs() * Eigen::Vector3d::Constant(it.getSize() / 2);
    for_cells_in_box(grid, centre - half, centre + half,
                     [&](int x, int y, int z) { f(grid.id(x, y, z)); });
  }
}

// The indexed links the obstacle does not allow, one bit each.
uint32_t links_blocked_by(const WorkspaceIndex& index, const RobotModel& robot, const Obstacle& o) {
  const std::vector<int> allowed = allowed_links_of(robot, o, "scene");
  uint32_t mask = 0;
  for (size_t l = 0; l < index.links().size(); ++l) {
    if (std::find(allowed.begin(), allowed.end(), index.links()[l]) == allowed.end())
      mask |= uint32_t{1} << l;
  }
  return mask;
}

// The links an obstacle lets touch it, sorted (named or through "@base": the same set).
std::vector<int> allowed_set(const RobotModel& robot, const Obstacle& o) {
  std::vector<int> links = allowed_links_of(robot, o, "scene");
  std::sort(links.begin(), links.end());
  links.erase(std::unique(links.begin(), links.end()), links.end());
  return links;
}

// The same primitive at the same pose, touchable by the same links (meshes and octrees are
// never taken for known: their content is in files).
bool same_primitive(const RobotModel& robot, const Obstacle& a, const Obstacle& b) {
  const Shape &s = a.shape, &t = b.shape;
  return a.type == ObstacleType::Primitive && b.type == ObstacleType::Primitive &&
         s.type == t.type && s.radius == t.radius && s.length == t.length && s.size == t.size &&
         a.pose.R == b.pose.R && a.pose.p == b.pose.p &&
         allowed_set(robot, a) == allowed_set(robot, b);
}

bool is_known(const RobotModel& robot, const Obstacle& o, const Environment* known) {
  if (!known) return false;
  for (const Obstacle& k : known->obstacles)
    if (same_primitive(robot, o, k)) return true;
  return false;
}

}  // namespace

EdgeMarks mark_edges(const WorkspaceIndex& index, const RobotModel& robot, const Environment& env,
                     const CollisionModel& collision, const Environment* known) {
  const auto started = std::chrono::steady_clock::now();
  const WorkspaceGrid& grid = index.grid();
  EdgeMarks m;
  m.bits.assign((index.edges() + 63) / 64, 0);
  std::vector<uint32_t> done(grid.cells(), 0);  // links already marked per cell
  for (size_t i = 0; i < env.obstacles.size(); ++i) {
    const Obstacle& o = env.obstacles[i];
    const uint32_t want = is_known(robot, o, known) ? 0 : links_blocked_by(index, robot, o);
    const auto visit = [&](size_t cell) {
      ++m.occupied_cells;
      uint32_t todo = want & ~done[cell];
      done[cell] |= todo;
      for (int l = 0; todo != 0; ++l, todo >>= 1)
        if (todo & 1u) index.mark(cell, l, m.bits.data());
    };
    if (want == 0) continue;
    if (o.type == ObstacleType::Mesh) {
      mesh_cells(grid, o, visit);
    } else if (o.type == ObstacleType::Octree) {
      octree_cells(grid, o, visit);
    } else {
      primitive_cells(grid, collision.shapes->obstacles[i], visit);
    }
  }
  for (const uint64_t word : m.bits) m.marked += static_cast<size_t>(__builtin_popcountll(word));
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return m;
}

}  // namespace lazyboe
