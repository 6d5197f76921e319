#include "lazyboe/io/query_io.h"

#include <cmath>

#include "lazyboe/common/error.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/io/csv.h"
#include "lazyboe/planning/ompl_planners.h"

namespace lazyboe {
namespace {

JointVector joint_vector(const JsonField& f, int dof) {
  const std::vector<double> v = f.numbers();
  if (static_cast<int>(v.size()) != dof)
    f.fail("expected " + std::to_string(dof) + " joint values");
  return Eigen::Map<const Eigen::VectorXd>(v.data(), dof);
}

void check_state_usable(const JsonField& f, const JointVector& q, const Simulator& sim,
                        SimulatorWorkspace& ws) {
  const RolloutStatus s = check_state(sim, ws, q);
  if (s == RolloutStatus::PositionLimit) f.fail("outside the joint limits");
  if (s == RolloutStatus::SelfCollision) f.fail("in self-collision");
  if (s == RolloutStatus::EnvCollision) f.fail("in collision with the environment");
}

}  // namespace

Query parse_query(const std::string& text, int line, const RobotModel& robot, const Simulator& sim,
                  SimulatorWorkspace& ws, const QueryDefaults& d, std::string& id_out) {
  const std::string where = "line " + std::to_string(line);
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error&) {
    fail(where, "not valid JSON");
  }
  if (!doc.is_object()) fail(where, "expected a JSON object");
  if (doc.contains("id") && doc["id"].is_string()) id_out = doc["id"].get<std::string>();
  const JsonField root(doc, where, "");
  root.allow_only({"id", "start", "goal", "planner", "budget", "seed", "theta", "stop_at_first",
                   "goal_bias", "selection_radius", "pruning_ratio"});
  Query q;
  q.line = line;
  q.id = root.at("id").string();
  PlannerParams& p = q.problem.params;
  p = d.params;
  p.planner = root.has("planner") ? root.at("planner").string() : "lazyboe";
  if (p.planner != "lazyboe" && p.planner != "boe" && p.planner != "rrt" && p.planner != "sst" &&
      !is_ompl_planner(p.planner)) {
    root.at("planner").fail(
        "unknown planner '" + p.planner +
        "' (expected lazyboe, boe, rrt, sst, ompl-rrt, ompl-sst or ompl-kpiece)");
  }
  p.budget = root.has("budget") ? root.at("budget").positive() : d.budget;
  p.seed = root.has("seed") ? static_cast<uint64_t>(root.at("seed").integer()) : 1;
  if (root.has("seed") && root.at("seed").integer() < 0) root.at("seed").fail("must be >= 0");
  p.theta = root.has("theta") ? root.at("theta").positive() : d.theta;
  if (root.has("stop_at_first")) p.stop_at_first = root.at("stop_at_first").boolean();
  if (root.has("goal_bias")) {
    p.goal_bias = root.at("goal_bias").number_at_least(0);
    if (p.goal_bias > 1) root.at("goal_bias").fail("must be in [0, 1]");
  }
  if (root.has("selection_radius")) p.selection_radius = root.at("selection_radius").positive();
  if (root.has("pruning_ratio")) p.pruning_ratio = root.at("pruning_ratio").positive();

  q.problem.start = joint_vector(root.at("start"), robot.dof);
  check_state_usable(root.at("start"), q.problem.start, sim, ws);

