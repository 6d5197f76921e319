#include "lazyboe/robot/urdf_parser.h"

#include <console_bridge/console.h>
#include <tinyxml.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/robot/urdf_check.h"
#include "lazyboe/robot/urdf_pose.h"

namespace lazyboe {
namespace {

// urdfdom reports parse problems through console_bridge; keep the last error for our message
// instead of letting it print to the terminal.
class CapturingOutputHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) last_error = text;
  }
  std::string last_error;
};

}  // namespace

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

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace lazyboe
