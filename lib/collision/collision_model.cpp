#include "lazyboe/collision/collision_model.h"

#include <fcl/narrowphase/detail/convexity_based_algorithm/gjk.h>
#include <fcl/narrowphase/detail/convexity_based_algorithm/minkowski_diff.h>
#include <fcl/narrowphase/detail/primitive_shape_algorithm/capsule_capsule.h>

#include <algorithm>
#include <cmath>

#include "lazyboe/collision/fcl_shapes.h"
#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

static_assert(sizeof(CollisionShapes::Robot) == sizeof(Eigen::Vector3d),
              "a robot shape's record has the stride of its sphere centre");

}  // namespace

std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> mesh_geometry(const TriangleMesh& mesh) {
  auto bvh = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(mesh.vertices.size()));
  bvh->addSubModel(mesh.vertices, triangles);
  bvh->endModel();
  bvh->computeLocalAABB();
  return bvh;
}

namespace {

// A convex hull (convex_hull.h: a closed surface of outward triangles) as FCL's Convex, whose
// support function GJK uses directly; the triangles give it its vertex neighbours.
std::shared_ptr<fcl::Convexd> convex_geometry(const TriangleMesh& hull) {
  auto vertices = std::make_shared<std::vector<Eigen::Vector3d>>(hull.vertices);
  auto faces = std::make_shared<std::vector<int>>();
  faces->reserve(4 * hull.triangles.size());
  for (const Eigen::Vector3i& t : hull.triangles)
    faces->insert(faces->end(), {3, t[0], t[1], t[2]});
  return std::make_shared<fcl::Convexd>(vertices, static_cast<int>(hull.triangles.size()), faces);
}

// `inflate` grows a primitive by the margin; a mesh is not grown (its pairs compare distances).
std::shared_ptr<fcl::CollisionGeometryd> make_geometry(const Shape& s, double inflate) {
  switch (s.type) {
    case ShapeType::Sphere:
      return std::make_shared<fcl::Sphered>(s.radius + inflate);
    case ShapeType::Capsule:
      return std::make_shared<fcl::Capsuled>(s.radius + inflate, s.length);
    case ShapeType::Cylinder:
      return std::make_shared<fcl::Cylinderd>(s.radius + inflate, s.length + 2 * inflate);
    case ShapeType::Box:
      return std::make_shared<fcl::Boxd>(s.size + Eigen::Vector3d::Constant(2 * inflate));
    case ShapeType::Mesh:
      if (s.convex) return convex_geometry(*s.mesh);
      return mesh_geometry(*s.mesh);
  }
  return nullptr;
}

double bounding_radius(const Shape& s) {
  switch (s.type) {
    case ShapeType::Sphere:
      return s.radius;
    case ShapeType::Capsule:
      return s.radius + s.length / 2;
    case ShapeType::Cylinder:
      return std::hypot(s.radius, s.length / 2);
    case ShapeType::Box:
      return s.size.norm() / 2;
    case ShapeType::Mesh:
      return farthest_vertex(*s.mesh);
  }
  return 0;
}

Eigen::Vector3d bounding_half_extents(const Shape& s) {
  switch (s.type) {
    case ShapeType::Sphere:
      return Eigen::Vector3d::Constant(s.radius);
    case ShapeType::Capsule:
      return Eigen::Vector3d(s.radius, s.radius, s.radius + s.length / 2);
    case ShapeType::Cylinder:
      return Eigen::Vector3d(s.radius, s.radius, s.length / 2);
    case ShapeType::Box:
      return s.size / 2;
    case ShapeType::Mesh: {
      Eigen::Vector3d lower, upper;
      mesh_bounds(*s.mesh, lower, upper);
      return lower.cwiseAbs().cwiseMax(upper.cwiseAbs());
    }
  }
  return Eigen::Vector3d::Zero();
}

std::shared_ptr<fcl::CollisionGeometryd> obstacle_geometry(const Obstacle& o) {
  switch (o.type) {
    case ObstacleType::Mesh:
      return mesh_geometry(*o.mesh);
    case ObstacleType::Octree:
      return std::make_shared<fcl::OcTreed>(o.cells);
    default:
      return make_geometry(o.shape, 0);
  }
}

// The obstacle's own bounding box, in its frame.
void local_bounds(const Obstacle& o, Eigen::Vector3d& lower, Eigen::Vector3d& upper) {
  if (o.type == ObstacleType::Mesh) {
    mesh_bounds(*o.mesh, lower, upper);
  } else if (o.type == ObstacleType::Octree) {
    occupied_bounds(*o.cells, lower, upper);
  } else {
    upper = bounding_half_extents(o.shape);
    lower = -upper;
  }
}

const fcl::CollisionGeometryd* own(CollisionShapes& shapes,
                                   std::shared_ptr<fcl::CollisionGeometryd> geometry) {
  shapes.owned.push_back(std::move(geometry));
  return shapes.owned.back().get();
}

fcl::Transform3d to_fcl(const Pose& pose) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.linear() = pose.R;
  t.translation() = pose.p;
  return t;
}

