// Scenes given at query time (issue 26, item 1): a bundle plans in any scene of its robot.
// Covered, through lazyboe-query and lazyboe-robot on a bundle built with lazyboe-build:
// an obstacle added at query time is gone around (every sample checked against the new scene
// by `lazyboe-robot check`, while the bundle's-scene trajectory crosses it); the same scene as a
// file and inline is one scene (same hash, same answer); switching scenes in one process (A, B,
// A) answers as three processes do; a session keeps a scene it has built; and through the
// library, a world of another scene shares the session's bundle, robot and indexes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "box_files.h"
#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/request.h"
#include "lazyboe/robot/kinematics.h"
#include "planning_fixture.h"  // shared_fixture, vec, joint
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// A bundle of the demo's size (6000 edges over the default region, seed 1): dense enough that
// BoE finds a way around a ball put on its path.
std::string make_bundle() {
  const std::string dir = fresh_dir("scenes-bundle");
  const std::string bundle = dir + "/bundle.h5";
  const CommandResult b = run(watchdog(300) + quote(tool_path("lazyboe-build")) + " --out " +
                              quote(bundle) + " --edges 6000 --theta 0.45 --seed 1 --quiet");
  if (b.exit_code != 0) throw std::runtime_error("lazyboe-build failed: " + describe(b));
  return bundle;
}

struct Fixture {
  std::string path = make_bundle();
  PlanningSession session{path, true, "", ""};
  // Far apart (1.1 rad), free above the table: the open table's answer is one straight motion.
  JointVector start = joint({-0.0785, -0.0105, 0.2413, -2.1436, -0.0328, 2.2495, 1.117});
  JointVector goal = joint({0.5712, 0.1721, -0.0083, -1.8393, -0.0147, 1.7537, 0.7134});
};

const Fixture& fixture() { return shared_fixture<Fixture>(); }

json table_scene() { return json::parse(read_file(source_path("data/environments/table.json"))); }

// BoE from start to goal, deterministic: it stops at its first solution.
json query(const std::string& id) {
  const Fixture& f = fixture();
  return {{"id", id},
          {"start", vec(f.start)},
          {"planner", "boe"},
          {"goal", {{"q", vec(f.goal)}, {"tolerance", 0.3}}},
          {"seed", 3},
          {"stop_at_first", true},
          {"budget", 30 * time_scale()}};
}

std::vector<json> run_queries(const std::string& name, const std::vector<json>& queries,
                              const std::vector<std::string>& extra = {}) {
  std::string text;
  for (const json& q : queries) text += q.dump() + "\n";
  const std::string file = write_temp_file(name + ".jsonl", text);
  std::string cmd = watchdog(300) + quote(tool_path("lazyboe-query")) + " --bundle " +
                    quote(fixture().path) + " --queries " + quote(file) +
                    " --trajectories inline --quiet";
  for (const std::string& a : extra) cmd += " " + quote(a);
  const CommandResult r = run(cmd);
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  std::vector<json> results;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) results.push_back(json::parse(line));
  EXPECT_EQ(results.size(), queries.size()) << describe(r);
  return results;
}

// A result without the fields that depend on the wall clock or the line.
json timeless(json r) {
  r.erase("time_to_first_solution");
  r.erase("planning_seconds");
  r.erase("time_to_executable");
  r.erase("line");
  if (r.contains("post_processing")) {
    r["post_processing"].erase("seconds");
    r["post_processing"].erase("raw_seconds");
  }
  return r;
}

// The trajectory's joint rows, as lazyboe-robot check reads them.
std::string configs_csv(const std::string& name, const json& result) {
  const int dof = fixture().session.robot.dof;
  std::string text;
  for (int i = 1; i <= dof; ++i) text += (i > 1 ? ",q" : "q") + std::to_string(i);
  text += "\n";
  for (const json& row : result.at("trajectory").at("q")) {
    std::string line;
    for (const json& v : row) line += (line.empty() ? "" : ",") + std::to_string(v.get<double>());
    text += line + "\n";
  }
  return write_temp_file(name, text);
}

struct CheckCounts {
  int rows = 0, env_collisions = 0, self_collisions = 0, outside_limits = 0;
};

// `lazyboe-robot check` of every sample of a result's trajectory in the scene `env_file`.
CheckCounts check_samples(const std::string& name, const json& result,
                          const std::string& env_file) {
  const std::string in = configs_csv(name + ".csv", result), out = in + ".out.csv";
  const CommandResult r = run(quote(tool_path("lazyboe-robot")) + " check --env " +
                              quote(env_file) + " --in " + quote(in) + " --out " + quote(out));
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  std::ifstream csv(out);
  std::string line;
  std::getline(csv, line);  // in_limits,self_collision,env_collision,min_distance
  CheckCounts c;
  while (std::getline(csv, line)) {
    int in_limits = 0, self = 0, env = 0;
    if (std::sscanf(line.c_str(), "%d,%d,%d", &in_limits, &self, &env) != 3) continue;
    ++c.rows;
    c.outside_limits += in_limits == 0;
    c.self_collisions += self;
    c.env_collisions += env;
  }
  return c;
}

