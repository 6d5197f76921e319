// lazyboe-robot: inspect a robot description: its joints and bodies, forward kinematics,
// inverse dynamics of logged states, collision checks, the allowed-collision pairs, and
// whether a joint trajectory is one the robot can execute.
#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "lazyboe/collision/allowed_pairs.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/io/csv.h"
#include "lazyboe/io/trajectory_csv.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/payload.h"
#include "lazyboe/robot/resource_path.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/sim/robot_setup.h"
#include "lazyboe/sim/trajectory_check.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;
using nlohmann::json;

JointVector parse_q(const std::string& text, const RobotModel& robot) {
  std::vector<double> values;
  size_t start = 0;
  while (start <= text.size()) {  // every comma separates two values, so "1,2," has an empty third
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string cell = text.substr(start, comma - start);
    start = comma + 1;
    values.push_back(parse_real_in(cell, {-1e3, 1e3}, "--q", " rad or m"));
  }
  if (static_cast<int>(values.size()) != robot.dof) {
    fail("--q", "expected " + std::to_string(robot.dof) + " comma-separated joint values, got " +
                    std::to_string(values.size()));
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), robot.dof);
}

json vec_json(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

json friction_json(const Friction& f) {
  switch (f.model) {
    case FrictionModel::None:
      return {{"model", "none"}};
    case FrictionModel::Sigmoid:
      return {{"model", "sigmoid"}, {"fi1", f.a}, {"fi2", f.b}, {"fi3", f.c}};
    case FrictionModel::ViscousCoulomb:
      return {{"model", "viscous_coulomb"},
              {"coulomb", f.a},
              {"viscous", f.b},
              {"smoothing_velocity", f.c}};
  }
  return {};
}

std::string shape_text(const Shape& s) {
  char buf[128];
  switch (s.type) {
    case ShapeType::Sphere:
      std::snprintf(buf, sizeof buf, "sphere r=%.4g", s.radius);
      break;
    case ShapeType::Capsule:
      std::snprintf(buf, sizeof buf, "capsule r=%.4g l=%.4g", s.radius, s.length);
      break;
    case ShapeType::Cylinder:
      std::snprintf(buf, sizeof buf, "cylinder r=%.4g l=%.4g", s.radius, s.length);
      break;
    case ShapeType::Box:
      std::snprintf(buf, sizeof buf, "box %.4gx%.4gx%.4g", s.size.x(), s.size.y(), s.size.z());
      break;
    case ShapeType::Mesh:
      std::snprintf(buf, sizeof buf, "%s of %zu triangles", s.convex ? "convex hull" : "mesh",
                    s.mesh->triangles.size());
      break;
  }
  return buf;
}

// The shape, and for a URDF mesh how it is represented: "capsule r=0.06 l=0.1 (fitted to
// meshes/x.stl, over-approximation 4.1 mm)" or "mesh of 980 triangles (exact: meshes/x.stl)".
std::string body_text(const CollisionBody& c) {
  std::string text = shape_text(c.shape);
  if (c.mesh_file.empty()) return text;
  if (c.representation != MeshRepresentation::Fitted)
    return text + " (" + mesh_representation_name(c.representation) + ": " + c.mesh_file + ")";
  char buf[64];
  std::snprintf(buf, sizeof buf, ", over-approximation %.1f mm)", 1000 * c.over_approximation);
  return text + " (fitted to " + c.mesh_file + buf;
}

json body_json(const RobotModel& robot, const CollisionBody& c) {
  json j = {{"name", c.name}, {"link", robot.links[c.link].name}, {"shape", shape_text(c.shape)}};
  if (c.mesh_file.empty()) return j;
  j["mesh_file"] = c.mesh_file;
  j["representation"] = mesh_representation_name(c.representation);
  if (c.representation == MeshRepresentation::Fitted)
    j["over_approximation_mm"] = 1000 * c.over_approximation;
  return j;
}

// `info --json`: the model as the tools read it.
json info_json(const RobotModel& robot, const CollisionModel& cm) {
  json j;
  j["name"] = robot.name;
  j["config"] = robot.files.config;
  j["urdf"] = robot.files.urdf;
  j["dof"] = robot.dof;
  j["gravity"] = vec_json(robot.gravity);
  j["control_rate"] = robot.control_rate;
  j["tip_link"] = robot.links[robot.tip_link()].name;
  j["sampling_region"] = {{"lower", vec_json(robot.region.lower)},
                          {"upper", vec_json(robot.region.upper)}};
  for (const Joint& jt : robot.joints) {
    j["joints"].push_back({{"name", jt.name},
                           {"type", joint_type_name(jt)},
                           {"lower", jt.lower},
                           {"upper", jt.upper},
                           {"max_velocity", jt.max_velocity},
                           {"max_acceleration", jt.max_acceleration},
                           {"max_jerk", jt.max_jerk},
                           {"max_effort", jt.max_effort},
                           {"max_torque_rate", jt.max_torque_rate},
                           {"friction", friction_json(jt.friction)}});
  }
  for (size_t b = 0; b < robot.bodies.size(); ++b) {
    j["bodies"].push_back({{"joint", robot.joints[b].name},
                           {"mass", robot.bodies[b].mass},
                           {"com", vec_json(robot.bodies[b].com)}});
  }
  for (const Link& l : robot.links) {
    j["links"].push_back(
        {{"name", l.name}, {"moved_by", l.body < 0 ? "base" : robot.joints[l.body].name}});
  }
  for (const CollisionBody& c : robot.geometry.bodies) {
    j["collision_bodies"].push_back(body_json(robot, c));
  }
  j["collision_margin"] = robot.geometry.margin;
  for (const auto& [a, b] : robot.geometry.allowed_pairs) {
    j["allowed_pairs"].push_back({robot.links[a].name, robot.links[b].name});
  }
  j["self_pairs_tested"] = cm.self_pairs.size();
  j["ignored_links"] = robot.ignored_links;
  j["controller"] = {{"kv", vec_json(robot.controller.kv)},
                     {"ka", vec_json(robot.controller.ka)},
                     {"friction_feedforward", robot.controller.friction_feedforward}};
  return j;
}

// The controller's gains and the sampling region, as the simulator and the builder use them.
void print_controller_and_region(const RobotModel& robot) {
  std::printf("\ntip link %s; controller gains per joint (kv N m s/rad, ka kg m^2)%s:\n",
              robot.links[robot.tip_link()].name.c_str(),
              robot.controller.friction_feedforward ? ", friction feed-forward" : "");
  for (int i = 0; i < robot.dof && robot.controller.present; ++i)
    std::printf("  %-20s kv %9.4g  ka %9.4g  region [%.4g, %.4g]\n", robot.joints[i].name.c_str(),
                robot.controller.kv[i], robot.controller.ka[i], robot.region.lower[i],
                robot.region.upper[i]);
}

int cmd_info(const RobotModel& robot, bool as_json) {
  const CollisionModel cm = build_collision_model(robot, Environment{});
  if (as_json) {
    std::cout << info_json(robot, cm).dump(2) << "\n";
    return 0;
  }
  std::printf("robot %s\n  config %s\n  urdf   %s\n", robot.name.c_str(),
              robot.files.config.c_str(), robot.files.urdf.c_str());
  std::printf("%d moving joints, gravity (%g, %g, %g) m/s^2, control rate %g Hz\n\n", robot.dof,
              robot.gravity.x(), robot.gravity.y(), robot.gravity.z(), robot.control_rate);
  std::printf("%-14s %-9s %9s %9s %8s %8s %8s %7s %8s  %s\n", "joint", "type", "lower", "upper",
              "vel", "acc", "jerk", "effort", "d_effort", "friction");
  for (const Joint& j : robot.joints) {
    std::printf("%-14s %-9s %9.4f %9.4f %8.4g %8.4g %8.4g %7.4g %8.4g  %s\n", j.name.c_str(),
                joint_type_name(j), j.lower, j.upper, j.max_velocity, j.max_acceleration,
                j.max_jerk, j.max_effort, j.max_torque_rate,
                friction_json(j.friction).dump().c_str());
  }
  std::printf("\n%-14s %-14s %9s\n", "link", "moved by", "mass(kg)");
  for (const Link& l : robot.links) {
    const bool owner = l.body >= 0 && robot.links[robot.link_index(l.name)].in_body.p.isZero() &&
                       robot.links[robot.link_index(l.name)].in_body.R.isIdentity();
    std::printf("%-14s %-14s", l.name.c_str(),
                l.body < 0 ? "base" : robot.joints[l.body].name.c_str());
    if (owner) std::printf(" %9.4f", robot.bodies[l.body].mass);
    std::printf("\n");
  }
  if (!robot.ignored_links.empty()) {
    std::printf("ignored (behind moving side joints):");
    for (const std::string& n : robot.ignored_links) std::printf(" %s", n.c_str());
    std::printf("\n");
  }
  std::printf("\ncollision bodies (margin %g m):\n", robot.geometry.margin);
  for (const CollisionBody& c : robot.geometry.bodies) {
    std::printf("  %-16s %-14s %s\n", c.name.c_str(), robot.links[c.link].name.c_str(),
                body_text(c).c_str());
  }
  std::printf("allowed-collision link pairs: %zu; body pairs tested for self-collision: %zu\n",
              robot.geometry.allowed_pairs.size(), cm.self_pairs.size());
  print_controller_and_region(robot);
  return 0;
}

int cmd_fk(const RobotModel& robot, const std::string& q_text, const std::string& link_name) {
  const JointVector q = parse_q(q_text, robot);
  const int link = link_name.empty() ? robot.tip_link() : robot.link_index(link_name);
  if (link < 0) fail("--link", robot.unknown_link(link_name));
  RobotData data(robot);
  forward_kinematics(robot, data, q);
  const Pose pose = link_pose(robot, data, link);
  json out;
  out["link"] = robot.links[link].name;
  out["position"] = vec_json(pose.p);
  out["quaternion"] = vec_json(pose.quaternion_wxyz());
  std::cout << out.dump() << "\n";
  return 0;
}

// SIGINT/SIGTERM stop `check` and `torques` before anything is written; the output's temporary
// file, if any, is removed on the way out. The handlers are installed before the inputs are read,
// so a signal during the reading (long for a big CSV) is reported the same way.
int interrupted(const std::string& out) {
  std::fprintf(stderr, "lazyboe-robot: interrupted; %s not written\n", out.c_str());
  return 130;
}

int cmd_torques(const RobotModel& robot, const std::string& in, const std::string& out) {
  const int n = robot.dof;
  std::vector<std::string> header = numbered_columns("q", n);
  for (const char* p : {"dq", "ddq"}) {
    for (const std::string& c : numbered_columns(p, n)) header.push_back(c);
  }
  install_stop_handlers();
  const CsvTable table = read_numeric_csv(in, header, {-1e6, 1e6});  // rad, rad/s, rad/s^2
  RobotData data(robot);
  CsvWriter writer(out, numbered_columns("tau", n));
  std::vector<double> row(n);
  for (const std::vector<double>& r : table.rows) {
    Eigen::Map<const Eigen::VectorXd> all(r.data(), 3 * n);
    const JointVector& tau =
        inverse_dynamics(robot, data, all.segment(0, n), all.segment(n, n), all.segment(2 * n, n));
    for (int i = 0; i < n; ++i) row[i] = tau[i];
    writer.row(row);
    if (stop_requested()) return interrupted(out);
  }
  writer.commit();
  std::fprintf(stderr, "lazyboe-robot: wrote %zu rows to %s\n", table.rows.size(), out.c_str());
  return 0;
}

// One configuration's row of `check`: in_limits, self_collision, env_collision, min_distance.
std::array<double, 4> check_row(const RobotModel& robot, const CollisionModel& cm, RobotData& rd,
                                CollisionData& cd, const std::vector<double>& r) {
  Eigen::Map<const Eigen::VectorXd> q(r.data(), robot.dof);
  const bool in_limits =
      (q.array() >= robot.q_min.array()).all() && (q.array() <= robot.q_max.array()).all();
  forward_kinematics(robot, rd, q);
  update_collision_transforms(cm, cd, rd);
  const CollisionReport report = check_collision(cm, cd);
  const DistanceReport dist = min_distance(cm, cd);
  return {double(in_limits), double(report.self_collision), double(report.env_collision),
          std::isfinite(dist.min()) ? dist.min() : -1.0};
}

int cmd_check(const RobotModel& robot, const std::string& env_path, const std::string& in,
              const std::string& out) {
  install_stop_handlers();
  const Environment env = load_environment(env_path);
  const CollisionModel cm = build_collision_model(robot, env);
  const CsvTable table = read_numeric_csv(in, numbered_columns("q", robot.dof), {-1e3, 1e3});
  // Rows are independent: all cores, each thread with its own workspaces (the models are
  // read-only and shared).
  const long n = static_cast<long>(table.rows.size());
  std::vector<std::array<double, 4>> rows(table.rows.size());
#pragma omp parallel
  {
    RobotData rd(robot);
    CollisionData cd(cm);
#pragma omp for schedule(dynamic, 256)
    for (long k = 0; k < n; ++k) {
      if (!stop_requested()) rows[k] = check_row(robot, cm, rd, cd, table.rows[k]);
    }
  }
  if (stop_requested()) return interrupted(out);
  CsvWriter writer(out, {"in_limits", "self_collision", "env_collision", "min_distance"});
  long colliding = 0;
  for (const std::array<double, 4>& r : rows) {
    colliding += r[1] != 0 || r[2] != 0;
    writer.row({r[0], r[1], r[2], r[3]});
  }
  if (stop_requested()) return interrupted(out);
  writer.commit();
  std::fprintf(stderr, "lazyboe-robot: %zu configurations, %ld in collision, written to %s\n",
               table.rows.size(), colliding, out.c_str());
  return 0;
}

int cmd_allowed_pairs(const RobotModel& robot, long samples, uint64_t seed) {
  if (samples <= 0) fail("--samples", "must be > 0");
  const AllowedPairsResult result = derive_allowed_pairs(robot, samples, seed);
  json pairs = json::array();
  std::fprintf(stderr, "%-14s %-14s %10s  %s\n", "link", "link", "collided", "allowed because");
  for (const LinkPairStats& p : result.pairs) {
    std::fprintf(stderr, "%-14s %-14s %9.2f%%  %s\n", robot.links[p.link_a].name.c_str(),
                 robot.links[p.link_b].name.c_str(), 100.0 * p.collisions / samples,
                 p.reason.empty() ? "-" : p.reason.c_str());
    if (!p.reason.empty())
      pairs.push_back({robot.links[p.link_a].name, robot.links[p.link_b].name});
  }
  std::cout << json{{"allowed_pairs", pairs}}.dump() << "\n";
  return 0;
}

constexpr int kInvalidTrajectory = 3;  // exit status: checked, and a limit is violated

// "valid: N samples, D s; peak fraction of limit: position 0.71 (joint 4), ...".
std::string check_summary(const TrajectoryCheckResult& r) {
  static const char* names[kJointLimitCount] = {"position", "velocity", "acceleration",
                                                "jerk",     "torque",   "torque rate"};
  char text[512];
  int used = std::snprintf(text, sizeof text,
                           "%d samples, %.3f s; peak fraction of limit:", r.samples, r.duration);
  for (int l = 0; l < kJointLimitCount && used < static_cast<int>(sizeof text); ++l) {
    used += std::snprintf(text + used, sizeof text - used, "%s %s %.3f (joint %d)", l ? "," : "",
                          names[l], r.peak_fraction[l], r.peak_joint[l] + 1);
  }
  if (used < static_cast<int>(sizeof text)) {
    std::snprintf(text + used, sizeof text - used, "; %d collision checks", r.collision_checks);
  }
  return text;
}

// A task given on the command line as JSON text (--payload, --end-effector-limits), read as a
// query's field is; `start` sets the default tilt axis.
JsonField task_field(const std::string& text, const std::string& option, nlohmann::json& doc) {
  doc = parse_json_text(text, option, false);
  return JsonField(doc, option, "");
}

int cmd_validate_trajectory(const RobotModel& bundle_robot, const std::string& env_path,
                            const std::string& in, const std::string& payload_text,
                            const std::string& limits_text) {
  nlohmann::json doc;
  const Payload payload =
      payload_text.empty()
          ? Payload{}
          : payload_from_json(task_field(payload_text, "--payload", doc), bundle_robot);
  const RobotModel robot = with_payload(bundle_robot, payload);
  // A trajectory checked against another scene than its own says nothing: no default.
  if (env_path.empty())
    fail("--env",
         "name the scene the trajectory was planned in (an environment file, or a "
         "bundled scene: table, shelf, empty)");
  const Environment env = load_environment(env_path);
  const CollisionModel cm = build_collision_model(robot, env);
  const TrajectoryCsv traj = read_trajectory_csv(in, robot.dof);
  if (traj.t.size() < 2) fail(in + ":" + std::to_string(traj.line[0]), "only one sample");
  TrajectoryCheckOptions options;
  if (!limits_text.empty()) {
    RobotData data(robot);
    options.end_effector = end_effector_limits_from_json(
        task_field(limits_text, "--end-effector-limits", doc), robot,
        Eigen::Map<const Eigen::VectorXd>(traj.q.data(), robot.dof), data);
  }
  const TrajectoryChecker checker(robot, cm, options);
  const int bad = first_bad_spacing(checker, traj.view());
  if (bad >= 0) {
    char what[256];
    std::snprintf(what, sizeof what,
                  "t: %.10g s after the previous sample, not the control period %g s (the "
                  "check needs every control tick: lazyboe-query --sample-interval %g)",
                  traj.t[bad] - traj.t[bad - 1], checker.dt, checker.dt);
    fail(in + ":" + std::to_string(traj.line[bad]), what);
  }
  TrajectoryCheckWorkspace ws(checker);
  const TrajectoryCheckResult r = check_trajectory(checker, ws, traj.view());
  if (r.valid) {
    std::printf("valid: %s; scene %s\n", check_summary(r).c_str(), env.name.c_str());
    return 0;
  }
  std::printf("invalid: %s (%s line %d; scene %s)\n",
              describe_violation(checker, r.violation).c_str(), in.c_str(),
              traj.line[r.violation.sample], env.name.c_str());
  return kInvalidTrajectory;
}

}  // namespace