// Can a robot shape's bounding sphere touch an obstacle's world bounding box?
inline bool sphere_may_touch_box(const Eigen::Vector3d& centre, double radius,
                                 const CollisionShapes::Obstacle& o) {
  const Eigen::Vector3d outside =
      (o.box_min - centre).cwiseMax(centre - o.box_max).cwiseMax(Eigen::Vector3d::Zero());
  return outside.squaredNorm() <= radius * radius;
}

inline bool spheres_may_touch(const CollisionData& data, const CollisionShapes& shapes, int a,
                              int b, double grow) {
  const double r = shapes.robot[a].sphere_radius + shapes.robot[b].sphere_radius + grow;
  return (data.sphere_centre[a] - data.sphere_centre[b]).squaredNorm() <= r * r;
}

// Intersection of two convex FCL shapes by FCL's own GJK (the boolean answer only: no EPA
// penetration pass and no heap allocation, unlike fcl::collide's libccd path).
bool narrow_collide(const fcl::CollisionGeometryd* g1, const fcl::Transform3d& t1,
                    const fcl::CollisionGeometryd* g2, const fcl::Transform3d& t2) {
  fcl::detail::MinkowskiDiff<double> diff;
  diff.shapes[0] = static_cast<const fcl::ShapeBased*>(g1);
  diff.shapes[1] = static_cast<const fcl::ShapeBased*>(g2);
  diff.toshape1.noalias() = t2.linear().transpose() * t1.linear();
  diff.toshape0 = t1.inverse(Eigen::Isometry) * t2;
  fcl::detail::GJK<double> gjk(128, 1e-8);
  return gjk.evaluate(diff, -Eigen::Vector3d::UnitX()) == fcl::detail::GJK<double>::Inside;
}

// A convex primitive (GJK applies), not a mesh or an octree.
inline bool is_primitive(const fcl::CollisionGeometryd* g) {
  return g->getObjectType() == fcl::OT_GEOM;
}

// A mesh or an octree against a robot shape, through fcl::collide (one contact is enough). Kept
// out of line: inlined, its setup would weigh on every culled pair of the primitives' path.
[[gnu::noinline]] bool collide_with_bvh(const CollisionData& data,
                                        const fcl::CollisionGeometryd* shape,
                                        const fcl::Transform3d& t1,
                                        const fcl::CollisionGeometryd* obstacle,
                                        const fcl::Transform3d& t2) {
  CollisionScratch& s = *data.scratch;
  s.collision_result.clear();
  return fcl::collide(shape, t1, obstacle, t2, s.collision_request, s.collision_result) > 0;
}

double narrow_distance(CollisionData& data, const fcl::CollisionGeometryd* g1,
                       const fcl::Transform3d& t1, const fcl::CollisionGeometryd* g2,
                       const fcl::Transform3d& t2) {
  if (is_primitive(g1) && is_primitive(g2) ? narrow_collide(g1, t1, g2, t2)
                                           : collide_with_bvh(data, g1, t1, g2, t2))
    return 0;
  data.scratch->distance_result.clear();
  const double d =
      fcl::distance(g1, t1, g2, t2, data.scratch->distance_request, data.scratch->distance_result);
  return std::max(0.0, d);
}

