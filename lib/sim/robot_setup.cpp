#include "lazyboe/sim/robot_setup.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "lazyboe/collision/allowed_pairs.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/srdf.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

// `x` to `digits` significant digits: configs stay readable.
double rounded(double x, int digits = 4) {
  if (x == 0 || !std::isfinite(x)) return x;
  const double scale = std::pow(10.0, digits - 1 - std::floor(std::log10(std::abs(x))));
  return std::round(x * scale) / scale;
}

// `path` as the config at `out_path` names it: relative to the config's folder.
std::string relative_to_config(const std::string& path, const std::string& out_path) {
  const fs::path folder = fs::absolute(out_path).parent_path();
  return fs::absolute(path).lexically_normal().lexically_relative(folder).string();
}

json joint_entry(const Joint& j) {
  const double acceleration = rounded(kAccelerationPerVelocity * j.max_velocity);
  return {{"name", j.name},
          {"max_acceleration", acceleration},
          {"max_jerk", rounded(kJerkPerAcceleration * acceleration)},
          {"max_torque_rate", rounded(kTorqueRatePerEffort * j.max_effort)},
          {"friction", {{"model", "none"}}}};
}

json draft_config(const RobotSetupOptions& o, const std::string& base, const std::string& tip,
                  const std::vector<Joint>& joints) {
  char description[300];
  std::snprintf(description, sizeof description,
                "Written by lazyboe-robot init from %s. Limits the URDF lacks: max_acceleration = "
                "%g x velocity limit, max_jerk = %g x max_acceleration, max_torque_rate = %g x "
                "effort limit per s; friction none (not identified).",
                fs::path(o.urdf_path).filename().c_str(), kAccelerationPerVelocity,
                kJerkPerAcceleration, kTorqueRatePerEffort);
  json config = {{"schema_version", 1},
                 {"name", o.name.empty() ? fs::path(o.urdf_path).stem().string() : o.name},
                 {"description", description},
                 {"urdf", relative_to_config(o.urdf_path, o.out_path)}};
  if (!base.empty()) config["base_link"] = base;
  if (!tip.empty()) config["tip_link"] = tip;
  if (!o.package_path.empty()) {
    config["package_path"] = json::array();
    for (const std::string& dir : o.package_path)
      config["package_path"].push_back(relative_to_config(dir, o.out_path));
  }
  config["joints"] = json::array();
  for (const Joint& j : joints) config["joints"].push_back(joint_entry(j));
  json meshes = {{"representation", mesh_representation_name(o.meshes)}};
  for (const std::string& link : o.exact_links) meshes["links"][link] = "exact";
  for (const std::string& link : o.convex_links) meshes["links"][link] = "convex";
  config["collision"] = {
      {"margin", o.margin}, {"meshes", meshes}, {"allowed_pairs", json::array()}};
  return config;
}

// ka: the joint inertia M_ii at the configuration of typical inertia; kv: the velocity loop's time
// constant M_ii / kv at most `time_constant` at the largest sampled M_ii, and kv T / M_ii at most
// 0.3 at the smallest (the discrete loop's stability at the control period T).
json controller_gains(const RobotModel& robot, const RobotSetupOptions& o,
                      const JointVector& typical) {
  RobotData data(robot);
  const int n = robot.dof;
  JointVector lo = JointVector::Constant(n, INFINITY), hi = JointVector::Constant(n, 0);
  Random rng(o.seed, 0);
  JointVector q(n);
  for (long s = 0; s < o.inertia_samples; ++s) {
    for (int i = 0; i < n; ++i) q[i] = rng.uniform(robot.q_min[i], robot.q_max[i]);
    const JointVector diagonal = mass_matrix(robot, data, q).diagonal();
    lo = lo.cwiseMin(diagonal);
    hi = hi.cwiseMax(diagonal);
  }
  const JointVector ka = mass_matrix(robot, data, typical).diagonal();
  json kv = json::array(), ka_json = json::array();
  for (int i = 0; i < n; ++i) {
    kv.push_back(rounded(std::min(hi[i] / o.time_constant, 0.3 * lo[i] * robot.control_rate), 3));
    ka_json.push_back(rounded(ka[i], 3));
  }
  char text[400];
  std::snprintf(
      text, sizeof text,
      "Written by lazyboe-robot init: ka is M_ii at the configuration of typical inertia; kv "
      "= min(max M_ii / %g s, 0.3 min M_ii x control rate) over %ld configurations "
      "sampled in the joint limits (seed %llu).",
      o.time_constant, o.inertia_samples, static_cast<unsigned long long>(o.seed));
  return {{"type", "velocity_tracking"},
          {"description", text},
          {"kv", kv},
          {"ka", ka_json},
          {"friction_feedforward", true}};
}

// What was assumed or derived, one line each, for the report.
std::vector<std::string> setup_notes(const RobotModel& robot, const SrdfDescription& srdf) {
  std::vector<std::string> notes;
  notes.push_back("chain: " + robot.links.front().name + " -> " + robot.links.back().name + ", " +
                  std::to_string(robot.dof) + " moving joints" +
                  (srdf.group.empty() ? "" : " (SRDF group '" + srdf.group + "')"));
  char line[300];
  std::snprintf(line, sizeof line,
                "limits the URDF lacks: max_acceleration = %g x velocity limit, max_jerk = %g x "
                "max_acceleration, max_torque_rate = %g x effort limit (per s)",
                kAccelerationPerVelocity, kJerkPerAcceleration, kTorqueRatePerEffort);
  notes.push_back(line);
  notes.push_back("friction: none assumed (identify it and set joints[].friction)");
  for (const CollisionBody& b : robot.geometry.bodies) {
    if (b.mesh_file.empty() || b.representation != MeshRepresentation::Fitted) continue;
    std::snprintf(line, sizeof line, "link %s: mesh fitted with a %s, over-approximation %.1f mm",
                  robot.links[b.link].name.c_str(), shape_type_name(b.shape.type),
                  1000 * b.over_approximation);
    notes.push_back(line);
  }
  if (!srdf.poses.empty())
    notes.push_back("SRDF named poses not used (give them as query states): " +
                    std::to_string(srdf.poses.size()));
  return notes;
}

}  // namespace

