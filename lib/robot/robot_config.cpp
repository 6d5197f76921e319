#include "lazyboe/robot/robot_config.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <utility>

#include "lazyboe/collision/link_geometry.h"
#include "lazyboe/common/data_dir.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/urdf_parser.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;

// The accepted ranges of the robot config's numbers (schemas/robot-config.schema.json and
// docs/reliability.md list the same): physical bounds wide enough for any real arm, narrow
// enough that the dynamics cannot overflow.
const RealRange kFrictionCoefficient{-1e6, 1e6};
const RealRange kFrictionTorque{0, 1e6};
const RealRange kSmoothingVelocity{0, 1e3, true};
const RealRange kMaxAcceleration{0, 1e6, true};
const RealRange kMaxJerk{0, 1e9, true};
const RealRange kMaxTorqueRate{0, 1e9, true};
const RealRange kGain{0, 1e6};
const RealRange kCollisionMargin{0, 1};
const RealRange kGravity{-1e3, 1e3};
const RealRange kRegionBound{-1e3, 1e3};

Friction read_friction(const JsonField& f) {
  Friction friction;
  const std::string model = f.at("model").string();
  if (model == "none") {
    f.allow_only({"model"});
  } else if (model == "sigmoid") {
    f.allow_only({"model", "fi1", "fi2", "fi3"});
    friction.model = FrictionModel::Sigmoid;
    friction.a = f.at("fi1").number_in(kFrictionCoefficient);
    friction.b = f.at("fi2").number_in(kFrictionCoefficient);
    friction.c = f.at("fi3").number_in(kFrictionCoefficient);
    friction.offset = friction.a / (1 + std::exp(-friction.b * friction.c));
  } else if (model == "viscous_coulomb") {
    f.allow_only({"model", "coulomb", "viscous", "smoothing_velocity"});
    friction.model = FrictionModel::ViscousCoulomb;
    friction.a = f.at("coulomb").number_in(kFrictionTorque, " N m");
    friction.b = f.at("viscous").number_in(kFrictionTorque, " N m s/rad");
    friction.c = f.at("smoothing_velocity").number_in(kSmoothingVelocity, " rad/s");
  } else {
    f.at("model").fail("unknown friction model '" + model +
                       "' (expected none, sigmoid or viscous_coulomb)");
  }
  return friction;
}

// A continuous joint's planned range: [lower, upper], rad, finite, lower < upper.
void read_position_range(const JsonField& field, Joint& joint) {
  if (!joint.continuous) {
    field.fail("only a continuous joint takes a position range ('" + joint.name +
               "' has the URDF's limits)");
  }
  const std::vector<JsonField> bounds = field.items();
  if (bounds.size() != 2) field.fail("expected [lower, upper] in rad");
  const RealRange any{-1e6, 1e6};
  joint.lower = bounds[0].number_in(any, " rad");
  joint.upper = bounds[1].number_in(any, " rad");
  if (!(joint.lower < joint.upper)) field.fail("expected lower < upper");
}

void read_config_joints(RobotModel& model, const JsonField& root) {
  std::vector<JsonField> entries = root.at("joints").items();
  std::set<std::string> seen;
  for (const JsonField& entry : entries) {
    entry.allow_only(
        {"name", "max_acceleration", "max_jerk", "max_torque_rate", "friction", "position_range"});
    const std::string name = entry.at("name").string();
    auto it = std::find_if(model.joints.begin(), model.joints.end(),
                           [&](const Joint& j) { return j.name == name; });
    if (it == model.joints.end()) {
      entry.at("name").fail("'" + name + "' is not a moving joint of the chain");
    }
    if (!seen.insert(name).second) entry.at("name").fail("joint '" + name + "' listed twice");
    it->max_acceleration = entry.at("max_acceleration").number_in(kMaxAcceleration, " rad/s^2");
    it->max_jerk = entry.at("max_jerk").number_in(kMaxJerk, " rad/s^3");
    it->max_torque_rate = entry.at("max_torque_rate").number_in(kMaxTorqueRate, " N m/s");
    it->friction = read_friction(entry.at("friction"));
    if (entry.has("position_range")) read_position_range(entry.at("position_range"), *it);
  }
  for (const Joint& j : model.joints) {
    if (!seen.count(j.name)) root.at("joints").fail("no entry for joint '" + j.name + "'");
  }
}

