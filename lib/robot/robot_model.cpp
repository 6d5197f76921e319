#include "lazyboe/robot/robot_model.h"

#include <console_bridge/console.h>
#include <dlfcn.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "lazyboe/collision/link_geometry.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/common/text.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/urdf_check.h"
#include "lazyboe/robot/urdf_pose.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;

// urdfdom reports parse problems through console_bridge; keep the last error for our message
// instead of letting it print to the terminal.
class CapturingOutputHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) last_error = text;
  }
  std::string last_error;
};

urdf::ModelInterfaceSharedPtr parse_urdf_file(const std::string& path) {
  require_input_file(path, "URDF file");
  std::ifstream in(path);
  if (!in) fail(path, "cannot open URDF file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  // urdfdom drops the XML parser's line number; parse once more to report where XML breaks.
  TiXmlDocument xml;
  xml.Parse(buffer.str().c_str());
  if (xml.Error()) {
    fail(path + ":" + std::to_string(xml.ErrorRow()) + ":" + std::to_string(xml.ErrorCol()),
         std::string("malformed XML (") + xml.ErrorDesc() + ")");
  }
  check_urdf_values(buffer.str(), path);
  CapturingOutputHandler handler;
  console_bridge::useOutputHandler(&handler);
  urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(buffer.str());
  console_bridge::restorePreviousOutputHandler();
  if (!urdf_model) {
    fail(path, "not a valid URDF" +
                   (handler.last_error.empty() ? std::string() : " (" + handler.last_error + ")"));
  }
  return urdf_model;
}

void check_inertial(const std::string& urdf_path, const urdf::Link& link) {
  if (!link.inertial) return;
  const urdf::Inertial& in = *link.inertial;
  const std::string where = urdf_path + ": link '" + link.name + "'";
  const double values[] = {in.mass, in.ixx, in.ixy, in.ixz, in.iyy, in.iyz, in.izz};
  for (double v : values) {
    if (!std::isfinite(v)) fail(where, "inertial values must be finite");
  }
  if (in.mass < 0) fail(where, "mass must be >= 0, got " + std::to_string(in.mass));
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I).eigenvalues();
  const double tol = 1e-9 * std::max(1.0, eig.cwiseAbs().maxCoeff());
  if (eig.minCoeff() < -tol) {
    fail(where, "inertia is not physical (not positive semi-definite)");
  }
  // Principal moments of a real body satisfy the triangle inequality.
  if (eig(0) + eig(1) < eig(2) - tol || eig(0) + eig(2) < eig(1) - tol ||
      eig(1) + eig(2) < eig(0) - tol) {
    fail(where, "inertia is not physical (principal moments violate the triangle inequality)");
  }
}

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

int link_field(const JsonField& object, const RobotModel& robot) {
  if (!object.has("link")) return robot.tip_link();
  const std::string name = object.at("link").string();
  const int link = robot.link_index(name);
  if (link < 0) object.at("link").fail(robot.unknown_link(name));
  return link;
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

bool RobotModel::is_allowed_pair(int link_a, int link_b) const {
  const std::pair<int, int> key(std::min(link_a, link_b), std::max(link_a, link_b));
  return std::binary_search(allowed_pairs.begin(), allowed_pairs.end(), key);
}

namespace {

// An installed copy of the data beside the binary this code was linked into: <prefix>/share/
// lazyboe above <prefix>/bin/<tool> or <prefix>/lib/python3.X/dist-packages/lazyboe/<module>.
std::string installed_beside_binary() {
  std::vector<std::filesystem::path> binaries;
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&installed_beside_binary), &info) && info.dli_fname)
    binaries.emplace_back(info.dli_fname);
  binaries.emplace_back("/proc/self/exe");  // dli_fname of the main program may be argv[0]
  for (const std::filesystem::path& binary : binaries) {
    std::error_code error;
    const std::filesystem::path dir = std::filesystem::canonical(binary, error).parent_path();
    if (error) continue;
    std::filesystem::path prefix;  // of the two installed layouts, else none
    const std::string packages = dir.parent_path().filename().string();
    if (dir.filename() == "bin") {
      prefix = dir.parent_path();
    } else if (dir.filename() == "lazyboe" &&
               (packages == "dist-packages" || packages == "site-packages")) {
      prefix = dir.parent_path().parent_path().parent_path().parent_path();
    }
    const std::filesystem::path data = prefix / "share" / "lazyboe";
    if (!prefix.empty() && std::filesystem::is_regular_file(data / "robots" / "panda.json", error))
      return data;
  }
  return "";
}

std::string find_data_dir() {
  if (std::string beside = installed_beside_binary(); !beside.empty()) return beside;
  std::error_code error;
  if (std::filesystem::is_directory(LAZYBOE_DATA_DIR, error)) return LAZYBOE_DATA_DIR;
  return LAZYBOE_INSTALLED_DATA_DIR;
}

}  // namespace

