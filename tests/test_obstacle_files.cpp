// Obstacles read from files (issue 26, item 2): one box as a primitive, as a triangle mesh (OBJ
// and binary STL, through Assimp), as a point cloud (PLY, ASCII and binary, and inline) voxelised
// into an octree, and as an OctoMap .bt file blocks alike on many random configurations; a
// scene's identity covers the files it names; bad files and fields get one error naming them.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "box_files.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/collision/mesh.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/kinematics.h"
#include "test_util.h"

namespace lazyboe {
namespace {

using json = nlohmann::json;

// The box: 16 cm wide, in front of the robot at hand height; clouds voxelised at 1 cm.
const test::BoxFiles kBox{{0.45, 0.1, 0.45}, {0.16, 0.16, 0.16}, 0.01, "obstacle-files/box"};
const Eigen::Vector3d kCentre = kBox.centre, kSize = kBox.size;
constexpr double kResolution = 0.01;

std::string dir() {
  static const std::string d = test::temp_dir() + "/obstacle-files";
  std::filesystem::create_directories(d);
  return d;
}

json position(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

// The table scene's floor and one object.
Environment scene_with(json object) {
  json env = {{"schema_version", 1}, {"name", "box"}};
  env["objects"] = {{{"name", "floor"},
                     {"type", "box"},
                     {"size", {2, 2, 0.02}},
                     {"position", {0, 0, -0.01}},
                     {"allowed_links", {"panda_link0", "panda_link1"}}},
                    object};
  const std::string path = test::write_temp_file("obstacle-files/scene.json", env.dump());
  return load_environment(path);
}

std::vector<Environment> representations() {
  std::vector<Environment> envs;
  envs.push_back(scene_with({{"name", "box"},
                             {"type", "box"},
                             {"size", position(kSize)},
                             {"position", position(kCentre)}}));
  for (const std::string& mesh : {kBox.obj(), kBox.binary_stl()})
    envs.push_back(scene_with(
        {{"name", "box"}, {"type", "mesh"}, {"file", mesh}, {"position", position(kCentre)}}));
  for (const bool binary : {false, true})
    envs.push_back(scene_with({{"name", "box"},
                               {"type", "points"},
                               {"file", kBox.ply(binary)},
                               {"resolution", kResolution}}));
  json inline_points = json::array();
  for (const Eigen::Vector3d& p : kBox.points()) inline_points.push_back(position(p));
  envs.push_back(scene_with({{"name", "box"},
                             {"type", "points"},
                             {"points", inline_points},
                             {"resolution", kResolution}}));
  envs.push_back(scene_with({{"name", "box"}, {"type", "octree"}, {"file", kBox.bt()}}));
  return envs;
}

TEST(ObstacleFiles, OneBoxBlocksAlikeInEveryRepresentation) {
  const RobotModel& robot = test::panda();
  const std::vector<Environment> envs = representations();
  std::vector<CollisionModel> models;
  for (const Environment& e : envs) models.push_back(build_collision_model(robot, e));
  RobotData rd(robot);
  std::vector<CollisionData> data;
  for (const CollisionModel& m : models) data.emplace_back(m);
  std::mt19937_64 rng(7);
  int blocked = 0, differ = 0, near = 0;
  for (int k = 0; k < 3000; ++k) {
    JointVector q(robot.dof);
    for (int i = 0; i < robot.dof; ++i)
      q[i] = std::uniform_real_distribution<double>(robot.q_min[i], robot.q_max[i])(rng);
    forward_kinematics(robot, rd, q);
    update_collision_transforms(models[0], data[0], rd);
    const bool box = check_collision(models[0], data[0]).env_collision;
    // Where the robot is within a cell of the box, a voxelised box may answer otherwise.
    const double distance = min_distance(models[0], data[0]).env_distance;
    if (distance > 0 && distance < 2 * kResolution) {
      ++near;
      continue;
    }
    blocked += box;
    for (size_t r = 1; r < models.size(); ++r) {
      update_collision_transforms(models[r], data[r], rd);
      const bool other = check_collision(models[r], data[r]).env_collision;
      differ += other != box;
      EXPECT_EQ(other, box) << "representation " << r << " at distance " << distance;
    }
  }
  EXPECT_GT(blocked, 50) << "too few configurations touch the box to compare";
  EXPECT_EQ(differ, 0);
  RecordProperty("blocked", blocked);
  RecordProperty("near", near);
}

TEST(ObstacleFiles, DistancesAgreeAwayFromTheBox) {
  const RobotModel& robot = test::panda();
  const std::vector<Environment> envs = representations();
  const CollisionModel box = build_collision_model(robot, envs[0]);
  const CollisionModel mesh = build_collision_model(robot, envs[1]);
  RobotData rd(robot);
  CollisionData a(box), b(mesh);
  std::mt19937_64 rng(3);
  for (int k = 0; k < 200; ++k) {
    JointVector q(robot.dof);
    for (int i = 0; i < robot.dof; ++i)
      q[i] = std::uniform_real_distribution<double>(robot.q_min[i], robot.q_max[i])(rng);
    forward_kinematics(robot, rd, q);
    update_collision_transforms(box, a, rd);
    update_collision_transforms(mesh, b, rd);
    const double d = min_distance(box, a).env_distance, e = min_distance(mesh, b).env_distance;
    if (d > 0.01) {
      EXPECT_NEAR(e, d, 1e-3) << k;
    }
  }
}

TEST(ObstacleFiles, TheIdentityCoversTheFilesNamed) {
  const std::string obj = kBox.obj();
  json object = {{"name", "box"}, {"type", "mesh"}, {"file", obj}};
  const std::string before = scene_with(object).identity;
  EXPECT_EQ(scene_with(object).identity, before);
  {
    std::ofstream out(obj, std::ios::app);
    out << "v 1 1 1\n";  // the same description, another file
  }
  EXPECT_NE(scene_with(object).identity, before);
}

TEST(ObstacleFiles, FilesAreNamedRelativeToTheEnvironmentFile) {
  kBox.obj();
  const json env = {{"schema_version", 1},
                    {"name", "relative"},
                    {"objects", {{{"name", "box"}, {"type", "mesh"}, {"file", "box.obj"}}}}};
  const std::string path = test::write_temp_file("obstacle-files/relative.json", env.dump());
  const Environment e = load_environment(path);
  ASSERT_EQ(e.obstacles.size(), 1u);
  EXPECT_EQ(e.obstacles[0].mesh->triangles.size(), 12u);
  ASSERT_EQ(e.files.size(), 1u);
  EXPECT_EQ(std::filesystem::path(e.files[0]).filename(), "box.obj");
}

std::string error_of(const json& object) {
  try {
    scene_with(object);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ObstacleFiles, BadFilesAndFieldsAreOneErrorNamingThem) {
  const std::string d = dir();
  const std::string empty = test::write_temp_file("obstacle-files/empty.stl", "");
  const std::string text = test::write_temp_file("obstacle-files/text.obj", "hello\n");
  const std::string garbage = test::write_temp_file("obstacle-files/garbage.bt", "not an octree");
  const std::string nan_ply = test::write_temp_file(
      "obstacle-files/nan.ply",
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\nnan 0 0\n");
  struct Case {
    json object;
    std::vector<std::string> needles;
  };
  const std::vector<Case> cases = {
      {{{"name", "m"}, {"type", "mesh"}, {"file", d + "/missing.stl"}},
       {"objects[1].file", "missing.stl"}},
      {{{"name", "m"}, {"type", "mesh"}, {"file", empty}}, {"objects[1].file", "empty.stl"}},
      {{{"name", "m"}, {"type", "mesh"}, {"file", text}}, {"objects[1].file", "text.obj"}},
      {{{"name", "o"}, {"type", "octree"}, {"file", garbage}}, {"objects[1].file", "garbage.bt"}},
      {{{"name", "p"}, {"type", "points"}, {"file", nan_ply}, {"resolution", 0.02}},
       {"objects[1].file", "nan.ply", "not a finite number"}},
      {{{"name", "p"}, {"type", "points"}, {"points", json::array()}, {"resolution", 0.02}},
       {"objects[1]", "no point"}},
      {{{"name", "p"}, {"type", "points"}, {"points", {{0, 0, 0}}}, {"resolution", 0}},
       {"objects[1].resolution"}},
      {{{"name", "p"}, {"type", "points"}, {"resolution", 0.02}},
       {"objects[1]", "\"file\" or \"points\""}},
      {{{"name", "m"}, {"type", "mesh"}, {"file", ""}}, {"objects[1].file", "must not be empty"}},
      {{{"name", "m"}, {"type", "mesh"}, {"file", text}, {"radius", 1}},
       {"objects[1].radius", "unknown field"}},
      {{{"name", "m"}, {"type", "meshes"}}, {"objects[1].type", "unknown object type"}},
  };
  for (const Case& c : cases) {
    const std::string e = error_of(c.object);
    SCOPED_TRACE(c.object.dump());
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    for (const std::string& n : c.needles) EXPECT_NE(e.find(n), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace lazyboe
