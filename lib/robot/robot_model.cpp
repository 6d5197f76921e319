#include "lazyboe/robot/robot_model.h"

#include <algorithm>
#include <string>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/common/text.h"

namespace lazyboe {
namespace {

// The body's inertia about its origin: I_O = I_com + m (|c|^2 1 - c c^T) (parallel axes).
void origin_inertia(const BodyInertia& body, OriginInertia& out) {
  const Eigen::Vector3d& c = body.com;
  const double m = body.mass;
  const Eigen::Vector3d h = m * c;
  const Eigen::Matrix3d& I = body.inertia_com;
  Eigen::Matrix3d& J = out.rotational;
  J(0, 0) = I(0, 0) + (h.y() * c.y() + h.z() * c.z());
  J(1, 1) = I(1, 1) + (h.x() * c.x() + h.z() * c.z());
  J(2, 2) = I(2, 2) + (h.x() * c.x() + h.y() * c.y());
  J(1, 0) = J(0, 1) = I(0, 1) - h.x() * c.y();
  J(2, 0) = J(0, 2) = I(0, 2) - h.x() * c.z();
  J(2, 1) = J(1, 2) = I(1, 2) - h.y() * c.z();
  out.mass = m;
  out.first_moment = h;
}

}  // namespace

void merge_inertia(BodyInertia& into, double mass, const Eigen::Vector3d& com,
                   const Eigen::Matrix3d& inertia_com) {
  const double total = into.mass + mass;
  if (total <= 0) return;
  const Eigen::Vector3d c = (into.mass * into.com + mass * com) / total;
  auto shift = [](double m, const Eigen::Vector3d& d) {
    return m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  };
  into.inertia_com =
      into.inertia_com + shift(into.mass, into.com - c) + inertia_com + shift(mass, com - c);
  into.com = c;
  into.mass = total;
  origin_inertia(into, into.about_origin);
}

const char* shape_type_name(ShapeType type) {
  switch (type) {
    case ShapeType::Sphere:
      return "sphere";
    case ShapeType::Box:
      return "box";
    case ShapeType::Cylinder:
      return "cylinder";
    case ShapeType::Capsule:
      return "capsule";
    case ShapeType::Mesh:
      return "mesh";
  }
  return "?";
}

MeshRepresentation parse_mesh_representation(const std::string& name, const std::string& where) {
  for (MeshRepresentation r :
       {MeshRepresentation::Fitted, MeshRepresentation::Exact, MeshRepresentation::Convex}) {
    if (name == mesh_representation_name(r)) return r;
  }
  fail(where, "unknown mesh representation '" + name + "' (expected fitted, exact or convex)");
}

const char* mesh_representation_name(MeshRepresentation representation) {
  switch (representation) {
    case MeshRepresentation::Exact:
      return "exact";
    case MeshRepresentation::Convex:
      return "convex";
    case MeshRepresentation::Fitted:
      break;
  }
  return "fitted";
}

std::string RobotModel::unknown_link(const std::string& link_name) const {
  std::vector<std::string> names;
  for (const Link& l : links) names.push_back(l.name);
  const std::string close = did_you_mean(link_name, names);
  if (!close.empty()) return "unknown link '" + link_name + "'" + close;
  std::string text = "unknown link '" + link_name + "' (the links: ";
  for (size_t i = 0; i < names.size(); ++i) text += (i ? ", " : "") + names[i];
  return text + ")";
}

int RobotModel::link_index(const std::string& link_name) const {
  for (size_t i = 0; i < links.size(); ++i) {
    if (links[i].name == link_name) return static_cast<int>(i);
  }
  return -1;
}

bool RobotGeometry::is_allowed_pair(int link_a, int link_b) const {
  const std::pair<int, int> key(std::min(link_a, link_b), std::max(link_a, link_b));
  return std::binary_search(allowed_pairs.begin(), allowed_pairs.end(), key);
}

}  // namespace lazyboe