void read_controller(RobotModel& model, const JsonField& root) {
  if (!root.has("controller")) return;
  const JsonField c = root.at("controller");
  c.allow_only({"type", "description", "kv", "ka", "friction_feedforward"});
  if (c.at("type").string() != "velocity_tracking") {
    c.at("type").fail("unknown controller (expected velocity_tracking)");
  }
  for (auto [key, gains] : {std::pair<const char*, JointVector*>{"kv", &model.controller.kv},
                            std::pair<const char*, JointVector*>{"ka", &model.controller.ka}}) {
    const std::vector<JsonField> items = c.at(key).items();
    if (static_cast<int>(items.size()) != model.dof) {
      c.at(key).fail("expected " + std::to_string(model.dof) + " gains, one per moving joint");
    }
    gains->resize(model.dof);
    for (int i = 0; i < model.dof; ++i) (*gains)[i] = items[i].number_in(kGain);
  }
  if (c.has("friction_feedforward")) {
    model.controller.friction_feedforward = c.at("friction_feedforward").boolean();
  }
  model.controller.present = true;
}

MeshRepresentation mesh_representation(const JsonField& field) {
  return parse_mesh_representation(field.string(), field.where());
}

// collision.meshes: {"representation": "fitted" | "exact" | "convex", "links": {"<link>":
// "exact", ...}}.
MeshSettings read_mesh_settings(const RobotModel& model, const JsonField& collision) {
  MeshSettings settings;
  if (!collision.has("meshes")) return settings;
  const JsonField meshes = collision.at("meshes");
  meshes.allow_only({"representation", "links"});
  if (meshes.has("representation"))
    settings.representation = mesh_representation(meshes.at("representation"));
  if (!meshes.has("links")) return settings;
  const JsonField links = meshes.at("links");
  if (!links.value().is_object()) links.fail("expected an object: link name -> fitted or exact");
  for (const auto& item : links.value().items()) {
    const std::string& link = item.key();
    const JsonField entry = links.at(link);
    if (model.link_index(link) < 0) entry.fail("unknown link '" + link + "'");
    settings.per_link.emplace_back(link, mesh_representation(entry));
  }
  return settings;
}

void read_collision(RobotModel& model, const JsonField& root,
                    const std::vector<urdf::LinkConstSharedPtr>& link_sources) {
  const JsonField collision = root.at("collision");
  collision.allow_only({"margin", "allowed_pairs", "meshes"});
  model.geometry.margin = collision.at("margin").number_in(kCollisionMargin, " m");
  const MeshSettings meshes = read_mesh_settings(model, collision);
  for (size_t i = 0; i < model.links.size(); ++i) {
    add_link_collision_bodies(model, *link_sources[i], static_cast<int>(i), meshes);
  }
  if (!collision.has("allowed_pairs")) return;
  for (const JsonField& pair : collision.at("allowed_pairs").items()) {
    std::vector<JsonField> names = pair.items();
    if (names.size() != 2) pair.fail("expected two link names");
    int idx[2];
    for (int k = 0; k < 2; ++k) {
      const std::string n = names[k].string();
      idx[k] = model.link_index(n);
      if (idx[k] < 0) names[k].fail("unknown link '" + n + "'");
    }
    if (idx[0] == idx[1]) pair.fail("a pair needs two different links");
    model.geometry.allowed_pairs.emplace_back(std::min(idx[0], idx[1]), std::max(idx[0], idx[1]));
  }
  std::sort(model.geometry.allowed_pairs.begin(), model.geometry.allowed_pairs.end());
  model.geometry.allowed_pairs.erase(
      std::unique(model.geometry.allowed_pairs.begin(), model.geometry.allowed_pairs.end()),
      model.geometry.allowed_pairs.end());
}

// The per-joint limit vectors, from the joints.
void fill_limits(RobotModel& model) {
  const int n = model.dof;
  for (JointVector* v : {&model.q_min, &model.q_max, &model.dq_max, &model.ddq_max, &model.dddq_max,
                         &model.tau_max, &model.dtau_max}) {
    v->resize(n);
  }
  for (int i = 0; i < n; ++i) {
    const Joint& j = model.joints[i];
    model.q_min[i] = j.lower;
    model.q_max[i] = j.upper;
    model.dq_max[i] = j.max_velocity;
    model.ddq_max[i] = j.max_acceleration;
    model.dddq_max[i] = j.max_jerk;
    model.tau_max[i] = j.max_effort;
    model.dtau_max[i] = j.max_torque_rate;
  }
}

