#include "lazyboe/io/query_io.h"

#include <cmath>

#include "lazyboe/common/error.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/common/text.h"
#include "lazyboe/io/csv.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe {
namespace {

JointVector joint_vector(const JsonField& f, int dof) {
  const std::vector<double> v = f.numbers();
  if (static_cast<int>(v.size()) != dof)
    f.fail("expected " + std::to_string(dof) + " joint values");
  return Eigen::Map<const Eigen::VectorXd>(v.data(), dof);
}

double parameter_value(const JsonField& f, const ParameterSpec& spec) {
  switch (spec.type) {
    case ParameterType::Boolean:
      return f.boolean() ? 1.0 : 0.0;
    case ParameterType::Integer:
      return static_cast<double>(f.integer());
    case ParameterType::Choice: {
      const int k = spec.choice_index(f.string());
      if (k < 0) f.fail("expected " + spec.range_text());
      return k;
    }
    default:
      return f.number();
  }
}

// "theta, stop_at_first and lazy_model", or "none".
std::string parameter_names_text(const PlannerInfo& info) {
  std::vector<std::string> names;
  for (const ParameterSpec& p : info.parameters) names.push_back(p.name);
  return names.empty() ? std::string("none") : list_text(names, " and ");
}

// The planner and the values of its declared parameters. Another planner's parameter is
// refused: it would be silently ignored.
void parse_planner(const JsonField& root, PlanRequest& r) {
  r.planner = root.has("planner") ? root.at("planner").string() : "lazyboe";
  const PlannerInfo* found = find_planner(r.planner);
  if (!found) {
    root.at("planner").fail("unknown planner '" + r.planner + "' (expected " +
                            planner_names_text() + ")" + did_you_mean(r.planner, planner_names()));
  }
  const PlannerInfo& info = *found;
  for (const std::string& name : all_parameter_names()) {
    if (!root.has(name)) continue;
    const JsonField f = root.at(name);
    const ParameterSpec* spec = info.parameter(name);
    if (!spec) {
      f.fail("not a parameter of " + r.planner + " (its parameters: " + parameter_names_text(info) +
             ")");
    }
    const double v = parameter_value(f, *spec);
    const std::string why = spec->check(v);
    if (!why.empty()) f.fail(why);
    r.parameters.set(name, v);
  }
}

void parse_position_goal(const JsonField& goal, const RobotModel& robot, const QueryDefaults& d,
                         Goal& g) {
  goal.allow_only({"position", "tolerance", "link"});
  g.kind = Goal::Kind::Position;
  g.position = goal.at("position").vec3_in({-100, 100}, " m");
  g.tolerance = goal.has("tolerance") ? goal.at("tolerance").number_in({0, 100, true}, " m")
                                      : d.position_tolerance;
  g.link = link_field(goal, robot);
}

Eigen::Vector3d unit_vector(const JsonField& f) {
  const Eigen::Vector3d v = f.vec3_in({-1e3, 1e3});
  if (!(v.norm() > 1e-9)) f.fail("must not be zero");
  return v.normalized();
}

// {"pose": {"position", "orientation": [w, x, y, z], "free_axis", "link"},
// "position_tolerance", "orientation_tolerance"}
void parse_pose_goal(const JsonField& goal, const RobotModel& robot, const QueryDefaults& d,
                     Goal& g) {
  goal.allow_only({"pose", "position_tolerance", "orientation_tolerance"});
  const JsonField pose = goal.at("pose");
  pose.allow_only({"position", "orientation", "free_axis", "link"});
  g.kind = Goal::Kind::Pose;
  g.position = pose.at("position").vec3_in({-100, 100}, " m");
  const JsonField o = pose.at("orientation");
  const std::vector<double> wxyz = o.numbers();
  if (wxyz.size() != 4) o.fail("expected a quaternion [w, x, y, z]");
  const Eigen::Quaterniond quaternion(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  if (!(quaternion.norm() > 1e-9)) o.fail("a quaternion of norm 0");
  g.orientation = quaternion.normalized();
  if (pose.has("free_axis")) {
    g.has_free_axis = true;
    g.free_axis = unit_vector(pose.at("free_axis"));
  }
  g.link = link_field(pose, robot);
  g.tolerance = goal.has("position_tolerance")
                    ? goal.at("position_tolerance").number_in({0, 100, true}, " m")
                    : d.pose_position_tolerance;
  g.orientation_tolerance =
      goal.has("orientation_tolerance")
          ? goal.at("orientation_tolerance").number_in({0, M_PI, true}, " rad")
          : d.orientation_tolerance;
}

void parse_goal(const JsonField& goal, const RobotModel& robot, const QueryDefaults& d, Goal& g) {
  if (goal.value().is_array()) {  // a goal set: any member will do
    g.kind = Goal::Kind::Set;
    for (const JsonField& member : goal.items()) {
      if (member.value().is_array()) member.fail("a goal set's members are single goals");
      g.members.emplace_back();
      parse_goal(member, robot, d, g.members.back());
    }
    if (g.members.empty()) goal.fail("an empty goal set");
    g.tolerance = g.members[0].tolerance;
  } else if (goal.has("q")) {
    goal.allow_only({"q", "tolerance"});
    g.kind = Goal::Kind::Joint;
    g.q = joint_vector(goal.at("q"), robot.dof);
    g.tolerance = goal.has("tolerance") ? goal.at("tolerance").number_in({0, 1e3, true}, " rad")
                                        : d.joint_tolerance;
  } else if (goal.has("pose")) {
    parse_pose_goal(goal, robot, d, g);
  } else if (goal.has("position")) {
    parse_position_goal(goal, robot, d, g);
  } else {
    goal.fail(
        "expected \"q\" (joint goal), \"pose\" (link pose goal), \"position\" (link position "
        "goal) or a list of goals (any of them)");
  }
}

// The fields a query may have: its own, and every parameter a registered planner declares.
const std::vector<std::string>& query_fields() {
  static const std::vector<std::string> fields = [] {
    std::vector<std::string> f = {"id",
                                  "start",
                                  "goal",
                                  "planner",
                                  "budget",
                                  "seed",
                                  "stop_at_first",
                                  "scene",
                                  "raw",
                                  "sample_interval",
                                  "shortcut_attempts",
                                  "payload",
                                  "end_effector_limits"};
    for (const std::string& name : all_parameter_names()) f.push_back(name);
    return f;
  }();
  return fields;
}

// What to return: the defaults (a tool's flags) unless the query sets them.
ReturnOptions parse_output(const JsonField& root, ReturnOptions o) {
  if (root.has("raw")) o.raw = root.at("raw").boolean();
  if (root.has("sample_interval"))
    o.sample_interval = root.at("sample_interval").number_in({0, 1e3, true}, " s");
  if (root.has("shortcut_attempts")) {
    const long n = root.at("shortcut_attempts").integer();
    if (n < 0 || n > 1000000) root.at("shortcut_attempts").fail("must be in [0, 1000000]");
    o.shortcut_attempts = static_cast<int>(n);
  }
  return o;
}

// The world of a query's "scene": an environment file's name, or an environment object.
WorldPtr parse_scene(const JsonField& root, SceneCache* scenes) {
  if (!root.has("scene")) return nullptr;
  const JsonField f = root.at("scene");
  if (!scenes) f.fail("a scene cannot be named here");
  if (f.value().is_object()) return scenes->inline_scene(f);
  const std::string path = f.string();
  if (path.empty()) f.fail("expected an environment file's name or an environment object");
  try {
    return scenes->load(path);
  } catch (const Error& e) {
    f.fail(e.what());
  }
}

void parse_problem(const JsonField& root, const Simulator& sim, const QueryDefaults& d,
                   PlanningProblem& p) {
  p.termination.budget = root.has("budget")
                             ? root.at("budget").number_in({0, kMaxBudgetSeconds, true}, " s")
                             : d.budget;
  if (root.has("stop_at_first")) p.termination.stop_at_first = root.at("stop_at_first").boolean();
  p.seed = root.has("seed") ? static_cast<uint64_t>(root.at("seed").integer()) : 1;
  if (root.has("seed") && root.at("seed").integer() < 0) root.at("seed").fail("must be >= 0");
  p.start = joint_vector(root.at("start"), sim.robot.dof);
  parse_goal(root.at("goal"), sim.robot, d, p.goal);
}

// The world with the query's task, when it has one (a payload, end-effector limits).
WorldPtr parse_task(const JsonField& root, const Simulator& sim, SimulatorWorkspace& ws,
                    const WorldPtr& world, SceneCache* scenes, const JointVector& start) {
  if (!root.has("payload") && !root.has("end_effector_limits")) return world;
  if (!scenes) root.fail("a payload or end-effector limits cannot be given here");
  Task task;
  if (root.has("payload")) task.payload = payload_from_json(root.at("payload"), sim.robot);
  if (root.has("end_effector_limits"))
    task.end_effector =
        end_effector_limits_from_json(root.at("end_effector_limits"), sim.robot, start, ws.robot);
  return scenes->with_task(world ? world : scenes->default_world(), task);
}

}  // namespace

Query read_query(const nlohmann::json& doc, const std::string& where, const Simulator& sim,
                 SimulatorWorkspace& ws, const QueryDefaults& d, SceneCache* scenes,
                 const WorldPtr& base, const EndPoseIndexes* coverage) {
  if (!doc.is_object()) fail(where, "expected a JSON object");
  const JsonField root(doc, where, "");
  root.allow_only(query_fields());
  Query q;
  q.id = root.at("id").string();
  parse_planner(root, q.request);
  q.request.output = parse_output(root, d.output);
  q.world = parse_scene(root, scenes);
  parse_problem(root, q.world ? q.world->sim : sim, d, q.request.problem);
  q.world = parse_task(root, sim, ws, q.world ? q.world : base, scenes, q.request.problem.start);
  const Simulator& in = q.world ? q.world->sim : sim;
  PlanningProblem& p = q.request.problem;
  if (needs_configurations(p.goal))
    resolve_goal(in, ws, p.start, p.seed, p.goal,
                 coverage ? coverage
                 : scenes ? scenes->goal_coverage()
                          : nullptr);
  const ProblemIssue issue = find_problem_issue(in, ws, q.request.problem);
  if (issue.any()) fail(where.empty() ? issue.field : where + ": " + issue.field, issue.what);
  return q;
}

Query parse_query(const std::string& text, int line, const Simulator& sim, SimulatorWorkspace& ws,
                  const QueryDefaults& d, std::string& id_out, SceneCache* scenes,
                  const EndPoseIndexes* coverage) {
  const std::string where = "line " + std::to_string(line);
  const nlohmann::json doc = parse_json_text(text, where, false);
  if (doc.is_object() && doc.contains("id") && doc["id"].is_string())
    id_out = doc["id"].get<std::string>();
  Query q = read_query(doc, where, sim, ws, d, scenes, nullptr, coverage);
  q.line = line;
  return q;
}

namespace {

nlohmann::json rows_json(const std::vector<JointVector>& rows) {
  nlohmann::json out = nlohmann::json::array();
  for (const JointVector& v : rows)
    out.push_back(std::vector<double>(v.data(), v.data() + v.size()));
  return out;
}

nlohmann::json execution_json(const ExecutionStats& e) {
  return {{"raw_steps", e.raw_steps},         {"steps", e.steps},
          {"shortcuts", e.shortcuts},         {"looked_blocked", e.looked_blocked},
          {"junctions", e.junctions},         {"blends_kept", e.blends_kept},
          {"simulations", e.simulations},     {"simulated_ticks", e.simulated_ticks},
          {"resumed_ticks", e.resumed_ticks}, {"seconds", e.seconds},
          {"raw_seconds", e.raw_seconds},     {"fell_back", e.fell_back},
          {"shortcuts_simulated_again", e.shortcuts_simulated_again}};
}

nlohmann::json trajectory_json(const Trajectory& traj) {
  nlohmann::json t;
  t["t"] = traj.t;
  t["q"] = rows_json(traj.q);
  t["dq"] = rows_json(traj.dq);
  if (!traj.ddq.empty()) {
    t["ddq"] = rows_json(traj.ddq);
    t["cmd"] = rows_json(traj.cmd);
  }
  return t;
}

// What the returned trajectory is: its figures, and the raw chain's beside a post-processed one.
void add_trajectory(const PlanAnswer& a, TrajectoryOutput mode, const std::string& csv_path,
                    nlohmann::json& j) {
  const Trajectory& traj = a.trajectory;
  const ExecutionStats* execution = a.raw ? nullptr : &a.execution;
  j["duration"] = traj.duration;
  j["stops"] = traj.stops;
  j["raw_duration"] = execution ? execution->raw_duration : traj.duration;
  j["raw_stops"] = execution ? execution->raw_stops : traj.stops;
  j["raw_cost"] = execution ? execution->raw_cost : traj.cost;
  if (execution) j["post_processing"] = execution_json(*execution);
  j["edges"] = traj.edges;
  if (mode == TrajectoryOutput::Inline) j["trajectory"] = trajectory_json(traj);
  if (mode == TrajectoryOutput::Csv) j["trajectory_file"] = csv_path;
}

}  // namespace

nlohmann::json result_json(const Query& q, const PlanAnswer& a, const PlanningWorld& world,
                           TrajectoryOutput mode, const std::string& csv_path) {
  const PlanResult& r = a.result;
  nlohmann::json j;
  j["id"] = q.id;
  j["line"] = q.line;
  j["planner"] = q.request.planner;
  j["success"] = r.success;
  j["time_to_first_solution"] =
      r.success ? nlohmann::json(r.time_to_first_solution) : nlohmann::json(nullptr);
  j["n_solutions"] = r.n_solutions;
  j["best_cost"] = r.success ? nlohmann::json(a.trajectory.cost) : nlohmann::json(nullptr);
  j["counters"] = {{"nodes", r.counters.nodes},
                   {"simulations", r.counters.simulations},
                   {"lazy_edges", r.counters.lazy_edges},
                   {"collision_checks", r.counters.collision_checks}};
  if (!r.success) j["failure"] = r.failure;
  if (r.success && !r.found_by.empty()) j["found_by"] = r.found_by;
  j["planning_seconds"] = a.planning_seconds;
  if (r.success) j["time_to_executable"] = a.seconds;
  j["scene"] = {{"name", world.env.name}, {"hash", world.env.identity}};
  if (r.success) add_trajectory(a, mode, csv_path, j);
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
  const bool full = !traj.ddq.empty();
  if (full) {
    for (const std::string& c : numbered_columns("ddq", n)) header.push_back(c);
    for (const std::string& c : numbered_columns("cmd", n)) header.push_back(c);
  }
  CsvWriter w(path, header);
  std::vector<double> row(header.size());
  for (size_t k = 0; k < traj.t.size(); ++k) {
    row[0] = traj.t[k];
    for (int i = 0; i < n; ++i) {
      row[1 + i] = traj.q[k][i];
      row[1 + n + i] = traj.dq[k][i];
      if (!full) continue;
      row[1 + 2 * n + i] = traj.ddq[k][i];
      row[1 + 3 * n + i] = traj.cmd[k][i];
    }
    w.row(row);
  }
  w.commit();
}

}  // namespace lazyboe
