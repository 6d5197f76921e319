// Scene preparation (issue 26's targets): a new world from an environment (parse, FCL geometry,
// collision model), for a 10-object scene of primitives and for a 100,000-point cloud
// voxelised at 2 cm; and one collision check of the Panda in each (a planner's inner loop).
#include <benchmark/benchmark.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/planning/world.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/robot_config.h"

namespace {

using json = nlohmann::json;
using namespace lazyboe;

const RobotModel& panda() {
  static const RobotModel robot = load_robot(default_robot_path());
  return robot;
}

// The table and 4 boxes and cylinders on it: 10 objects.
json ten_objects() {
  json env = json::parse(R"({"schema_version": 1, "name": "ten", "objects": [
    {"name": "floor", "type": "box", "size": [2, 2, 0.02], "position": [0, 0, -0.01],
     "allowed_links": ["panda_link0", "panda_link1"]},
    {"name": "top", "type": "box", "size": [0.6, 1.2, 0.04], "position": [0.65, 0, 0.18]}]})");
  for (int k = 0; k < 4; ++k)
    env["objects"].push_back(
        {{"name", "leg" + std::to_string(k)},
         {"type", "cylinder"},
         {"radius", 0.025},
         {"length", 0.16},
         {"position", {0.375 + 0.55 * (k / 2), -0.575 + 1.15 * (k % 2), 0.08}}});
  for (int k = 0; k < 4; ++k)
    env["objects"].push_back({{"name", "box" + std::to_string(k)},
                              {"type", k % 2 ? "box" : "cylinder"},
                              {"size", {0.1, 0.15, 0.2}},
                              {"radius", 0.05},
                              {"length", 0.2},
                              {"position", {0.5 + 0.1 * k, -0.4 + 0.25 * k, 0.3}}});
  for (json& o : env["objects"]) {  // only the fields of each type
    if (o["type"] == "box") o.erase("radius"), o.erase("length");
    if (o["type"] == "cylinder") o.erase("size");
  }
  return env;
}

// 100,000 points on the surfaces of a box of clutter above the table.
json cloud(int n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  json points = json::array();
  for (int k = 0; k < n; ++k) {
    const double a = u(rng), b = u(rng);
    const int face = k % 3;
    const double x = 0.4 + 0.4 * (face == 0 ? 0 : a), y = -0.3 + 0.6 * (face == 1 ? 0 : b),
                 z = 0.2 + 0.3 * (face == 2 ? 0 : (face == 0 ? a : b));
    points.push_back({x, y, z});
  }
  return {{"schema_version", 1},
          {"name", "cloud"},
          {"objects",
           {{{"name", "cloud"}, {"type", "points"}, {"points", points}, {"resolution", 0.02}}}}};
}

void prepare(benchmark::State& state, const json& env) {
  const SimulationOptions options;
  for (auto _ : state) {
    const PlanningWorld world(panda(), environment_from_json(JsonField(env, "bench", ""), ""),
                              options);
    benchmark::DoNotOptimize(&world);
  }
}

void BM_PrepareTenObjects(benchmark::State& state) { prepare(state, ten_objects()); }
BENCHMARK(BM_PrepareTenObjects)->Unit(benchmark::kMillisecond);

void BM_PreparePointCloud(benchmark::State& state) {
  prepare(state, cloud(static_cast<int>(state.range(0))));
}
BENCHMARK(BM_PreparePointCloud)->Arg(100000)->Unit(benchmark::kMillisecond);

void check(benchmark::State& state, const json& env) {
  const PlanningWorld world(panda(), environment_from_json(JsonField(env, "bench", ""), ""),
                            SimulationOptions{});
  RobotData rd(panda());
  CollisionData cd(world.collision);
  std::mt19937_64 rng(2);
  std::vector<JointVector> qs(256, JointVector(panda().dof));
  for (JointVector& q : qs)
    for (int i = 0; i < panda().dof; ++i)
      q[i] = std::uniform_real_distribution<double>(panda().q_min[i], panda().q_max[i])(rng);
  size_t k = 0;
  for (auto _ : state) {
    forward_kinematics(panda(), rd, qs[k++ % qs.size()]);
    update_collision_transforms(world.collision, cd, rd);
    benchmark::DoNotOptimize(in_collision(world.collision, cd));
  }
}

void BM_CheckTenObjects(benchmark::State& state) { check(state, ten_objects()); }
BENCHMARK(BM_CheckTenObjects);
void BM_CheckPointCloud(benchmark::State& state) { check(state, cloud(100000)); }
BENCHMARK(BM_CheckPointCloud);

}  // namespace