// The sampling region (default: the joint limits).
void read_sampling_region(RobotModel& model, const JsonField& root) {
  const int n = model.dof;
  model.region.lower = model.q_min;
  model.region.upper = model.q_max;
  if (!root.has("sampling_region")) return;
  const JsonField region = root.at("sampling_region");
  region.allow_only({"description", "lower", "upper"});
  for (auto [key, bound] : {std::pair<const char*, JointVector*>{"lower", &model.region.lower},
                            std::pair<const char*, JointVector*>{"upper", &model.region.upper}}) {
    const std::vector<JsonField> v = region.at(key).items();
    if (static_cast<int>(v.size()) != n) {
      region.at(key).fail("expected " + std::to_string(n) + " values, one per moving joint");
    }
    for (int i = 0; i < n; ++i) (*bound)[i] = v[i].number_in(kRegionBound, " rad or m");
  }
  for (int i = 0; i < n; ++i) {
    if (!(model.region.lower[i] < model.region.upper[i])) {
      region.fail("joint " + std::to_string(i + 1) + ": lower must be below upper");
    }
    if (model.region.lower[i] < model.q_min[i] || model.region.upper[i] > model.q_max[i]) {
      region.fail("joint " + std::to_string(i + 1) + ": outside the joint limits");
    }
  }
}

// A chain whose mass matrix is singular (a moving body with no mass or inertia about its
// axis) cannot be simulated; say so now rather than produce NaNs later.
void check_mass_matrix(const RobotModel& model, const std::string& upath) {
  RobotData data(model);
  const JointVector mid = (model.q_min + model.q_max) / 2;
  const JointMatrix& M = mass_matrix(model, data, mid);
  Eigen::SelfAdjointEigenSolver<JointMatrix> eig(M);
  if (!(eig.eigenvalues().minCoeff() > 1e-12)) {
    fail(upath, "the mass matrix is singular: a moving body has no mass or inertia");
  }
}

}  // namespace

int link_field(const JsonField& object, const RobotModel& robot) {
  if (!object.has("link")) return robot.tip_link();
  const std::string name = object.at("link").string();
  const int link = robot.link_index(name);
  if (link < 0) object.at("link").fail(robot.unknown_link(name));
  return link;
}

std::string default_robot_path() { return data_dir() + "/robots/panda.json"; }

RobotModel load_robot(const std::string& config_path) {
  const std::string path = resolve_bundled_file(config_path, data_dir() + "/robots", "robot");
  return robot_from_json(load_json_file(path), path);
}

RobotModel robot_from_json(const nlohmann::json& config, const std::string& config_path) {
  const JsonField root(config, config_path, "");
  root.allow_only({"schema_version", "name", "description", "urdf", "base_link", "tip_link",
                   "gravity", "control_rate", "joints", "collision", "controller",
                   "sampling_region", "package_path"});
  if (root.at("schema_version").integer() != 1) {
    root.at("schema_version").fail("unsupported version (this build reads version 1)");
  }

  RobotModel model;
  model.files.config = config_path;
  model.name = root.at("name").string();
  const std::string urdf_rel = root.at("urdf").string();
  model.files.urdf = (fs::path(config_path).parent_path() / urdf_rel).lexically_normal().string();
  if (root.has("package_path")) {
    for (const JsonField& dir : root.at("package_path").items())
      model.files.package_path.push_back(
          (fs::path(config_path).parent_path() / dir.string()).lexically_normal().string());
  }
  if (root.has("gravity")) model.gravity = root.at("gravity").vec3_in(kGravity, " m/s^2");
  if (root.has("control_rate")) {
    const long rate = root.at("control_rate").integer();
    if (rate < 1 || rate > 1000000) root.at("control_rate").fail("must be in [1, 1000000] Hz");
    model.control_rate = static_cast<double>(rate);
  }

  const urdf::ModelInterfaceSharedPtr urdf_model = parse_urdf_file(model.files.urdf);
  const std::string& upath = model.files.urdf;
  std::string base_name;
  const std::vector<urdf::LinkConstSharedPtr> chain =
      find_chain(root, *urdf_model, upath, config_path, base_name);
  const std::vector<urdf::LinkConstSharedPtr> link_sources = build_bodies(model, chain, upath);
  if (model.dof == 0) fail(upath, "the chain from '" + base_name + "' has no moving joint");

  read_config_joints(model, root);
  read_controller(model, root);
  read_collision(model, root, link_sources);
  fill_limits(model);
  read_sampling_region(model, root);
  check_mass_matrix(model, upath);
  return model;
}

}  // namespace lazyboe
