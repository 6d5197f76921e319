#include "lazyboe/planning/workspace_sweep.h"

#include <algorithm>
#include <cmath>

#include "lazyboe/collision/mesh.h"
#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

// A chord between two samples is shorter than the arc the shape's points travel along it; over
// one sample interval the two differ by far less than this factor.
constexpr double kArcOverChord = 1.1;

double squared_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

SweptShape swept_shape(const RobotModel& robot, const CollisionBody& cb) {
  SweptShape s;
  s.body = robot.links[cb.link].body;
  s.in_body = robot.links[cb.link].in_body * cb.in_link;
  switch (cb.shape.type) {
    case ShapeType::Capsule:
    case ShapeType::Cylinder:  // inside the capsule of its radius and length
      s.half_length = cb.shape.length / 2;
      s.radius = cb.shape.radius;
      break;
    case ShapeType::Sphere:
      s.radius = cb.shape.radius;
      break;
    case ShapeType::Box:
      s.radius = cb.shape.size.norm() / 2;
      break;
    case ShapeType::Mesh:  // about its bounding box's centre, the shape's frame
      s.radius = farthest_vertex(*cb.shape.mesh);
      break;
  }
  s.radius += robot.geometry.margin;
  return s;
}

}  // namespace

std::vector<SweptShape> swept_shapes(const RobotModel& robot, std::vector<int>& links) {
  std::vector<SweptShape> shapes;
  links.clear();
  for (const CollisionBody& cb : robot.geometry.bodies) {
    if (robot.links[cb.link].body < 0) continue;  // fixed to the base
    SweptShape s = swept_shape(robot, cb);
    const auto at = std::find(links.begin(), links.end(), cb.link);
    s.link = static_cast<int>(at - links.begin());
    if (at == links.end()) links.push_back(cb.link);
    shapes.push_back(s);
  }
  if (links.size() > kMaxLinks)
    fail(robot.name, "the workspace index takes at most " + std::to_string(kMaxLinks) +
                         " moving links with collision shapes");
  return shapes;
}

void sweep_segments(const BundleView& bundle, const RobotModel& robot,
                    const std::vector<SweptShape>& shapes, size_t edge, RobotData& data,
                    std::vector<Segment>& segments) {
  const size_t samples = bundle.sample_count(edge), m = shapes.size();
  const int n = bundle.dof();
  segments.resize(samples * m);
  JointVector q(n);
  for (size_t i = 0; i < samples; ++i) {
    const float* row = bundle.samples(edge) + i * static_cast<size_t>(n);
    for (int j = 0; j < n; ++j) q[j] = row[j];
    forward_kinematics(robot, data, q);
    for (size_t s = 0; s < m; ++s) {
      const Pose world = data.body_pose[shapes[s].body] * shapes[s].in_body;
      const Eigen::Vector3d axis = world.R.col(2) * shapes[s].half_length;
      segments[i * m + s] = {world.p - axis, world.p + axis, shapes[s].radius};
    }
  }
  // Every point of the motion between two samples lies within half the arc of one of them.
  for (size_t i = 0; i < samples; ++i) {
    for (size_t s = 0; s < m; ++s) {
      double step = 0;
      for (const size_t j : {i - 1, i + 1}) {
        if (j >= samples) continue;  // i - 1 wraps around for i = 0
        const Segment& o = segments[j * m + s];
        const Segment& x = segments[i * m + s];
        step = std::max({step, (o.a - x.a).norm(), (o.b - x.b).norm()});
      }
      segments[i * m + s].radius += kArcOverChord * step / 2;
    }
  }
}

void swept_keys(const WorkspaceGrid& grid, const std::vector<SweptShape>& shapes,
                const std::vector<Segment>& segments, size_t links, uint32_t stamp_value,
                std::vector<uint32_t>& stamp, std::vector<uint32_t>& keys) {
  keys.clear();
  const double half_diagonal = grid.cell * std::sqrt(3.0) / 2;
  std::array<int, 3> first, last;
  for (size_t i = 0; i < segments.size(); ++i) {
    const Segment& g = segments[i];
    const size_t link = static_cast<size_t>(shapes[i % shapes.size()].link);
    const double reach = g.radius + half_diagonal;
    const Eigen::Vector3d r = Eigen::Vector3d::Constant(reach);
    if (!grid.cell_range(g.a.cwiseMin(g.b) - r, g.a.cwiseMax(g.b) + r, first, last)) continue;
    for (int z = first[2]; z <= last[2]; ++z) {
      for (int y = first[1]; y <= last[1]; ++y) {
        for (int x = first[0]; x <= last[0]; ++x) {
          if (squared_distance(grid.centre(x, y, z), g.a, g.b) > reach * reach) continue;
          const size_t key = grid.id(x, y, z) * links + link;
          if (stamp[key] == stamp_value) continue;
          stamp[key] = stamp_value;
          keys.push_back(static_cast<uint32_t>(key));
        }
      }
    }
  }
}

}  // namespace lazyboe
