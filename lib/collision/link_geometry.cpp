#include "lazyboe/collision/link_geometry.h"

#include <urdf_model/link.h>

#include <cmath>

#include "lazyboe/collision/convex_hull.h"
#include "lazyboe/collision/mesh.h"
#include "lazyboe/collision/mesh_fit.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/resource_path.h"
#include "lazyboe/robot/urdf_pose.h"

namespace lazyboe {
namespace {

// Thinner than this (m) along every direction of one axis, a mesh encloses no volume.
constexpr double kFlatMesh = 1e-6;

struct Element {
  CollisionBody body;
  bool used = false;  // merged into a capsule
};

}  // namespace

Shape urdf_primitive_shape(const urdf::Geometry& geometry, const std::string& where) {
  Shape shape;
  switch (geometry.type) {
    case urdf::Geometry::SPHERE:
      shape.type = ShapeType::Sphere;
      shape.radius = static_cast<const urdf::Sphere&>(geometry).radius;
      if (!(shape.radius > 0)) fail(where, "sphere radius must be > 0");
      break;
    case urdf::Geometry::BOX: {
      const urdf::Vector3& dim = static_cast<const urdf::Box&>(geometry).dim;
      shape.type = ShapeType::Box;
      shape.size = Eigen::Vector3d(dim.x, dim.y, dim.z);
      if (!(shape.size.minCoeff() > 0)) fail(where, "box size must be > 0");
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& cyl = static_cast<const urdf::Cylinder&>(geometry);
      shape.type = ShapeType::Cylinder;
      shape.radius = cyl.radius;
      shape.length = cyl.length;
      if (!(cyl.radius > 0 && cyl.length > 0)) fail(where, "cylinder size must be > 0");
      break;
    }
    default:
      fail(where, "unknown collision geometry");
  }
  return shape;
}

namespace {

// The mesh of a <mesh> element, scaled, with the reader's errors prefixed by `where`.
TriangleMesh read_link_mesh(const std::string& file, const urdf::Mesh& m,
                            const std::string& where) {
  TriangleMesh mesh;
  try {
    mesh = load_mesh(file, Eigen::Vector3d(m.scale.x, m.scale.y, m.scale.z));
  } catch (const Error& e) {
    fail(where, e.what());
  }
  if (thinnest_extent(mesh) < kFlatMesh) {
    fail(where, file + ": degenerate mesh (zero volume: its vertices lie in one plane)");
  }
  return mesh;
}

// A mesh element as a fitted capsule (or sphere), or as the mesh itself or its convex hull
// about its box centre.
void set_mesh_shape(CollisionBody& body, TriangleMesh mesh, MeshRepresentation representation,
                    const std::string& where) {
  body.representation = representation;
  if (representation != MeshRepresentation::Exact) {  // an exact shape is the mesh itself
    body.source_mesh = std::make_shared<const TriangleMesh>(mesh);
    body.source_in_link = body.in_link;
  }
  if (representation == MeshRepresentation::Fitted) {
    const FittedShape fitted = fit_enclosing_capsule(mesh);
    body.shape = fitted.shape;
    body.in_link = body.in_link * fitted.in_mesh;
    body.over_approximation = fitted.over_approximation;
    return;
  }
  if (representation == MeshRepresentation::Convex) {
    mesh = convex_hull(mesh, where + ": " + body.mesh_file);
    body.shape.convex = true;
  }
  Eigen::Vector3d lower, upper;
  mesh_bounds(mesh, lower, upper);
  const Eigen::Vector3d centre = (lower + upper) / 2;  // a small bounding sphere about the frame
  for (Eigen::Vector3d& v : mesh.vertices) v -= centre;
  body.shape.type = ShapeType::Mesh;
  body.shape.mesh = std::make_shared<const TriangleMesh>(std::move(mesh));
  body.in_link = body.in_link * Pose(Eigen::Matrix3d::Identity(), centre);
}

// Merges each cylinder with two spheres of its radius centred on its ends into one capsule.
void merge_capsules(std::vector<Element>& elements) {
  const double tol = 1e-6;
  for (Element& cyl : elements) {
    CollisionBody& c = cyl.body;
    if (c.shape.type != ShapeType::Cylinder) continue;
    const Eigen::Vector3d axis = c.in_link.R.col(2);
    const double half = c.shape.length / 2;
    Element* caps[2] = {nullptr, nullptr};
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d centre = c.in_link.p + (end == 0 ? half : -half) * axis;
      for (Element& s : elements) {
        if (!s.used && s.body.mesh_file.empty() && s.body.shape.type == ShapeType::Sphere &&
            std::abs(s.body.shape.radius - c.shape.radius) < tol &&
            (s.body.in_link.p - centre).norm() < tol) {
          caps[end] = &s;
          break;
        }
      }
    }
    if (!caps[0] || !caps[1] || caps[0] == caps[1]) continue;
    caps[0]->used = caps[1]->used = true;
    c.shape.type = ShapeType::Capsule;
    for (const std::string suffix : {"_cylinder", "_cyl"}) {
      const size_t n = suffix.size();
      if (c.name.size() > n && c.name.compare(c.name.size() - n, n, suffix) == 0) {
        c.name.resize(c.name.size() - n);
        break;
      }
    }
  }
}

}  // namespace

MeshRepresentation MeshSettings::of(const std::string& link) const {
  for (const auto& [name, r] : per_link)
    if (name == link) return r;
  return representation;
}

void add_link_collision_bodies(RobotModel& model, const urdf::Link& link, int link_index,
                               const MeshSettings& meshes) {
  const std::vector<std::string> search = package_search_path(model.files.package_path);
  std::vector<Element> elements;
  for (size_t k = 0; k < link.collision_array.size(); ++k) {
    const urdf::Collision& c = *link.collision_array[k];
    const std::string where =
        model.files.urdf + ": link '" + link.name + "' collision " + std::to_string(k);
    if (!c.geometry) fail(where, "missing geometry");
    Element e;
    e.body.name = c.name.empty() ? link.name + "_" + std::to_string(k) : c.name;
    e.body.link = link_index;
    e.body.in_link = pose_from_urdf(c.origin);
    if (c.geometry->type == urdf::Geometry::MESH) {
      const auto& m = static_cast<const urdf::Mesh&>(*c.geometry);
      e.body.mesh_file = resolve_urdf_resource(m.filename, model.files.urdf, search, where);
      set_mesh_shape(e.body, read_link_mesh(e.body.mesh_file, m, where), meshes.of(link.name),
                     where);
      model.files.resources.push_back(e.body.mesh_file);
    } else {
      e.body.shape = urdf_primitive_shape(*c.geometry, where);
    }
    elements.push_back(std::move(e));
  }
  merge_capsules(elements);
  for (Element& e : elements)
    if (!e.used) model.geometry.bodies.push_back(std::move(e.body));
}

}  // namespace lazyboe