// Writes the config `init` makes, then says what it assumed and how the gains tracked.
int cmd_init(RobotSetupOptions options, const std::string& package_path,
             const std::string& meshes) {
  options.meshes = parse_mesh_representation(meshes, "--meshes");
  options.package_path = split_path_list(package_path);
  refuse_output_as_input({"--out", options.out_path},
                         {{"--urdf", options.urdf_path}, {"--srdf", options.srdf_path}});
  const RobotSetup setup = make_robot_config(options);
  AtomicFile file(options.out_path);
  file.stream() << setup.config.dump(2) << "\n";
  file.commit();
  std::fprintf(stderr, "lazyboe-robot init: wrote %s\n", options.out_path.c_str());
  for (const std::string& note : setup.notes) std::fprintf(stderr, "  %s\n", note.c_str());
  int failed = 0;
  for (const StepCheck& s : setup.steps) {
    std::fprintf(stderr, "  velocity step on %-20s %-18s tracking error %4.0f%% of the step%s\n",
                 s.joint.c_str(), rollout_status_name(s.status), 100 * s.tracking_error,
                 s.passed() ? "" : "  <- check this joint's gains and limits");
    failed += !s.passed();
  }
  if (failed) {
    std::fprintf(stderr,
                 "  %d joint(s) did not track a step within %.0f%%: edit controller.kv/ka or the "
                 "limits in %s (docs/robot-description.md)\n",
                 failed, 100 * kStepTrackingTolerance, options.out_path.c_str());
  }
  std::fprintf(stderr, "  next: lazyboe-robot info --robot %s\n", options.out_path.c_str());
  return 0;
}

