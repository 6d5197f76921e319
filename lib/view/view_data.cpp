#include "lazyboe/view/view_data.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>

#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/io/trajectory_csv.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/sim/random.h"
#include "lazyboe/view/robot_visuals.h"

namespace lazyboe {

namespace {

using nlohmann::json;

// Rounded to `digits` decimals so the page stays small (dividing by the power of ten gives the
// double nearest the decimal, which prints as that decimal).
double rounded(double v, int digits) {
  const double scale = std::pow(10.0, digits);
  return std::round(v * scale) / scale;
}

json pose_json(const Pose& pose) {
  json R = json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R.push_back(pose.R(r, c));
  return {{"R", R}, {"p", {pose.p.x(), pose.p.y(), pose.p.z()}}};
}

// A triangle mesh's vertices and triangles, flat, into `out`.
void add_triangles(const TriangleMesh& mesh, json& out) {
  json vertices = json::array(), triangles = json::array();
  for (const Eigen::Vector3d& v : mesh.vertices)
    for (int c = 0; c < 3; ++c) vertices.push_back(v[c]);
  for (const Eigen::Vector3i& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) triangles.push_back(t[c]);
  out["vertices"] = std::move(vertices);
  out["triangles"] = std::move(triangles);
}

json shape_json(const std::string& name, const Shape& s, const Pose& pose) {
  json j = {{"name", name},
            {"type", shape_type_name(s.type)},
            {"radius", s.radius},
            {"length", s.length},
            {"size", {s.size.x(), s.size.y(), s.size.z()}},
            {"pose", pose_json(pose)}};
  if (s.type == ShapeType::Mesh) add_triangles(*s.mesh, j);
  return j;
}

}  // namespace

json robot_view_json(const RobotModel& robot, std::vector<std::string>& warnings) {
  json joints = json::array(), links = json::array(), shapes = json::array();
  for (const Joint& j : robot.joints) {
    joints.push_back({{"name", j.name},
                      {"type", j.type == JointType::Revolute ? "revolute" : "prismatic"},
                      {"origin", pose_json(j.origin)},
                      {"axis", {j.axis.x(), j.axis.y(), j.axis.z()}}});
  }
  for (const Link& l : robot.links)
    links.push_back({{"name", l.name}, {"body", l.body}, {"in_body", pose_json(l.in_body)}});
  for (const CollisionBody& b : robot.geometry.bodies) {
    json s = shape_json(b.name, b.shape, b.in_link);
    s["link"] = b.link;
    if (b.source_mesh) {  // drawn as its mesh; the shape checked stays in the data
      s["display"] = {{"pose", pose_json(b.source_in_link)}};
      add_triangles(*b.source_mesh, s["display"]);
    }
    shapes.push_back(s);
  }
  json visuals = json::array();
  for (const RobotVisual& v : load_robot_visuals(robot, warnings)) {
    json s = shape_json(v.name, v.shape, v.in_link);
    s["link"] = v.link;
    visuals.push_back(s);
  }
  return {{"name", robot.name}, {"config", robot.files.config},
          {"visuals", visuals}, {"dof", robot.dof},
          {"joints", joints},   {"links", links},
          {"shapes", shapes},   {"tip", robot.tip_link()}};
}

namespace {

// A mesh obstacle: its vertices and triangles, flat.
json mesh_json(const Obstacle& o) {
  json j = {{"name", o.name}, {"type", "mesh"}, {"pose", pose_json(o.pose)}};
  add_triangles(*o.mesh, j);
  return j;
}

// An octree obstacle (a voxelised cloud, an OctoMap): its occupied cells, centres and sizes.
json cells_json(const Obstacle& o) {
  json centres = json::array(), sizes = json::array();
  for (auto it = o.cells->begin_leafs(); it != o.cells->end_leafs(); ++it) {
    if (!o.cells->isNodeOccupied(*it)) continue;
    centres.insert(centres.end(), {it.getX(), it.getY(), it.getZ()});
    sizes.push_back(it.getSize());
  }
  return {{"name", o.name},
          {"type", "cells"},
          {"centres", centres},
          {"sizes", sizes},
          {"pose", pose_json(o.pose)}};
}

}  // namespace

json environment_view_json(const Environment& env) {
  json obstacles = json::array();
  for (const Obstacle& o : env.obstacles) {
    if (o.type == ObstacleType::Mesh)
      obstacles.push_back(mesh_json(o));
    else if (o.type == ObstacleType::Octree)
      obstacles.push_back(cells_json(o));
    else
      obstacles.push_back(shape_json(o.name, o.shape, o.pose));
  }
  return {{"name", env.name}, {"path", env.path}, {"obstacles", obstacles}};
}

namespace {

struct QueryEnds {
  std::string id;
  json start, goal;  // goal: one goal_marks, or {"set": [goal_marks, ...]}
  json payload;      // {link, com, box} or null
};

// A joint vector of the robot's size, as the page's kinematics needs it.
json joint_vector(const JsonField& field, int dof) {
  const std::vector<double> v = field.numbers();
  if (v.size() != size_t(dof))
    field.fail("expected " + std::to_string(dof) + " numbers (the robot's joints)");
  return v;
}

// What the page draws of one goal: {q}, {position, link} or {pose: {R, p}, link}, with the
// (position) tolerance when given.
json goal_marks(const JsonField& goal, int dof) {
  json g = json::object();
  if (goal.has("q")) g["q"] = joint_vector(goal.at("q"), dof);
  if (goal.has("position")) {
    const Eigen::Vector3d p = goal.at("position").vec3();
    g["position"] = {p.x(), p.y(), p.z()};
  }
  if (goal.has("tolerance")) g["tolerance"] = goal.at("tolerance").positive();
  if (goal.has("pose")) {
    const JsonField pose = goal.at("pose");
    const std::vector<double> w = pose.at("orientation").numbers();
    if (w.size() != 4) pose.at("orientation").fail("expected 4 numbers [w, x, y, z]");
    const Eigen::Quaterniond quaternion(w[0], w[1], w[2], w[3]);
    if (!(quaternion.norm() > 1e-9)) pose.at("orientation").fail("must not be zero");
    g["pose"] =
        pose_json(Pose{quaternion.normalized().toRotationMatrix(), pose.at("position").vec3()});
    if (pose.has("link")) g["link"] = pose.at("link").string();
    if (goal.has("position_tolerance")) g["tolerance"] = goal.at("position_tolerance").positive();
  } else if (goal.has("link")) {
    g["link"] = goal.at("link").string();
  }
  return g;
}

// The goal of a query line: one goal, or a set of them ("goal": [...]).
json goal_view(const nlohmann::json& value, const JsonField& goal, int dof) {
  if (value.is_object()) return goal_marks(goal, dof);
  if (!value.is_array() || value.empty()) goal.fail("expected an object or a list of goals");
  json set = json::array();
  for (const JsonField& member : goal.items()) set.push_back(goal_marks(member, dof));
  return {{"set", set}};
}

// A payload as the page draws it: a box (its own, or 5 cm for a point mass) at its centre of
// mass, on its link.
json payload_view(const JsonField& payload) {
  const Eigen::Vector3d com = payload.has("com") ? payload.at("com").vec3() : Eigen::Vector3d{};
  const Eigen::Vector3d box =
      payload.has("box") ? payload.at("box").vec3() : Eigen::Vector3d::Constant(0.05);
  json p = {{"com", {com.x(), com.y(), com.z()}}, {"box", {box.x(), box.y(), box.z()}}};
  if (payload.has("link")) p["link"] = payload.at("link").string();
  return p;
}

// Start, goal and payload of each query line (1-based). Only what the page draws is read
// (lazyboe-query has checked the rest), but that strictly: a line that is not JSON, a start or
// goal.q of the wrong size, a goal.position that is not 3 numbers are errors naming the line
// and field.
std::map<int, QueryEnds> read_query_ends(const std::string& path, int dof) {
  require_input_file(path, "queries");
  std::ifstream in(path);
  std::map<int, QueryEnds> out;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path + ":" + std::to_string(line);
    const json value = parse_json_text(text, where, false);
    const JsonField q(value, where, "");
    if (!value.is_object()) q.fail("expected a query object (schemas/query.schema.json)");
    QueryEnds e;
    if (value.contains("id") && value["id"].is_string()) e.id = value["id"];
    e.start = joint_vector(q.at("start"), dof);
    e.goal = goal_view(value["goal"], q.at("goal"), dof);
    if (q.has("payload")) e.payload = payload_view(q.at("payload"));
    out[line] = e;
  }
  return out;
}

std::vector<int> edge_list(const JsonField& r) {
  std::vector<int> edges;
  if (!r.has("edges")) return edges;
  for (const JsonField& e : r.at("edges").items()) edges.push_back(static_cast<int>(e.integer()));
  return edges;
}

// Keeps samples at least `interval` apart (and the last), rounded for the page.
json thinned_samples(const std::vector<double>& t, const std::vector<double>& q, int dof,
                     double interval) {
  json ts = json::array(), qs = json::array();
  const size_t n = t.size();
  double last = -1e300;
  for (size_t i = 0; i < n; ++i) {
    if (i + 1 < n && i > 0 && t[i] - last < interval - 1e-9) continue;
    last = t[i];
    ts.push_back(rounded(t[i], 4));
    json row = json::array();
    for (int k = 0; k < dof; ++k) row.push_back(rounded(q[i * dof + k], 7));
    qs.push_back(row);
  }
  return {{"t", ts}, {"q", qs}};
}

// t and q of an inline trajectory, checked as the CSV reader checks a file.
void read_inline_trajectory(const JsonField& traj, int dof, std::vector<double>& t,
                            std::vector<double>& q) {
  const std::vector<JsonField> times = traj.at("t").items(), rows = traj.at("q").items();
  if (times.empty()) traj.at("t").fail("no samples");
  if (rows.size() != times.size())
    traj.at("q").fail(std::to_string(rows.size()) + " rows for " + std::to_string(times.size()) +
                      " times");
  for (size_t i = 0; i < times.size(); ++i) {
    t.push_back(times[i].number());
    if (i > 0 && !(t[i] >= t[i - 1])) times[i].fail("times must not decrease");
    const std::vector<double> row = rows[i].numbers();
    if (row.size() != size_t(dof))
      rows[i].fail("expected " + std::to_string(dof) + " numbers (the robot's joints)");
    q.insert(q.end(), row.begin(), row.end());
  }
}

// As written (relative to where lazyboe-query ran), else relative to the results file's
// directory, else that directory with the file's name alone.
std::string resolve_trajectory_file(const std::string& file, const std::string& results_path) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(results_path).parent_path();
  if (fs::path(file).is_absolute()) return file;
  for (const fs::path& candidate : {fs::path(file), dir / file, dir / fs::path(file).filename()})
    if (fs::exists(candidate)) return candidate.string();
  return file;
}

}  // namespace