JointVector typical_inertia_configuration(const RobotModel& robot, uint64_t seed, long samples) {
  RobotData data(robot);
  const int n = robot.dof;
  Random rng(seed, 1);
  std::vector<JointVector> qs, diagonals;
  JointVector q(n);
  for (long s = 0; s < std::max(1L, samples); ++s) {
    for (int i = 0; i < n; ++i) q[i] = rng.uniform(robot.region.lower[i], robot.region.upper[i]);
    qs.push_back(q);
    // M_ii > 0 for a model that loads (its mass matrix is checked positive definite); the
    // floor keeps the log finite all the same.
    diagonals.push_back(mass_matrix(robot, data, q).diagonal().array().max(1e-300).log().matrix());
  }
  JointVector median(n);
  std::vector<double> column(qs.size());
  for (int i = 0; i < n; ++i) {
    for (size_t s = 0; s < qs.size(); ++s) column[s] = diagonals[s][i];
    std::nth_element(column.begin(), column.begin() + column.size() / 2, column.end());
    median[i] = column[column.size() / 2];
  }
  size_t best = 0;
  for (size_t s = 1; s < qs.size(); ++s)
    if ((diagonals[s] - median).squaredNorm() < (diagonals[best] - median).squaredNorm()) best = s;
  return qs[best];
}

std::vector<StepCheck> check_velocity_steps(const RobotModel& robot, const JointVector& start) {
  CollisionModel collision = build_collision_model(robot, Environment{});
  collision.self_pairs.clear();  // the gains are checked, not the geometry
  const Simulator sim(robot, collision, SimulationOptions{});
  SimulatorWorkspace ws(sim);
  const int n = robot.dof;
  std::vector<StepCheck> steps;
  std::vector<double> knots(5 * n), ticks;
  for (int i = 0; i < n; ++i) {
    const double v = 0.3 * robot.dq_max[i];
    std::fill(knots.begin(), knots.end(), 0.0);
    for (int k = 1; k <= 3; ++k) knots[k * n + i] = v;
    const CommandProfile profile{knots.data(), 5, n, 1.0};
    TrajectorySamples samples;
    samples.ticks = &ticks;
    ticks.clear();
    StepCheck step;
    step.joint = robot.joints[i].name;
    step.status = simulate(sim, ws, start, profile, samples).status;
    for (size_t row = 0; row + 4 * n <= ticks.size(); row += 4 * n) {
      const double error = std::abs(ticks[row + n + i] - ticks[row + 3 * n + i]) / v;
      step.tracking_error = std::max(step.tracking_error, error);
    }
    steps.push_back(step);
  }
  return steps;
}

RobotSetup make_robot_config(const RobotSetupOptions& o) {
  std::string base = o.base_link, tip = o.tip_link;
  SrdfDescription srdf;
  if (!o.srdf_path.empty()) {
    srdf = read_srdf(o.srdf_path, o.srdf_group);
    if (base.empty()) base = srdf.base_link;
    if (tip.empty()) tip = srdf.tip_link;
  }
  RobotSetup setup;
  setup.config = draft_config(o, base, tip, chain_joints(o.urdf_path, base, tip));
  const RobotModel draft = robot_from_json(nlohmann::json::parse(setup.config.dump()), o.out_path);
  // Where the gains' feed-forward is taken and the steps start (the same inertia in the draft
  // and the final model: only the controller and the allowed pairs are added).
  const JointVector typical = typical_inertia_configuration(draft, o.seed, o.inertia_samples);
  setup.config["controller"] = controller_gains(draft, o, typical);
  std::set<std::pair<std::string, std::string>> pairs;
  int adjacent = 0, always = 0, from_srdf = 0;
  for (const LinkPairStats& p : derive_allowed_pairs(draft, o.pair_samples, o.seed).pairs) {
    if (p.reason.empty()) continue;
    pairs.insert({draft.links[p.link_a].name, draft.links[p.link_b].name});
    (p.reason == "adjacent" ? adjacent : always)++;
  }
  for (const SrdfPair& p : srdf.disabled) {
    const int a = draft.link_index(p.link1), b = draft.link_index(p.link2);
    if (a < 0 || b < 0 || a == b) continue;  // a link off the planned chain
    from_srdf +=
        pairs.insert({draft.links[std::min(a, b)].name, draft.links[std::max(a, b)].name}).second;
  }
  for (const auto& [a, b] : pairs) setup.config["collision"]["allowed_pairs"].push_back({a, b});
  const RobotModel robot = robot_from_json(nlohmann::json::parse(setup.config.dump()), o.out_path);
  setup.steps = check_velocity_steps(robot, typical);
  setup.notes = setup_notes(robot, srdf);
  char line[300];
  std::snprintf(line, sizeof line,
                "allowed pairs: %d adjacent, %d colliding in every one of %ld sampled "
                "configurations (seed %llu), %d more from the SRDF",
                adjacent, always, o.pair_samples, static_cast<unsigned long long>(o.seed),
                from_srdf);
  setup.notes.push_back(line);
  return setup;
}

}  // namespace lazyboe