// `init`'s options, into `setup`, `package_path` and `meshes`.
CLI::App* add_init_command(CLI::App& app, RobotSetupOptions& setup, std::string& package_path,
                           std::string& meshes) {
  auto* init = app.add_subcommand("init", "Write a robot config from a URDF (and an SRDF)");
  init->add_option("--urdf", setup.urdf_path, "The robot's URDF")->required();
  init->add_option("--srdf", setup.srdf_path, "MoveIt SRDF: a group's chain, disabled pairs");
  init->add_option("--group", setup.srdf_group, "SRDF group (default: the first with a chain)");
  init->add_option("--package-path", package_path, "Folders DIR[:DIR] of package:// meshes");
  init->add_option("--base-link", setup.base_link, "Root of the planned chain");
  init->add_option("--tip-link", setup.tip_link, "End of the planned chain (the tool flange)");
  init->add_option("--name", setup.name, "Robot name (default: the URDF's file name)");
  init->add_option("--meshes", meshes,
                   "Mesh links: fitted (capsules), exact (the meshes) or convex (their hulls)")
      ->capture_default_str();
  init->add_option("--exact-links", setup.exact_links,
                   "Mesh links kept exact (comma-separated), whatever --meshes says")
      ->delimiter(',');
  init->add_option("--convex-links", setup.convex_links,
                   "Mesh links checked as their convex hulls (comma-separated), whatever --meshes "
                   "says")
      ->delimiter(',');
  init->add_option("--margin", setup.margin, "Collision margin, m")->capture_default_str();
  init->add_option("--samples", setup.pair_samples, "Configurations sampled for allowed pairs")
      ->capture_default_str()
      ->check(lazyboe::whole_number(false));
  init->add_option("--seed", setup.seed, "Random seed")->capture_default_str();
  init->add_option("--out", setup.out_path, "Robot config (JSON) to write")->required();
  return init;
}