namespace {

json nullable(const nlohmann::json& value, const char* key) {
  return value.contains(key) ? value[key] : json(nullptr);
}

class ResultsReader {
 public:
  ResultsReader(const std::string& path, const RobotModel& robot, const ResultsViewOptions& options)
      : path_(path), robot_(robot), options_(options) {
    if (!options.queries_path.empty()) queries_ = read_query_ends(options.queries_path, robot.dof);
  }

  void read_line(const std::string& text, int file_line) {
    const std::string where = path_ + ":" + std::to_string(file_line);
    const json value = parse_json_text(text, where, false);
    const JsonField r(value, where, "");
    if (!value.is_object()) r.fail("expected a result object (schemas/result.schema.json)");
    const int line = static_cast<int>(r.at("line").integer());
    json item = {{"id", nullable(value, "id")},
                 {"planner", nullable(value, "planner")},
                 {"line", line},
                 {"success", r.at("success").boolean()}};
    if (!item["id"].is_null() && !item["id"].is_string()) r.at("id").fail("expected a string");
    add_query_ends(item, line, where);
    ++results_;
    if (!item["success"].get<bool>()) {
      item["reason"] = value.contains("error")     ? r.at("error").string()
                       : value.contains("failure") ? r.at("failure").string()
                                                   : std::string("no reason given");
      item["kind"] = value.contains("error") ? "error" : "failure";
      failures_.push_back(item);
      return;
    }
    item["cost"] = r.at("best_cost").number();
    item["time_to_first_solution"] = r.at("time_to_first_solution").number();
    if (value.contains("duration")) item["duration"] = r.at("duration").number();
    item["edges"] = edge_list(r);
    std::vector<double> t, q;
    if (value.contains("trajectory")) {
      read_inline_trajectory(r.at("trajectory"), robot_.dof, t, q);
    } else if (value.contains("trajectory_file")) {
      const std::string file = resolve_trajectory_file(r.at("trajectory_file").string(), path_);
      const TrajectoryCsv csv = read_trajectory_csv(file, robot_.dof);
      t = csv.t;
      q = csv.q;
    } else {
      without_.push_back(item);
      return;
    }
    item["samples"] = thinned_samples(t, q, robot_.dof, options_.min_sample_interval);
    trajectories_.push_back(item);
  }