std::string data_dir() {
  if (const char* env = std::getenv("LAZYBOE_DATA_DIR"); env && *env) return env;
  static const std::string found = find_data_dir();
  return found;
}

std::string default_robot_path() { return data_dir() + "/robots/panda.json"; }

namespace {

// The chain: from base_link (default: the URDF root) to tip_link (default: follow the only
// child until the tree ends). `base_name` receives the base link's name.
std::vector<urdf::LinkConstSharedPtr> find_chain(const JsonField& root,
                                                 const urdf::ModelInterface& urdf_model,
                                                 const std::string& upath,
                                                 const std::string& config_path,
                                                 std::string& base_name) {
  base_name = root.has("base_link") ? root.at("base_link").string() : urdf_model.getRoot()->name;
  urdf::LinkConstSharedPtr base = urdf_model.getLink(base_name);
  if (!base) root.at("base_link").fail("no link '" + base_name + "' in " + upath);
  std::vector<urdf::LinkConstSharedPtr> chain;  // base ... tip
  if (root.has("tip_link")) {
    const std::string tip_name = root.at("tip_link").string();
    urdf::LinkConstSharedPtr link = urdf_model.getLink(tip_name);
    if (!link) root.at("tip_link").fail("no link '" + tip_name + "' in " + upath);
    // A chain longer than the URDF has links goes round a loop of joints (check_urdf_values
    // refuses them before urdfdom parses the file; this bound keeps the walk finite anyway).
    while (link && link != base) {
      if (chain.size() > urdf_model.links_.size()) fail(upath, urdf_loop_message(link->name));
      chain.push_back(link);
      link = link->getParent();
    }
    if (!link) root.at("tip_link").fail("'" + tip_name + "' is not below '" + base_name + "'");
    chain.push_back(base);
    std::reverse(chain.begin(), chain.end());
  } else {
    urdf::LinkConstSharedPtr link = base;
    chain.push_back(link);
    while (!link->child_links.empty()) {
      if (link->child_links.size() > 1) {
        fail(config_path,
             "the URDF branches at link '" + link->name + "'; set tip_link to choose the chain");
      }
      link = link->child_links[0];
      if (chain.size() > urdf_model.links_.size()) fail(upath, urdf_loop_message(link->name));
      chain.push_back(link);
    }
  }
  return chain;
}

// A moving joint of the chain; `origin` is its frame in the parent body.
Joint joint_from_urdf(const urdf::Joint& uj, const Pose& origin, const std::string& where) {
  Joint j;
  j.name = uj.name;
  j.type = uj.type == urdf::Joint::PRISMATIC ? JointType::Prismatic : JointType::Revolute;
  j.continuous = uj.type == urdf::Joint::CONTINUOUS;
  j.origin = origin;
  j.axis = Eigen::Vector3d(uj.axis.x, uj.axis.y, uj.axis.z);
  if (!(j.axis.norm() > 1e-9)) fail(where, "axis must not be zero");
  j.axis.normalize();
  j.axis_is_z = (j.axis - Eigen::Vector3d::UnitZ()).norm() < 1e-15;
  if (!uj.limits) {
    fail(where, j.continuous ? "missing <limit> (a continuous joint needs its velocity and effort)"
                             : "missing <limit>");
  }
  j.lower = j.continuous ? -kContinuousRange : uj.limits->lower;
  j.upper = j.continuous ? kContinuousRange : uj.limits->upper;
  j.max_velocity = uj.limits->velocity;
  j.max_effort = uj.limits->effort;
  if (!(std::isfinite(j.lower) && std::isfinite(j.upper) && j.lower < j.upper)) {
    fail(where, "position limits must satisfy lower < upper");
  }
  if (!(j.max_velocity > 0)) fail(where, "velocity limit must be > 0");
  if (!(j.max_effort > 0)) fail(where, "effort limit must be > 0");
  return j;
}

// Walks the chain: a moving joint starts a new body; fixed joints merge into the current one.
// Links hanging off the chain through fixed joints join their body too. Returns the URDF link
// of every model link.
std::vector<urdf::LinkConstSharedPtr> build_bodies(
    RobotModel& model, const std::vector<urdf::LinkConstSharedPtr>& chain,
    const std::string& upath) {
  std::set<std::string> on_chain;
  for (const auto& l : chain) on_chain.insert(l->name);
  int body = -1;
  std::vector<urdf::LinkConstSharedPtr> link_sources;
  std::function<void(const urdf::LinkConstSharedPtr&, const Pose&)> add_link =
      [&](const urdf::LinkConstSharedPtr& link, const Pose& in_body) {
        check_inertial(upath, *link);
        model.links.push_back({link->name, body, in_body});
        link_sources.push_back(link);
        if (body >= 0 && link->inertial) {
          const Pose inertial = in_body * pose_from_urdf(link->inertial->origin);
          Eigen::Matrix3d I;
          const urdf::Inertial& in = *link->inertial;
          I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
          merge_inertia(model.bodies[body], in.mass, inertial.p,
                        inertial.R * I * inertial.R.transpose());
        }
        for (const auto& child : link->child_links) {
          if (on_chain.count(child->name)) continue;
          const urdf::Joint& j = *child->parent_joint;
          if (j.type == urdf::Joint::FIXED) {
            add_link(child, in_body * pose_from_urdf(j.parent_to_joint_origin_transform));
          } else {
            model.ignored_links.push_back(child->name);
          }
        }
      };
  Pose in_body;  // current chain link in the current body frame
  for (size_t k = 0; k < chain.size(); ++k) {
    const urdf::LinkConstSharedPtr& link = chain[k];
    if (k > 0) {
      const urdf::Joint& uj = *link->parent_joint;
      const Pose origin = in_body * pose_from_urdf(uj.parent_to_joint_origin_transform);
      const std::string where = upath + ": joint '" + uj.name + "'";
      if (uj.type == urdf::Joint::FIXED) {
        in_body = origin;
      } else if (uj.type == urdf::Joint::REVOLUTE || uj.type == urdf::Joint::PRISMATIC ||
                 uj.type == urdf::Joint::CONTINUOUS) {
        if (model.dof >= kMaxDof) {
          fail(where, "chain has more than " + std::to_string(kMaxDof) + " moving joints");
        }
        model.joints.push_back(joint_from_urdf(uj, origin, where));
        model.bodies.emplace_back();
        body = model.dof++;
        in_body = Pose();
      } else {
        fail(where, "only revolute, continuous, prismatic and fixed joints are supported");
      }
    }
    add_link(link, in_body);
  }
  return link_sources;
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
  model.collision_margin = collision.at("margin").number_in(kCollisionMargin, " m");
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
    model.allowed_pairs.emplace_back(std::min(idx[0], idx[1]), std::max(idx[0], idx[1]));
  }
  std::sort(model.allowed_pairs.begin(), model.allowed_pairs.end());
  model.allowed_pairs.erase(std::unique(model.allowed_pairs.begin(), model.allowed_pairs.end()),
                            model.allowed_pairs.end());
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
  model.region_lower = model.q_min;
  model.region_upper = model.q_max;
  if (!root.has("sampling_region")) return;
  const JsonField region = root.at("sampling_region");
  region.allow_only({"description", "lower", "upper"});
  for (auto [key, bound] : {std::pair<const char*, JointVector*>{"lower", &model.region_lower},
                            std::pair<const char*, JointVector*>{"upper", &model.region_upper}}) {
    const std::vector<JsonField> v = region.at(key).items();
    if (static_cast<int>(v.size()) != n) {
      region.at(key).fail("expected " + std::to_string(n) + " values, one per moving joint");
    }
    for (int i = 0; i < n; ++i) (*bound)[i] = v[i].number_in(kRegionBound, " rad or m");
  }
  for (int i = 0; i < n; ++i) {
    if (!(model.region_lower[i] < model.region_upper[i])) {
      region.fail("joint " + std::to_string(i + 1) + ": lower must be below upper");
    }
    if (model.region_lower[i] < model.q_min[i] || model.region_upper[i] > model.q_max[i]) {
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

std::vector<Joint> chain_joints(const std::string& urdf_path, const std::string& base_link,
                                const std::string& tip_link) {
  const urdf::ModelInterfaceSharedPtr urdf_model = parse_urdf_file(urdf_path);
  nlohmann::json selection = nlohmann::json::object();
  if (!base_link.empty()) selection["base_link"] = base_link;
  if (!tip_link.empty()) selection["tip_link"] = tip_link;
  std::string base_name;
  RobotModel model;
  build_bodies(model,
               find_chain(JsonField(selection, "the chain", ""), *urdf_model, urdf_path, urdf_path,
                          base_name),
               urdf_path);
  if (model.dof == 0) fail(urdf_path, "the chain from '" + base_name + "' has no moving joint");
  return model.joints;
}

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
  model.config_path = config_path;
  model.name = root.at("name").string();
  const std::string urdf_rel = root.at("urdf").string();
  model.urdf_path = (fs::path(config_path).parent_path() / urdf_rel).lexically_normal().string();
  if (root.has("package_path")) {
    for (const JsonField& dir : root.at("package_path").items())
      model.package_path.push_back(
          (fs::path(config_path).parent_path() / dir.string()).lexically_normal().string());
  }
  if (root.has("gravity")) model.gravity = root.at("gravity").vec3_in(kGravity, " m/s^2");
  if (root.has("control_rate")) {
    const long rate = root.at("control_rate").integer();
    if (rate < 1 || rate > 1000000) root.at("control_rate").fail("must be in [1, 1000000] Hz");
    model.control_rate = static_cast<double>(rate);
  }

  const urdf::ModelInterfaceSharedPtr urdf_model = parse_urdf_file(model.urdf_path);
  const std::string& upath = model.urdf_path;
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