// A pair with a robot mesh (exact representation) in it: FCL's collision of the two, then, when
// they do not touch, their distance against the margin (a mesh cannot be grown as a primitive).
[[gnu::noinline]] bool mesh_pair_collides(const CollisionData& data, double margin,
                                          const fcl::CollisionGeometryd* g1,
                                          const fcl::Transform3d& t1,
                                          const fcl::CollisionGeometryd* g2,
                                          const fcl::Transform3d& t2) {
  if (collide_with_bvh(data, g1, t1, g2, t2)) return true;
  if (!(margin > 0)) return false;
  CollisionScratch& s = *data.scratch;
  s.distance_result.clear();
  return fcl::distance(g1, t1, g2, t2, s.distance_request, s.distance_result) < margin;
}

inline bool is_convex(const fcl::CollisionGeometryd* g) {
  return g->getNodeType() == fcl::GEOM_CONVEX;
}

// Two convex shapes, one of them a convex hull (no grown copy): their GJK distance against the
// margin (negative when they overlap), or with no margin their intersection.
[[gnu::noinline]] bool convex_pair_collides(const CollisionData& data, double margin,
                                            const fcl::CollisionGeometryd* g1,
                                            const fcl::Transform3d& t1,
                                            const fcl::CollisionGeometryd* g2,
                                            const fcl::Transform3d& t2) {
  if (!(margin > 0)) return narrow_collide(g1, t1, g2, t2);
  CollisionScratch& s = *data.scratch;
  s.distance_result.clear();
  return fcl::distance(g1, t1, g2, t2, s.distance_request, s.distance_result) < margin;
}

// Signed distance of two capsules by FCL's closed-form segment-segment routine: much cheaper
// than the generic GJK path, and most robot shapes are capsules.
double capsule_distance(const CollisionShapes& shapes, const CollisionData& data, int a, int b) {
  double dist = 0;
  Eigen::Vector3d pa, pb;
  fcl::detail::capsuleCapsuleDistance(*shapes.capsule[a], data.transform[a], *shapes.capsule[b],
                                      data.transform[b], &dist, &pa, &pb);
  return dist;
}

// The pair tests take the shapes from the caller, which loads model.shapes once per query.
bool self_collides(const CollisionShapes& shapes, const CollisionData& data, int a, int b) {
  const double margin = shapes.margin;
  if (!spheres_may_touch(data, shapes, a, b, margin)) return false;
  const CollisionShapes::Robot& sa = shapes.robot[a];
  const CollisionShapes::Robot& sb = shapes.robot[b];
  if (shapes.capsule[a] && shapes.capsule[b]) return capsule_distance(shapes, data, a, b) < margin;
  // Hulls (no grown copy) against each other by distance, against a grown primitive by GJK.
  const bool hull_a = !sa.inflated && is_convex(sa.exact);
  const bool hull_b = !sb.inflated && is_convex(sb.exact);
  if (hull_a && hull_b)
    return convex_pair_collides(data, margin, sa.exact, data.transform[a], sb.exact,
                                data.transform[b]);
  if (hull_a && sb.inflated)
    return narrow_collide(sb.inflated, data.transform[b], sa.exact, data.transform[a]);
  if (hull_b && sa.inflated)
    return narrow_collide(sa.inflated, data.transform[a], sb.exact, data.transform[b]);
  if (!sa.inflated || !sb.inflated)  // a mesh (or a hull against a mesh)
    return mesh_pair_collides(data, margin, sa.exact, data.transform[a], sb.exact,
                              data.transform[b]);
  return narrow_collide(sa.inflated, data.transform[a], sb.exact, data.transform[b]);
}

// Gaps below this are left to GJK (its own tolerance is 1e-8 m): the test below only spares it
// pairs that are clearly apart.
constexpr double kClearlyApart = 1e-6;

// A robot shape as a segment with a radius: a capsule's axis (FCL's z, lz long), or a sphere's
// centre; false for other shapes.
inline bool as_swept_sphere(const fcl::CollisionGeometryd* g, double& half_length, double& radius) {
  if (g->getNodeType() == fcl::GEOM_CAPSULE) {
    const auto& c = *static_cast<const fcl::Capsuled*>(g);
    half_length = 0.5 * c.lz;
    radius = c.radius;
    return true;
  }
  if (g->getNodeType() == fcl::GEOM_SPHERE) {
    half_length = 0;
    radius = static_cast<const fcl::Sphered*>(g)->radius;
    return true;
  }
  return false;
}