  json result() const {
    return {{"path", path_},         {"queries", options_.queries_path},
            {"results", results_},   {"trajectories", trajectories_},
            {"failures", failures_}, {"without_trajectory", without_}};
  }

 private:
  void add_query_ends(json& item, int line, const std::string& where) const {
    const auto it = queries_.find(line);
    if (it == queries_.end()) return;
    if (!it->second.id.empty() && item["id"].is_string() && item["id"] != it->second.id)
      fail(where, "id '" + item["id"].get<std::string>() + "' is not the id '" + it->second.id +
                      "' of line " + std::to_string(line) + " of " + options_.queries_path);
    item["start"] = it->second.start;
    item["goal"] = it->second.goal;
    item["payload"] = it->second.payload;
  }

  std::string path_;
  const RobotModel& robot_;
  const ResultsViewOptions& options_;
  std::map<int, QueryEnds> queries_;
  int results_ = 0;
  json trajectories_ = json::array(), failures_ = json::array(), without_ = json::array();
};

}  // namespace

json results_view_json(const std::string& results_path, const RobotModel& robot,
                       const ResultsViewOptions& options) {
  require_input_file(results_path, "results");
  ResultsReader reader(results_path, robot, options);
  std::ifstream in(results_path);
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    reader.read_line(text, line);
  }
  return reader.result();
}

