// How the workspace index sweeps an edge (workspace_index.h): the robot's moving collision
// shapes as segments with a radius (a capsule's axis; a sphere's or box's centre), placed at
// every stored sample of the edge, and the grid cells within reach of them. Internal to the
// library (the index, its tests and its benchmark).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/workspace_index.h"
#include "lazyboe/robot/kinematics.h"

namespace lazyboe {

constexpr uint32_t kMaxLinks = 32;  // indexed links: one bit each in the marking's masks

// A collision shape on a moving body, as the points within `radius` of its segment
// [-half_length, half_length] along its local z (capsules exactly; cylinders by their capsule,
// spheres and boxes by their bounding sphere), the radius grown by the collision margin.
struct SweptShape {
  int link = 0;  // index into the indexed links
  int body = 0;
  Pose in_body;
  double half_length = 0, radius = 0;
};

struct Segment {
  Eigen::Vector3d a, b;
  double radius = 0;  // the shape's, plus half its motion to the neighbouring samples
};

// The moving shapes of `robot`; `links` receives the indexed links (RobotModel link indices, in
// the order of the robot's collision bodies). Throws Error for more than kMaxLinks links.
std::vector<SweptShape> swept_shapes(const RobotModel& robot, std::vector<int>& links);

// segments[i * shapes.size() + s]: shape s at stored sample i of `edge`.
void sweep_segments(const BundleView& bundle, const RobotModel& robot,
                    const std::vector<SweptShape>& shapes, size_t edge, RobotData& data,
                    std::vector<Segment>& segments);

// The (cell, link) keys (cell * links + link) within reach of `segments`: each cell whose centre
// lies within a segment's radius plus half the cell's diagonal. `stamp` (one per key, zero or
// an older stamp) remembers the keys already listed for `stamp_value`.
void swept_keys(const WorkspaceGrid& grid, const std::vector<SweptShape>& shapes,
                const std::vector<Segment>& segments, size_t links, uint32_t stamp_value,
                std::vector<uint32_t>& stamp, std::vector<uint32_t>& keys);

}  // namespace lazyboe