// An obstacle's box in its own frame, as half sides: a box's own, or the one about a cylinder
// (FCL's z its axis); false for other shapes.
inline bool own_box(const fcl::CollisionGeometryd* g, Eigen::Vector3d& half) {
  if (g->getNodeType() == fcl::GEOM_BOX) {
    half = 0.5 * static_cast<const fcl::Boxd*>(g)->side;
    return true;
  }
  if (g->getNodeType() == fcl::GEOM_CYLINDER) {
    const auto& c = *static_cast<const fcl::Cylinderd*>(g);
    half = Eigen::Vector3d(c.radius, c.radius, 0.5 * c.lz);
    return true;
  }
  return false;
}

// A robot capsule or sphere (grown) and an obstacle box or cylinder that a separating axis
// keeps apart by more than the shape's radius: a face normal of the obstacle's own box, or (for
// a capsule) its segment's direction crossed with one (the six axes of a segment against a box).
// Most pairs whose bounding sphere reaches an obstacle's bounding box are decided here, several
// times cheaper than GJK. False means only that GJK must decide (a capsule passing a corner of
// the box, whose separating direction is none of these).
bool clearly_apart(const fcl::CollisionGeometryd* shape, const fcl::Transform3d& ts,
                   const fcl::CollisionGeometryd* obstacle, const fcl::Transform3d& to) {
  double half_length = 0, radius = 0;
  Eigen::Vector3d half;
  if (!as_swept_sphere(shape, half_length, radius) || !own_box(obstacle, half)) return false;
  const Eigen::Matrix3d to_box = to.linear().transpose();
  const Eigen::Vector3d centre = to_box * (ts.translation() - to.translation());
  const Eigen::Vector3d axis = to_box * ts.linear().col(2);  // unit
  const double grown = radius + kClearlyApart;
  for (int i = 0; i < 3; ++i) {
    const double reach = half[i] + grown + std::abs(axis[i]) * half_length;
    if (std::abs(centre[i]) > reach) return true;
  }
  if (half_length == 0) return false;
  // The axes across the segment (its direction x each box axis): the segment projects onto
  // one to a point, the box to sum_j half_j |L_j|, the robot shape's radius to radius |L|.
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const double lj = axis[k], lk = -axis[j];  // L = axis x e_i, whose own component is 0
    const double length = std::sqrt(lj * lj + lk * lk);
    if (length < 1e-9) continue;  // the segment along e_i: the faces above decide
    const double reach = half[j] * std::abs(lj) + half[k] * std::abs(lk) + grown * length;
    if (std::abs(centre[j] * lj + centre[k] * lk) > reach) return true;
  }
  return false;
}

bool env_collides(const CollisionShapes& shapes, const CollisionData& data, int a, int o) {
  const CollisionShapes::Robot& robot = shapes.robot[a];
  const CollisionShapes::Obstacle& obstacle = shapes.obstacles[o];
  if (!sphere_may_touch_box(data.sphere_centre[a], shapes.env_radius[a], obstacle)) return false;
  if (!robot.inflated && obstacle.primitive && is_convex(robot.exact))  // a hull
    return convex_pair_collides(data, shapes.margin, robot.exact, data.transform[a],
                                obstacle.geometry, obstacle.transform);
  if (!robot.inflated)  // a mesh
    return mesh_pair_collides(data, shapes.margin, robot.exact, data.transform[a],
                              obstacle.geometry, obstacle.transform);
  if (!obstacle.primitive)
    return collide_with_bvh(data, robot.inflated, data.transform[a], obstacle.geometry,
                            obstacle.transform);
  if (clearly_apart(robot.inflated, data.transform[a], obstacle.geometry, obstacle.transform))
    return false;
  return narrow_collide(robot.inflated, data.transform[a], obstacle.geometry, obstacle.transform);
}

}  // namespace

