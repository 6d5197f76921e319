#include "lazyboe/collision/environment.h"

#include <set>

#include "lazyboe/common/hash.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"

namespace lazyboe {
namespace {

// Accepted ranges (schemas/environment.schema.json and docs/reliability.md list the same): a
// scene of at most a few hundred metres around the robot, so that no size or distance
// overflows the collision checker's arithmetic.
const RealRange kExtent{0, 100, true};  // box sizes, radii, lengths, m
const RealRange kPosition{-100, 100};   // m
const RealRange kAngle{-100, 100};      // rad
const RealRange kQuaternionComponent{-1e3, 1e3};

}  // namespace

std::string default_environment_path() { return data_dir() + "/environments/table.json"; }

Environment load_environment(const std::string& path) {
  const nlohmann::json doc = load_json_file(path);
  return environment_from_json(JsonField(doc, path, ""), path);
}

Environment environment_from_json(const JsonField& root, const std::string& path) {
  root.allow_only({"schema_version", "name", "description", "objects"});
  if (root.at("schema_version").integer() != 1) {
    root.at("schema_version").fail("unsupported version (this build reads version 1)");
  }
  Environment env;
  env.path = path;
  env.origin = root.path().empty() ? path : root.where();
  env.identity = fnv1a64_hex(root.value().dump());
  env.name = root.at("name").string();
  if (root.has("description")) env.description = root.at("description").string();
  std::set<std::string> names;
  for (const JsonField& item : root.at("objects").items()) {
    Obstacle o;
    o.name = item.at("name").string();
    if (!names.insert(o.name).second)
      item.at("name").fail("duplicate object name '" + o.name + "'");
    const std::string type = item.at("type").string();
    if (type == "box") {
      item.allow_only({"name", "type", "size", "position", "rpy", "quaternion", "allowed_links"});
      o.shape.type = ShapeType::Box;
      o.shape.size = item.at("size").vec3_in(kExtent, " m");
    } else if (type == "sphere") {
      item.allow_only({"name", "type", "radius", "position", "allowed_links"});
      o.shape.type = ShapeType::Sphere;
      o.shape.radius = item.at("radius").number_in(kExtent, " m");
    } else if (type == "cylinder" || type == "capsule") {
      item.allow_only(
          {"name", "type", "radius", "length", "position", "rpy", "quaternion", "allowed_links"});
      o.shape.type = type == "cylinder" ? ShapeType::Cylinder : ShapeType::Capsule;
      o.shape.radius = item.at("radius").number_in(kExtent, " m");
      o.shape.length = item.at("length").number_in(kExtent, " m");
    } else {
      item.at("type").fail("unknown object type '" + type +
                           "' (expected box, sphere, cylinder or capsule)");
    }
    o.pose.p = item.at("position").vec3_in(kPosition, " m");
    if (item.has("rpy") && item.has("quaternion")) item.fail("give rpy or quaternion, not both");
    if (item.has("rpy")) {
      const Eigen::Vector3d rpy = item.at("rpy").vec3_in(kAngle, " rad");
      o.pose.R = rotation_from_rpy(rpy.x(), rpy.y(), rpy.z());
    } else if (item.has("quaternion")) {
      const std::vector<JsonField> items = item.at("quaternion").items();
      if (items.size() != 4) item.at("quaternion").fail("expected 4 numbers [w, x, y, z]");
      std::vector<double> q;
      for (const JsonField& c : items) q.push_back(c.number_in(kQuaternionComponent));
      Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
      if (!(quat.norm() > 1e-9)) item.at("quaternion").fail("must not be zero");
      o.pose.R = quat.normalized().toRotationMatrix();
    }
    if (item.has("allowed_links")) {
      for (const JsonField& link : item.at("allowed_links").items()) {
        o.allowed_links.push_back(link.string());
      }
    }
    env.obstacles.push_back(o);
  }
  return env;
}

}  // namespace lazyboe