// `validate-trajectory`'s options.
CLI::App* add_validate_command(CLI::App& app, std::string& in_path, std::string& env,
                               std::string& payload_text, std::string& limits_text) {
  auto* validate = app.add_subcommand(
      "validate-trajectory",
      "Check a trajectory CSV at the control rate against the limits and for collision");
  validate->add_option("--in", in_path, "CSV with header t,q1..qn,dq1..dqn[,more columns]")
      ->required();
  validate->add_option("--env", env,
                       "The scene the trajectory was planned in: an environment file, or a "
                       "bundled scene by name (table, shelf, empty); required");
  validate->add_option("--payload", payload_text,
                       "The payload the arm carries, as a query's \"payload\" (JSON text)");
  validate->add_option("--end-effector-limits", limits_text,
                       "End-effector limits, as a query's \"end_effector_limits\" (JSON text)");
  return validate;
}

int main(int argc, char** argv) {
  CLI::App app{"Inspect a robot description: joints, kinematics, dynamics, collision."};
  app.require_subcommand(1);
  // Tool-wide options (--robot) are accepted after the subcommand too, as users type them.
  app.fallthrough();
  std::string robot_path = lazyboe::default_robot_path();
  app.add_option("--robot", robot_path, "Robot config (JSON) naming its URDF")
      ->capture_default_str();

  auto* info = app.add_subcommand("info", "Joints, limits, links and collision bodies");
  bool info_json = false;
  info->add_flag("--json", info_json, "Print as JSON");

  auto* fk = app.add_subcommand("fk", "Pose of a link in the base frame, as JSON");
  std::string q_text, link_name;
  fk->add_option("--q", q_text, "Joint positions q1,...,qn")->required();
  fk->add_option("--link", link_name, "Link name (default: the tip link, the end of the chain)");

  auto* torques = app.add_subcommand("torques", "Inverse dynamics with friction for logged states");
  std::string in_path, out_path;
  torques->add_option("--in", in_path, "CSV with header q1..qn,dq1..dqn,ddq1..ddqn")->required();
  torques->add_option("--out", out_path, "CSV written with header tau1..taun")->required();

  auto* check = app.add_subcommand("check", "Limits and collision of configurations");
  std::string env_path = lazyboe::default_environment_path();
  check->add_option("--env", env_path, "Environment (JSON)")->capture_default_str();
  check->add_option("--in", in_path, "CSV with header q1..qn")->required();
  check
      ->add_option("--out", out_path,
                   "CSV written with in_limits,self_collision,env_collision,min_distance")
      ->required();

  auto* pairs =
      app.add_subcommand("allowed-pairs", "Derive the allowed-collision link pairs by sampling");
  long samples = 100000;
  uint64_t seed = 1;
  pairs->add_option("--samples", samples, "Random configurations to test")
      ->capture_default_str()
      ->check(lazyboe::whole_number(false));
  pairs->add_option("--seed", seed, "Random seed")
      ->capture_default_str()
      ->check(lazyboe::whole_number(true));

  std::string validate_env, payload_text, limits_text;
  CLI::App* validate = add_validate_command(app, in_path, validate_env, payload_text, limits_text);

  lazyboe::RobotSetupOptions setup;
  std::string package_path, meshes = "fitted";
  CLI::App* init = add_init_command(app, setup, package_path, meshes);

  lazyboe::one_line_cli_errors(app, "lazyboe-robot");
  CLI11_PARSE(app, argc, argv);
  return lazyboe::run_tool("lazyboe-robot", [&]() {
    if (*init) return cmd_init(setup, package_path, meshes);
    const lazyboe::RobotModel robot = lazyboe::load_robot(robot_path);
    if (*torques || *check) {
      lazyboe::refuse_output_as_input({"--out", out_path},
                                      {{"--in", in_path},
                                       {"--robot", robot_path},
                                       {"URDF", robot.files.urdf},
                                       {"--env", *check ? env_path : std::string()}});
    }
    if (*info) return cmd_info(robot, info_json);
    if (*fk) return cmd_fk(robot, q_text, link_name);
    if (*torques) return cmd_torques(robot, in_path, out_path);
    if (*check) return cmd_check(robot, env_path, in_path, out_path);
    if (*validate)
      return cmd_validate_trajectory(robot, validate_env, in_path, payload_text, limits_text);
    return cmd_allowed_pairs(robot, samples, seed);
  });
}