CollisionModel build_collision_model(const RobotModel& robot, const Environment& env,
                                     const CollisionOptions& options) {
  CollisionModel model;
  auto shapes = std::make_shared<CollisionShapes>();
  model.margin = robot.geometry.margin;
  shapes->margin = model.margin;
  for (const CollisionBody& cb : robot.geometry.bodies) {
    CollisionModel::RobotShape s;
    s.name = cb.name;
    s.link = cb.link;
    s.body = robot.links[cb.link].body;
    s.in_body = robot.links[cb.link].in_body * cb.in_link;
    s.sphere_radius = bounding_radius(cb.shape);
    CollisionShapes::Robot g;
    g.exact = own(*shapes, make_geometry(cb.shape, 0));
    // A mesh has no grown copy: its pairs compare distances with the margin.
    if (cb.shape.type != ShapeType::Mesh)
      g.inflated = own(*shapes, make_geometry(cb.shape, model.margin));
    g.sphere_radius = s.sphere_radius;
    model.robot.push_back(s);
    shapes->robot.push_back(g);
    shapes->env_radius.push_back(s.sphere_radius + model.margin);
    shapes->capsule.push_back(
        cb.shape.type == ShapeType::Capsule ? static_cast<const fcl::Capsuled*>(g.exact) : nullptr);
  }
  for (const Obstacle& o : env.obstacles) {
    CollisionModel::ObstacleShape s;
    s.name = o.name;
    s.pose = o.pose;
    s.transform = to_fcl(o.pose);
    // World box around the obstacle's local bounding box (tight for axis-aligned obstacles).
    Eigen::Vector3d lower, upper;
    local_bounds(o, lower, upper);
    const Eigen::Vector3d centre = o.pose.R * ((lower + upper) / 2) + o.pose.p;
    const Eigen::Vector3d half = o.pose.R.cwiseAbs() * ((upper - lower) / 2);
    s.box_min = centre - half;
    s.box_max = centre + half;
    model.obstacles.push_back(s);
    CollisionShapes::Obstacle g;
    g.box_min = s.box_min;
    g.box_max = s.box_max;
    g.transform = s.transform;
    g.geometry = own(*shapes, obstacle_geometry(o));
    g.primitive = is_primitive(g.geometry);
    shapes->obstacles.push_back(g);
  }
  model.shapes = std::move(shapes);
  const int n = static_cast<int>(model.robot.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const auto& sa = model.robot[a];
      const auto& sb = model.robot[b];
      if (sa.body == sb.body) continue;  // rigidly joined: their distance never changes
      if (!options.ignore_allowed_pairs && robot.geometry.is_allowed_pair(sa.link, sb.link))
        continue;
      model.self_pairs.emplace_back(a, b);
    }
  }
  for (size_t o = 0; o < env.obstacles.size(); ++o) {
    const std::vector<int> allowed =
        allowed_links_of(robot, env.obstacles[o], env.origin.empty() ? env.path : env.origin);
    for (int a = 0; a < n; ++a) {
      if (std::find(allowed.begin(), allowed.end(), model.robot[a].link) != allowed.end()) continue;
      model.env_pairs.emplace_back(a, static_cast<int>(o));
    }
  }
  return model;
}

std::vector<int> allowed_links_of(const RobotModel& robot, const Obstacle& obstacle,
                                  const std::string& where) {
  std::vector<int> allowed;
  for (const std::string& name : obstacle.allowed_links) {
    if (name == kBaseLinks) {
      for (size_t l = 0; l < robot.links.size(); ++l)
        if (robot.links[l].body <= 0) allowed.push_back(static_cast<int>(l));
      continue;
    }
    const int link = robot.link_index(name);
    if (link < 0) {
      fail(where, "object '" + obstacle.name + "': allowed link '" + name +
                      "' is not a link of robot '" + robot.name + "' (" + kBaseLinks +
                      " names its base and first link for any robot)");
    }
    allowed.push_back(link);
  }
  return allowed;
}

CollisionData::CollisionData(const CollisionModel& model)
    : transform(model.robot.size(), Eigen::Isometry3d::Identity()),
      sphere_centre(model.robot.size(), Eigen::Vector3d::Zero()),
      scratch(std::make_unique<CollisionScratch>()) {
  scratch->distance_request.gjk_solver_type = fcl::GST_INDEP;
}