  const JsonField goal = root.at("goal");
  Goal& g = q.problem.goal;
  if (goal.has("q")) {
    goal.allow_only({"q", "tolerance"});
    g.kind = Goal::Kind::Joint;
    g.q = joint_vector(goal.at("q"), robot.dof);
    g.tolerance = goal.has("tolerance") ? goal.at("tolerance").positive() : d.joint_tolerance;
    check_state_usable(goal.at("q"), g.q, sim, ws);
  } else if (goal.has("position")) {
    goal.allow_only({"position", "tolerance", "link"});
    g.kind = Goal::Kind::Position;
    g.position = goal.at("position").vec3();
    g.tolerance = goal.has("tolerance") ? goal.at("tolerance").positive() : d.position_tolerance;
    const std::string link =
        goal.has("link") ? goal.at("link").string() : robot.links[robot.tip_link()].name;
    g.link = robot.link_index(link);
    if (g.link < 0) goal.at("link").fail("unknown link '" + link + "'");
    // Reach bound: the sum of joint offsets from the first joint on.
    double reach = 0;
    for (const Joint& j : robot.joints) reach += j.origin.p.norm();
    reach += robot.links[g.link].in_body.p.norm();
    const Eigen::Vector3d shoulder = robot.joints[0].origin.p;
    if ((g.position - shoulder).norm() > reach + g.tolerance) {
      goal.at("position").fail("unreachable: farther than the arm can reach");
    }
  } else {
    goal.fail("expected \"q\" (joint goal) or \"position\" (end-effector goal)");
  }
  RobotData data(robot);
  if (g.contains(robot, data, q.problem.start)) goal.fail("the start already satisfies the goal");
  return q;
}

nlohmann::json result_json(const Query& q, const PlanResult& r, const Trajectory* traj,
                           TrajectoryOutput mode, const std::string& csv_path) {
  nlohmann::json j;
  j["id"] = q.id;
  j["line"] = q.line;
  j["planner"] = q.problem.params.planner;
  j["success"] = r.success;
  j["time_to_first_solution"] =
      r.success ? nlohmann::json(r.time_to_first_solution) : nlohmann::json(nullptr);
  j["n_solutions"] = r.n_solutions;
  j["best_cost"] =
      r.success ? nlohmann::json(traj ? traj->cost : r.best_cost) : nlohmann::json(nullptr);
  j["counters"] = {{"nodes", r.counters.nodes},
                   {"simulations", r.counters.simulations},
                   {"lazy_edges", r.counters.lazy_edges},
                   {"collision_checks", r.counters.collision_checks}};
  if (!r.success) j["failure"] = r.failure;
  if (traj) {
    j["duration"] = traj->duration;
    j["edges"] = traj->edges;
    if (mode == TrajectoryOutput::Inline) {
      nlohmann::json t;
      t["t"] = traj->t;
      for (size_t k = 0; k < traj->q.size(); ++k) {
        t["q"].push_back(
            std::vector<double>(traj->q[k].data(), traj->q[k].data() + traj->q[k].size()));
        t["dq"].push_back(
            std::vector<double>(traj->dq[k].data(), traj->dq[k].data() + traj->dq[k].size()));
      }
      j["trajectory"] = t;
    } else if (mode == TrajectoryOutput::Csv) {
      j["trajectory_file"] = csv_path;
    }
  }
  return j;
}

nlohmann::json error_json(const std::string& id, int line, const std::string& planner,
                          const std::string& error) {
  nlohmann::json j;
  j["id"] = id.empty() ? nlohmann::json(nullptr) : nlohmann::json(id);
  j["line"] = line;
  j["planner"] = planner.empty() ? nlohmann::json(nullptr) : nlohmann::json(planner);
  j["success"] = false;
  j["time_to_first_solution"] = nullptr;
  j["n_solutions"] = 0;
  j["best_cost"] = nullptr;
  j["error"] = error;
  return j;
}

void write_trajectory_csv(const std::string& path, const Trajectory& traj) {
  const int n = traj.q.empty() ? 0 : static_cast<int>(traj.q[0].size());
  std::vector<std::string> header = {"t"};
  for (const std::string& c : numbered_columns("q", n)) header.push_back(c);
  for (const std::string& c : numbered_columns("dq", n)) header.push_back(c);
  CsvWriter w(path, header);
  std::vector<double> row(1 + 2 * n);
  for (size_t k = 0; k < traj.t.size(); ++k) {
    row[0] = traj.t[k];
    for (int i = 0; i < n; ++i) {
      row[1 + i] = traj.q[k][i];
      row[1 + n + i] = traj.dq[k][i];
    }
    w.row(row);
  }
  w.commit();
}

}  // namespace lazyboe