namespace {

// `count` distinct edges of `edges`, drawn with the seed (partial Fisher-Yates), in edge order.
std::vector<size_t> sample_edges(size_t edges, size_t count, uint64_t seed) {
  std::vector<size_t> ids(edges);
  std::iota(ids.begin(), ids.end(), size_t{0});
  Random random(seed, 0);
  count = std::min(count, edges);
  for (size_t i = 0; i < count; ++i) std::swap(ids[i], ids[i + random.next() % (edges - i)]);
  ids.resize(count);
  std::sort(ids.begin(), ids.end());
  return ids;
}

}  // namespace

json bundle_sample_json(const BundleView& bundle, const RobotModel& robot,
                        const BundleSampleOptions& options) {
  if (bundle.dof() != robot.dof)
    fail(bundle.path(),
         "has " + std::to_string(bundle.dof()) + " joints, the robot " + std::to_string(robot.dof));
  const std::vector<size_t> ids =
      sample_edges(bundle.size(), (options.points + 1) / 2, options.seed);
  const double theta = bundle.header().design_theta;
  const EdgeIndex starts(bundle, EdgePoint::Start);
  RobotData data(robot);
  std::vector<std::pair<uint32_t, double>> near;
  json points = json::array(), lazy = json::array(), collision = json::array(),
       density = json::array();
  for (const size_t e : ids) {
    for (const double* q : {bundle.q0(e), bundle.qf(e)}) {
      forward_kinematics(robot, data, Eigen::Map<const Eigen::VectorXd>(q, robot.dof));
      const Eigen::Vector3d p = link_pose(robot, data, robot.tip_link()).p;
      for (int k = 0; k < 3; ++k) points.push_back(rounded(p[k], 4));
      starts.within(q, theta, near);
      density.push_back(near.size());
      if (bundle.has_perturbation()) {
        lazy.push_back(rounded(bundle.p_lazy_prop(e), 3));
        collision.push_back(rounded(bundle.p_collision(e), 3));
      }
    }
  }
  json out = {{"path", bundle.path()},
              {"edges", bundle.size()},
              {"sampled_edges", ids.size()},
              {"seed", options.seed},
              {"theta", theta},
              {"points", points},
              {"density", density},
              {"has_perturbation", bundle.has_perturbation()}};
  out["edge_ids"] = ids;
  if (bundle.has_perturbation()) {
    out["p_lazy_prop"] = lazy;
    out["p_collision"] = collision;
  }
  return out;
}

}  // namespace lazyboe