CollisionData::~CollisionData() = default;
CollisionData::CollisionData(const CollisionData& other)
    : transform(other.transform),
      sphere_centre(other.sphere_centre),
      scratch(other.scratch ? std::make_unique<CollisionScratch>(*other.scratch) : nullptr) {}
CollisionData& CollisionData::operator=(const CollisionData& other) {
  if (this != &other) *this = CollisionData(other);
  return *this;
}
CollisionData::CollisionData(CollisionData&&) noexcept = default;
CollisionData& CollisionData::operator=(CollisionData&&) noexcept = default;

void update_collision_transforms(const CollisionModel& model, CollisionData& data,
                                 const RobotData& robot_data) {
  for (size_t a = 0; a < model.robot.size(); ++a) {
    const CollisionModel::RobotShape& s = model.robot[a];
    const Pose world = s.body < 0 ? s.in_body : robot_data.body_pose[s.body] * s.in_body;
    data.transform[a].linear() = world.R;
    data.transform[a].translation() = world.p;
    data.sphere_centre[a] = world.p;  // every shape is centred on its own frame origin
  }
}

bool in_collision(const CollisionModel& model, CollisionData& data) {
  const CollisionShapes& shapes = *model.shapes;
  for (const auto& [a, o] : model.env_pairs) {
    if (env_collides(shapes, data, a, o)) return true;
  }
  for (const auto& [a, b] : model.self_pairs) {
    if (self_collides(shapes, data, a, b)) return true;
  }
  return false;
}

CollisionReport check_collision(const CollisionModel& model, CollisionData& data) {
  const CollisionShapes& shapes = *model.shapes;
  CollisionReport report;
  for (const auto& [a, o] : model.env_pairs) {
    if (env_collides(shapes, data, a, o)) {
      report.env_collision = true;
      report.first_a = a;
      report.first_b = o;
      break;
    }
  }
  for (const auto& [a, b] : model.self_pairs) {
    if (self_collides(shapes, data, a, b)) {
      report.self_collision = true;
      if (report.first_a < 0) {
        report.first_a = a;
        report.first_b = b;
      }
      break;
    }
  }
  return report;
}

DistanceReport min_distance(const CollisionModel& model, CollisionData& data) {
  DistanceReport report;
  for (const auto& [a, o] : model.env_pairs) {
    report.env_distance = std::min(
        report.env_distance,
        narrow_distance(data, model.shapes->robot[a].exact, data.transform[a],
                        model.shapes->obstacles[o].geometry, model.obstacles[o].transform));
  }
  for (const auto& [a, b] : model.self_pairs) {
    const CollisionShapes::Robot& sa = model.shapes->robot[a];
    const CollisionShapes::Robot& sb = model.shapes->robot[b];
    if (model.shapes->capsule[a] && model.shapes->capsule[b]) {
      report.self_distance = std::min(report.self_distance,
                                      std::max(0.0, capsule_distance(*model.shapes, data, a, b)));
      continue;
    }
    report.self_distance =
        std::min(report.self_distance,
                 narrow_distance(data, sa.exact, data.transform[a], sb.exact, data.transform[b]));
  }
  return report;
}

bool self_pair_collides(const CollisionModel& model, CollisionData& data, int shape_a,
                        int shape_b) {
  return self_collides(*model.shapes, data, shape_a, shape_b);
}

int obstacle_at(const CollisionModel& model, CollisionData& data, const Eigen::Vector3d& point) {
  const fcl::Sphered dot(1e-6);
  fcl::Transform3d at = fcl::Transform3d::Identity();
  at.translation() = point;
  for (size_t o = 0; o < model.obstacles.size(); ++o) {
    const CollisionModel::ObstacleShape& shape = model.obstacles[o];
    if ((point.array() < shape.box_min.array()).any() ||
        (point.array() > shape.box_max.array()).any())
      continue;
    if (collide_with_bvh(data, &dot, at, model.shapes->obstacles[o].geometry, shape.transform))
      return static_cast<int>(o);
  }
  return -1;
}

}  // namespace lazyboe