// `object` (without a position) on the hand's way through `result`'s trajectory (near its
// middle), where it leaves the start and the goal free; the table scene with it, as JSON.
json blocked_scene(const json& result, const json& object) {
  const Fixture& f = fixture();
  const RobotModel& robot = f.session.robot;
  const json& rows = result.at("trajectory").at("q");
  const int hand = robot.link_index("panda_link7");
  RobotData data(robot);
  SimulatorWorkspace ws(f.session.sim());
  const size_t mid = rows.size() / 2;
  for (size_t step = 0; step < mid; ++step) {
    for (const size_t k : {mid + step, mid - step}) {
      forward_kinematics(robot, data, joint(rows.at(k).get<std::vector<double>>()));
      const Eigen::Vector3d p = link_pose(robot, data, hand).p;
      json scene = table_scene();
      scene["name"] = "table-with-ball";
      json placed = object;
      placed["position"] = {p.x(), p.y(), p.z()};
      scene["objects"].push_back(placed);
      const WorldPtr world = f.session.scenes.inline_scene(JsonField(scene, "ball", ""));
      if (check_state(world->sim, ws, f.start) == RolloutStatus::Valid &&
          check_state(world->sim, ws, f.goal) == RolloutStatus::Valid)
        return scene;
    }
  }
  throw std::runtime_error("no sample of the trajectory leaves start and goal free of it");
}

const json kBall = {{"name", "ball"}, {"type", "sphere"}, {"radius", 0.05}};

TEST(Scenes, AnObstacleGivenAtQueryTimeIsGoneAround) {
  const json open = run_queries("open", {query("open")}).at(0);
  ASSERT_TRUE(open.value("success", false)) << open.dump().substr(0, 600);
  EXPECT_EQ(open["scene"]["name"], "table");

  const json scene = blocked_scene(open, kBall);
  const std::string scene_file = write_temp_file("scenes/ball.json", scene.dump(2));
  json q = query("blocked");
  q["scene"] = scene_file;
  const json blocked = run_queries("blocked", {q}).at(0);
  ASSERT_TRUE(blocked.value("success", false)) << blocked.dump().substr(0, 600);
  EXPECT_EQ(blocked["scene"]["name"], "table-with-ball");

  // The bundle's-scene trajectory crosses the ball; the new one is free at every sample.
  const CheckCounts before = check_samples("open", open, scene_file);
  const CheckCounts after = check_samples("blocked", blocked, scene_file);
  EXPECT_GT(before.rows, 0);
  EXPECT_GT(before.env_collisions, 0) << "the ball is not on the old trajectory's way";
  EXPECT_GT(after.rows, 0);
  EXPECT_EQ(after.env_collisions, 0);
  EXPECT_EQ(after.self_collisions, 0);
  EXPECT_EQ(after.outside_limits, 0);
}

TEST(Scenes, TheSameSceneFromAFileAndInlineIsOneScene) {
  const std::string file = source_path("data/environments/empty.json");
  json by_file = query("file"), inline_scene = query("inline");
  by_file["scene"] = file;
  json empty = json::parse(read_file(file));
  inline_scene["scene"] = empty;
  const std::vector<json> r = run_queries("file-inline", {by_file, inline_scene});
  ASSERT_EQ(r.size(), 2u);
  ASSERT_TRUE(r[0].value("success", false)) << r[0].dump().substr(0, 600);
  EXPECT_EQ(r[0]["scene"], r[1]["scene"]);
  EXPECT_EQ(r[0]["scene"]["name"], "empty");
  json a = timeless(r[0]), b = timeless(r[1]);
  a.erase("id");
  b.erase("id");
  EXPECT_TRUE(a == b) << r[0].dump().substr(0, 400) << "\n" << r[1].dump().substr(0, 400);
}

