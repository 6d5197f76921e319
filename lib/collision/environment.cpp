#include "lazyboe/collision/environment.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include "lazyboe/common/data_dir.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
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

std::string resolve_environment_path(const std::string& path) {
  // A path or a file name is a file: never silently another one (a missing table.json is not
  // the bundled table). Only a bare name ("shelf") names a bundled scene.
  return resolve_bundled_file(path, data_dir() + "/environments", "scene");
}

Environment load_environment(const std::string& path) {
  const std::string file = resolve_environment_path(path);
  const nlohmann::json doc = load_json_file(file);
  return environment_from_json(JsonField(doc, file, ""), file);
}

namespace {

// A file an object names: relative to the environment file's folder (an inline scene's: the
// current directory).
std::string object_file(const JsonField& item, const std::string& env_path) {
  const std::string name = item.at("file").string();
  if (name.empty()) item.at("file").fail("must not be empty");
  const std::filesystem::path file(name);
  if (file.is_absolute() || env_path.empty()) return name;
  return (std::filesystem::path(env_path).parent_path() / file).string();
}

// Loaders throw Error naming the file; the message gets the field's place first.
template <typename Load>
auto load_for(const JsonField& field, Load load) {
  try {
    return load();
  } catch (const Error& e) {
    field.fail(e.what());
  }
}

void parse_primitive(const JsonField& item, const std::string& type, Obstacle& o) {
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
                         "' (expected box, sphere, cylinder, capsule, mesh, points or octree)");
  }
}

Eigen::Vector3d mesh_scale(const JsonField& item) {
  if (!item.has("scale")) return Eigen::Vector3d::Ones();
  const JsonField f = item.at("scale");
  if (f.value().is_number()) return Eigen::Vector3d::Constant(f.number_in(kExtent));
  return f.vec3_in(kExtent);
}

std::vector<Eigen::Vector3d> inline_points(const JsonField& f) {
  std::vector<Eigen::Vector3d> points;
  for (const JsonField& p : f.items()) points.push_back(p.vec3_in(kPosition, " m"));
  return points;
}

// Meshes, point clouds and octrees; their files are recorded in env.files.
void parse_geometry(const JsonField& item, const std::string& type, Environment& env, Obstacle& o) {
  const std::vector<std::string> placed = {"name", "type",       "position",
                                           "rpy",  "quaternion", "allowed_links"};
  auto allow = [&](std::vector<std::string> extra) {
    extra.insert(extra.end(), placed.begin(), placed.end());
    item.allow_only(extra);
  };
  if (type == "mesh") {
    allow({"file", "scale"});
    const std::string file = object_file(item, env.path);
    o.type = ObstacleType::Mesh;
    o.mesh = std::make_shared<const TriangleMesh>(
        load_for(item.at("file"), [&] { return load_mesh(file, mesh_scale(item)); }));
    env.files.push_back(file);
  } else if (type == "points") {
    allow({"file", "points", "resolution"});
    if (item.has("file") == item.has("points"))
      item.fail("give \"file\" or \"points\", one of them");
    const double resolution = item.at("resolution").number_in({0, 100, true}, " m");
    std::vector<Eigen::Vector3d> points;
    if (item.has("file")) {
      const std::string file = object_file(item, env.path);
      points = load_for(item.at("file"), [&] { return load_point_cloud(file); });
      env.files.push_back(file);
    } else {
      points = inline_points(item.at("points"));
    }
    o.type = ObstacleType::Octree;
    o.cells = voxelise(points, resolution, item.where());
  } else {
    allow({"file"});
    const std::string file = object_file(item, env.path);
    o.type = ObstacleType::Octree;
    o.cells = load_for(item.at("file"), [&] { return load_octree(file); });
    env.files.push_back(file);
  }
}

void parse_pose(const JsonField& item, bool required, Pose& pose) {
  if (required || item.has("position")) pose.p = item.at("position").vec3_in(kPosition, " m");
  if (item.has("rpy") && item.has("quaternion")) item.fail("give rpy or quaternion, not both");
  if (item.has("rpy")) {
    const Eigen::Vector3d rpy = item.at("rpy").vec3_in(kAngle, " rad");
    pose.R = rotation_from_rpy(rpy.x(), rpy.y(), rpy.z());
  } else if (item.has("quaternion")) {
    const std::vector<JsonField> items = item.at("quaternion").items();
    if (items.size() != 4) item.at("quaternion").fail("expected 4 numbers [w, x, y, z]");
    std::vector<double> q;
    for (const JsonField& c : items) q.push_back(c.number_in(kQuaternionComponent));
    Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    if (!(quat.norm() > 1e-9)) item.at("quaternion").fail("must not be zero");
    pose.R = quat.normalized().toRotationMatrix();
  }
}

Obstacle parse_object(const JsonField& item, Environment& env) {
  Obstacle o;
  o.name = item.at("name").string();
  const std::string type = item.at("type").string();
  const bool geometry = type == "mesh" || type == "points" || type == "octree";
  if (geometry)
    parse_geometry(item, type, env, o);
  else
    parse_primitive(item, type, o);
  // A mesh, cloud or map is placed by its own coordinates unless a pose is given.
  parse_pose(item, !geometry, o.pose);
  if (item.has("allowed_links")) {
    for (const JsonField& link : item.at("allowed_links").items())
      o.allowed_links.push_back(link.string());
  }
  return o;
}

// The description's hash, and each named file's content.
std::string identity_of(const JsonField& root, const std::vector<std::string>& files) {
  Fnv1a64 h;
  h.update(root.value().dump());
  if (!files.empty()) h.update(hash_files(files));
  return h.hex();
}

}  // namespace

Environment environment_from_json(const JsonField& root, const std::string& path) {
  root.allow_only({"schema_version", "name", "description", "objects"});
  if (root.at("schema_version").integer() != 1) {
    root.at("schema_version").fail("unsupported version (this build reads version 1)");
  }
  Environment env;
  env.path = path;
  env.origin = root.path().empty() ? path : root.where();
  env.name = root.at("name").string();
  if (root.has("description")) env.description = root.at("description").string();
  std::set<std::string> names;
  for (const JsonField& item : root.at("objects").items()) {
    env.obstacles.push_back(parse_object(item, env));
    if (!names.insert(env.obstacles.back().name).second)
      item.at("name").fail("duplicate object name '" + env.obstacles.back().name + "'");
  }
  env.identity = identity_of(root, env.files);
  return env;
}

}  // namespace lazyboe