// A, B, A in one process (a query's "scene"), and each in a process of its own (--env).
TEST(Scenes, SwitchingScenesInOneProcessAnswersAsSeparateProcessesDo) {
  const json scene_b = blocked_scene(run_queries("probe", {query("probe")}).at(0), kBall);
  const std::string a = source_path("data/environments/table.json");
  const std::string b = write_temp_file("scenes/switch-b.json", scene_b.dump());
  std::vector<json> mixed;
  for (const std::string& scene : {a, b, a}) {
    json q = query("q" + std::to_string(mixed.size()));
    q["scene"] = scene;
    mixed.push_back(q);
  }
  const std::vector<json> together = run_queries("mixed", mixed, {"--jobs", "2"});
  ASSERT_EQ(together.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    json q = mixed[k];
    const std::string scene = q["scene"];
    q.erase("scene");
    const std::vector<json> alone = run_queries("alone", {q}, {"--env", scene});
    ASSERT_EQ(alone.size(), 1u);
    SCOPED_TRACE(k);
    ASSERT_TRUE(together[k].value("success", false)) << together[k].dump().substr(0, 600);
    EXPECT_TRUE(timeless(together[k]) == timeless(alone[0]))
        << together[k].dump().substr(0, 400) << "\n"
        << alone[0].dump().substr(0, 400);
  }
  EXPECT_NE(together[0]["scene"]["hash"], together[1]["scene"]["hash"]);
  EXPECT_NE(together[0]["edges"], together[1]["edges"]) << "the ball changed nothing";
}

// The box on the way as a primitive, a mesh, a point cloud and an OctoMap: each plan goes
// around it, checked against the primitive at every sample.
TEST(Scenes, TheSameBoxAsAPrimitiveMeshCloudAndOctreeIsGoneAround) {
  const json open = run_queries("open-box", {query("open-box")}).at(0);
  ASSERT_TRUE(open.value("success", false));
  // Placed where a cube 1 cm larger on each side leaves start and goal free: the voxelised
  // clouds reach up to one cell (1 cm) beyond the box.
  const json grown = {{"name", "box"}, {"type", "box"}, {"size", {0.08, 0.08, 0.08}}};
  const json at = blocked_scene(open, grown)["objects"].back()["position"];
  const BoxFiles box{Eigen::Vector3d(at[0], at[1], at[2]), Eigen::Vector3d::Constant(0.06), 0.01,
                     "scenes/box"};
  const std::vector<json> objects = {
      {{"type", "box"}, {"size", {0.06, 0.06, 0.06}}},
      {{"type", "mesh"}, {"file", box.obj()}},
      {{"type", "points"}, {"file", box.ply(true)}, {"resolution", 0.01}},
      {{"type", "octree"}, {"file", box.bt()}}};
  std::string primitive_file;
  for (size_t k = 0; k < objects.size(); ++k) {
    json object = objects[k];
    object["name"] = "box";
    if (k < 2) object["position"] = at;  // the cloud and the map are in base coordinates
    json scene = table_scene();
    scene["name"] = "box-" + object["type"].get<std::string>();
    scene["objects"].push_back(object);
    const std::string file =
        write_temp_file("scenes/" + scene["name"].get<std::string>() + ".json", scene.dump());
    if (k == 0) primitive_file = file;
    json q = query("around");
    q["scene"] = file;
    const json r = run_queries("around", {q}).at(0);
    SCOPED_TRACE(scene["name"].get<std::string>());
    ASSERT_TRUE(r.value("success", false)) << r.dump().substr(0, 600);
    const CheckCounts c = check_samples("around", r, primitive_file);
    EXPECT_GT(c.rows, 0);
    EXPECT_EQ(c.env_collisions, 0);
  }
  EXPECT_GT(check_samples("open-box", open, primitive_file).env_collisions, 0)
      << "the box is not on the open table's way";
}

// Through the library: one session, worlds by content, the bundle and indexes shared.
TEST(Scenes, ASessionKeepsItsScenesByContent) {
  const Fixture& f = fixture();
  const PlanningSession& session = f.session;
  EXPECT_EQ(session.world().env.name, "table");
  const WorldPtr empty = session.scenes.load(source_path("data/environments/empty.json"));
  EXPECT_EQ(session.scenes.load(source_path("data/environments/empty.json")), empty);
  // The bundle's own scene, reformatted: the same content, so the default world itself.
  const std::string spaced =
      write_temp_file("scenes/table-spaced.json", table_scene().dump(8) + "\n\n");
  EXPECT_EQ(session.scenes.load(spaced), session.scenes.default_world());
  // Contexts of two worlds: the same bundle and indexes, each its own simulator.
  const PlanningContext in_empty = session.context(*empty), in_table = session.context();
  EXPECT_EQ(in_empty.bundle, in_table.bundle);
  EXPECT_EQ(in_empty.index, in_table.index);
  EXPECT_NE(&in_empty.sim, &in_table.sim);
  EXPECT_EQ(empty->collision.obstacles.size(), 1u);  // the floor
  // One workspace serves both worlds.
  SimulatorWorkspace ws(session.sim());
  PlanRequest request;
  request.planner = "boe";
  request.problem.start = f.start;
  request.problem.goal.q = f.goal;
  request.problem.goal.tolerance = 0.3;
  request.problem.termination.stop_at_first = true;
  request.problem.termination.budget = 30 * time_scale();
  const PlanAnswer there = answer_request(in_empty, request, ws);
  const PlanAnswer here = answer_request(in_table, request, ws);
  EXPECT_TRUE(there.result.success) << there.result.failure;
  EXPECT_TRUE(here.result.success) << here.result.failure;
}

// The workspace index (written by lazyboe-build) steers lazysp in a new scene; the answer is
// still simulated in it, so it goes around the ball. In the bundle's own scene the index
// changes nothing: the same answers with and without it.
TEST(Scenes, LazyspPlansWithTheWorkspaceIndexInANewScene) {
  const Fixture& f = fixture();
  ASSERT_TRUE(f.session.workspace.index) << f.session.workspace.source;
  const json open = run_queries("index-open", {query("open")}).at(0);
  ASSERT_TRUE(open.value("success", false)) << open.dump().substr(0, 600);
  const json scene = blocked_scene(open, kBall);
  const WorldPtr world = f.session.scenes.inline_scene(JsonField(scene, "ball", ""));
  ASSERT_TRUE(world->edge_marks);
  EXPECT_GT(world->edge_marks->marked, 0u);
  EXPECT_LT(world->edge_marks->marked, f.session.bundle.size());

  const std::string scene_file = write_temp_file("scenes/index-ball.json", scene.dump(2));
  json q = query("lazysp");
  q["planner"] = "lazysp";
  q["scene"] = scene_file;
  const json r = run_queries("index-lazysp", {q}).at(0);
  ASSERT_TRUE(r.value("success", false)) << r.dump().substr(0, 600);
  const CheckCounts c = check_samples("index-lazysp", r, scene_file);
  EXPECT_GT(c.rows, 0);
  EXPECT_EQ(c.env_collisions, 0);

  const std::string bare = fresh_dir("scenes-no-index") + "/bundle.h5";
  fs::copy_file(f.path, bare);
  json own = query("own");
  own["planner"] = "lazysp";
  std::string text = own.dump() + "\n";
  own["seed"] = 4;
  own["id"] = "own-4";
  text += own.dump() + "\n";
  const std::string file = write_temp_file("scenes/own.jsonl", text);
  std::vector<json> answers;
  for (const std::string& bundle : {f.path, bare}) {
    const CommandResult run_r =
        run(watchdog(300) + quote(tool_path("lazyboe-query")) + " --bundle " + quote(bundle) +
            " --queries " + quote(file) + " --trajectories inline");
    ASSERT_EQ(run_r.exit_code, 0) << describe(run_r);
    EXPECT_NE(run_r.err.find(bundle == bare ? "workspace index none" : "workspace index mapped"),
              std::string::npos)
        << run_r.err;
    answers.push_back(json::array());
    std::istringstream in(run_r.out);
    for (std::string line; std::getline(in, line);)
      answers.back().push_back(timeless(json::parse(line)));
  }
  EXPECT_EQ(answers[0], answers[1]);
}

// The bench's count of problems that need no planning: one direct command solves the open
// table's problem, not the same problem with a ball on the straight line, nor a position goal.
TEST(Scenes, ADirectCommandSolvesTheOpenProblemOnly) {
  const Fixture& f = fixture();
  PlanningProblem p;
  p.start = f.start;
  p.goal.q = f.goal;
  p.goal.tolerance = 0.3;
  const PlanningContext open = f.session.context();
  SimulatorWorkspace ws(f.session.sim());
  EXPECT_TRUE(solved_by_direct_command(open.sim, ws, open.command, p));

  const json line = {
      {"trajectory", {{"q", {vec(f.start), vec((f.start + f.goal) / 2), vec(f.goal)}}}}};
  const WorldPtr blocked =
      f.session.scenes.inline_scene(JsonField(blocked_scene(line, kBall), "ball", ""));
  const PlanningContext there = f.session.context(*blocked);
  EXPECT_FALSE(solved_by_direct_command(there.sim, ws, there.command, p));

  PlanningProblem position = p;
  position.goal.kind = Goal::Kind::Position;
  EXPECT_FALSE(solved_by_direct_command(open.sim, ws, open.command, position));
}

TEST(Scenes, AnEnvironmentForAnotherRobotIsRefusedWithOneLine) {
  json scene = table_scene();
  scene["objects"][0]["allowed_links"] = {"base_link", "shoulder_link"};  // a UR5's
  const std::string file = write_temp_file("scenes/ur5-floor.json", scene.dump());
  const std::string queries = write_temp_file("scenes/one.jsonl", query("one").dump() + "\n");
  const CommandResult r =
      run(quote(tool_path("lazyboe-query")) + " --bundle " + quote(fixture().path) + " --queries " +
          quote(queries) + " --env " + quote(file));
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  expect_one_line_error(r, {file, "base_link", "is not a link of robot"});
}

}  // namespace
}  // namespace lazyboe::test
