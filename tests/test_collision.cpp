// Collision: hand-made poses that must and must not collide (self and environment), the margin
// at near-touching distances, excluded pairs, and agreement of the fast culled check with the
// exact distances on many random configurations.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <tuple>

#include "lazyboe/collision/allowed_pairs.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/robot_config.h"
#include "test_util.h"

namespace lazyboe {
namespace {

JointVector q_of(std::initializer_list<double> values) {
  JointVector q(static_cast<int>(values.size()));
  int i = 0;
  for (double v : values) q[i++] = v;
  return q;
}

const JointVector kReady = q_of({0, -0.785, 0, -2.356, 0, 1.571, 0.785});

struct Checker {
  const RobotModel& robot;
  CollisionModel model;
  RobotData rd;
  CollisionData cd;
  Checker(const RobotModel& r, const Environment& env, CollisionOptions options = {})
      : robot(r), model(build_collision_model(r, env, options)), rd(r), cd(model) {}
  void set(const JointVector& q) {
    forward_kinematics(robot, rd, q);
    update_collision_transforms(model, cd, rd);
  }
  CollisionReport report(const JointVector& q) {
    set(q);
    return check_collision(model, cd);
  }
};

Environment env_file(const std::string& name) {
  return load_environment(test::source_path("data/environments/" + name + ".json"));
}

int shape_index(const CollisionModel& m, const std::string& name) {
  for (size_t i = 0; i < m.robot.size(); ++i) {
    if (m.robot[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

TEST(Collision, ReadyPoseIsFreeInEveryEnvironment) {
  for (const char* name : {"empty", "table", "shelf"}) {
    Checker c(test::panda(), env_file(name));
    const CollisionReport r = c.report(kReady);
    EXPECT_FALSE(r.self_collision) << name;
    EXPECT_FALSE(r.env_collision) << name;
    EXPECT_GT(min_distance(c.model, c.cd).min(), c.model.margin) << name;
  }
}

TEST(Collision, ArmReachingIntoTheTableCollides) {
  Checker table(test::panda(), env_file("table"));
  Checker empty(test::panda(), env_file("empty"));
  // Shoulder pitched forward and elbow opened: the flange ends up below the tabletop (z 0.2).
  const JointVector q = q_of({0, 1.2, 0, -0.8, 0, 1.5, 0});
  RobotData rd(test::panda());
  forward_kinematics(test::panda(), rd, q);
  ASSERT_LT(link_pose(test::panda(), rd, test::panda().tip_link()).p.z(), 0.2);
  const CollisionReport r = table.report(q);
  EXPECT_TRUE(r.env_collision);
  EXPECT_FALSE(r.self_collision);
  EXPECT_FALSE(empty.report(q).env_collision);  // no table there
}

TEST(Collision, FoldedElbowSelfCollides) {
  Checker c(test::panda(), env_file("empty"));
  // Elbow folded to its limit with the wrist turned back into the upper arm.
  const JointVector q = q_of({0, 0, 0, -3.0, 0, 0.2, 0});
  const CollisionReport r = c.report(q);
  EXPECT_TRUE(r.self_collision);
  EXPECT_FALSE(r.env_collision);
}

TEST(Collision, AdjacentLinksOverlapButAreExcluded) {
  const RobotModel& robot = test::panda();
  Checker normal(robot, env_file("empty"));
  CollisionOptions all_pairs;
  all_pairs.ignore_allowed_pairs = true;
  Checker unfiltered(robot, env_file("empty"), all_pairs);
  // Neighbouring capsules overlap at their joints by design, in every configuration.
  EXPECT_FALSE(normal.report(kReady).self_collision);
  EXPECT_TRUE(unfiltered.report(kReady).self_collision);
  const int l1 = shape_index(unfiltered.model, "link1_a"),
            l2 = shape_index(unfiltered.model, "link2_a");
  ASSERT_GE(l1, 0);
  ASSERT_GE(l2, 0);
  EXPECT_TRUE(self_pair_collides(unfiltered.model, unfiltered.cd, l1, l2));
  for (const auto& [a, b] : normal.model.self_pairs) {
    EXPECT_FALSE(
        robot.geometry.is_allowed_pair(normal.model.robot[a].link, normal.model.robot[b].link));
  }
}

TEST(Collision, FloorIsAllowedOnlyForTheBaseLinks) {
  const RobotModel& robot = test::panda();
  Checker c(robot, env_file("empty"));
  const int link0 = robot.link_index("panda_link0"), link1 = robot.link_index("panda_link1");
  for (const auto& [a, o] : c.model.env_pairs) {
    EXPECT_NE(c.model.robot[a].link, link0);
    EXPECT_NE(c.model.robot[a].link, link1);
  }
  EXPECT_FALSE(c.report(q_of({0, 0, 0, -0.1, 0, 0.1, 0})).any());
}

// "@base" (what the bundled environments say) is the base and the first moving body: for the
// Panda exactly link0 and link1, the same pairs as naming them; for a chain with links fixed to
// its base, those too.
TEST(Collision, AtBaseIsTheBaseAndTheFirstMovingBody) {
  const RobotModel& robot = test::panda();
  const Environment at_base = env_file("empty");
  ASSERT_EQ(at_base.obstacles[0].allowed_links, (std::vector<std::string>{"@base"}));
  Environment named = at_base;
  named.obstacles[0].allowed_links = {"panda_link0", "panda_link1"};
  EXPECT_EQ(build_collision_model(robot, at_base).env_pairs,
            build_collision_model(robot, named).env_pairs);
  std::vector<int> allowed = allowed_links_of(robot, at_base.obstacles[0], "empty.json");
  std::sort(allowed.begin(), allowed.end());
  EXPECT_EQ(allowed,
            (std::vector<int>{robot.link_index("panda_link0"), robot.link_index("panda_link1")}));
}

// A small sphere placed at a chosen distance d from the link7 capsule's surface: it collides
// exactly when d is below the margin, and the reported distance is d.
TEST(Collision, NearTouchingRespectsTheMargin) {
  const RobotModel& robot = test::panda();
  Checker probe(robot, Environment{});
  probe.set(kReady);
  const int s = shape_index(probe.model, "link7_a");
  ASSERT_GE(s, 0);
  const Eigen::Isometry3d& t = probe.cd.transform[s];
  const double capsule_radius = 0.04, sphere_radius = 0.01;
  const double margin = robot.geometry.margin;
  ASSERT_GT(margin, 0.002);
  for (double d : {0.0005, margin - 1e-3, margin - 1e-4, margin + 1e-4, margin + 3e-3}) {
    Environment env;
    env.path = "generated";
    Obstacle o;
    o.name = "probe";
    o.shape.type = ShapeType::Sphere;
    o.shape.radius = sphere_radius;
    // Beside the capsule's mid-point, along its local x axis.
    o.pose.p = t.translation() + t.linear().col(0) * (capsule_radius + sphere_radius + d);
    env.obstacles.push_back(o);
    Checker c(robot, env);
    const CollisionReport r = c.report(kReady);
    EXPECT_EQ(r.env_collision, d < margin) << "d = " << d;
    EXPECT_NEAR(min_distance(c.model, c.cd).env_distance, d, 1e-6) << "d = " << d;
  }
}

// Boxes and cylinders of every size and orientation about the arm (the fast check's separating
// test works in an obstacle's own axes), on a floor.
Environment turned_objects(uint64_t seed) {
  Environment env = env_file("empty");
  env.path = "generated";
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 10; ++i) {
    Obstacle o;
    o.name = "object" + std::to_string(i);
    o.shape.type = i % 2 == 0 ? ShapeType::Box : ShapeType::Cylinder;
    o.shape.size = Eigen::Vector3d(0.12 + 0.1 * u(rng), 0.12 + 0.1 * u(rng), 0.12 + 0.1 * u(rng));
    o.shape.radius = 0.06 + 0.05 * u(rng);
    o.shape.length = 0.12 + 0.1 * u(rng);
    o.pose.p = Eigen::Vector3d(0.6 * u(rng), 0.6 * u(rng), 0.5 + 0.4 * u(rng));
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    o.pose.R = Eigen::AngleAxisd(3.14 * u(rng), axis).toRotationMatrix();
    env.obstacles.push_back(o);
  }
  return env;
}

// The fast check (bounding-volume culling, separating axes, inflated shapes, early exit) must
// agree with the exact distances: in collision exactly when some tested pair is closer than the
// margin.
TEST(Collision, FastCheckAgreesWithExactDistances) {
  const RobotModel& panda = test::panda();
  // The Panda's shapes are all capsules: a copy with spheres for its last three.
  RobotModel spheres = panda;
  for (size_t b = spheres.geometry.bodies.size() - 3; b < spheres.geometry.bodies.size(); ++b)
    spheres.geometry.bodies[b].shape.type = ShapeType::Sphere;
  const std::vector<std::tuple<std::string, const RobotModel*, Environment>> scenes = {
      {"table", &panda, env_file("table")},
      {"shelf", &panda, env_file("shelf")},
      {"turned objects", &panda, turned_objects(7)},
      {"turned objects, spheres", &spheres, turned_objects(7)}};
  for (const auto& [name, robot_model, env] : scenes) {
    const RobotModel& robot = *robot_model;
    Checker c(robot, env);
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> u(0, 1);
    int colliding = 0, free = 0, checked = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      JointVector q(robot.dof);
      for (int i = 0; i < robot.dof; ++i)
        q[i] = robot.q_min[i] + u(rng) * (robot.q_max[i] - robot.q_min[i]);
      c.set(q);
      const DistanceReport d = min_distance(c.model, c.cd);
      if (std::abs(d.min() - c.model.margin) < 1e-6) continue;  // too close to call
      const bool fast = in_collision(c.model, c.cd);
      const CollisionReport r = check_collision(c.model, c.cd);
      EXPECT_EQ(fast, d.min() < c.model.margin) << name << " trial " << trial;
      EXPECT_EQ(r.env_collision, d.env_distance < c.model.margin) << name << " trial " << trial;
      EXPECT_EQ(r.self_collision, d.self_distance < c.model.margin) << name << " trial " << trial;
      (fast ? colliding : free)++;
      ++checked;
    }
    // Both outcomes must be well represented for the comparison to mean something.
    EXPECT_GT(colliding, 300) << name;
    EXPECT_GT(free, 300) << name;
  }
}

TEST(Collision, UnknownAllowedLinkInEnvironmentIsAnError) {
  Environment env;
  env.path = "custom.json";
  Obstacle o;
  o.name = "post";
  o.shape.type = ShapeType::Sphere;
  o.shape.radius = 0.1;
  o.allowed_links = {"no_such_link"};
  env.obstacles.push_back(o);
  try {
    build_collision_model(test::panda(), env);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("custom.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("no_such_link"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("@base"), std::string::npos) << "names the way out";
  }
}

// `--env shelf` (a bundled scene by name) works from any folder; a file name that is missing is
// an error, never silently the bundled file of that name; an unknown name lists the bundled.
TEST(Collision, BundledScenesByName) {
  const Environment by_name = load_environment("shelf");
  EXPECT_EQ(by_name.identity, env_file("shelf").identity);
  EXPECT_EQ(std::filesystem::path(by_name.path).filename(), "shelf.json");
  for (const std::string& missing : {std::string("no-such-scene"), std::string("table.json")}) {
    if (std::filesystem::exists(missing)) continue;  // a file of that name here: not a name
    try {
      load_environment(missing);
      ADD_FAILURE() << missing << " was loaded";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(missing + ":", 0), 0u) << message;
      if (missing == "no-such-scene") {
        EXPECT_NE(message.find("empty, shelf, table"), std::string::npos) << message;
      }
    }
  }
}

// The docs' paths ("data/environments/shelf.json") from a folder without data/: the bundled
// file; a path under data/ the bundled data does not have stays an error naming it.
TEST(Collision, TheDocsDataPathsWorkFromAnyFolder) {
  namespace fs = std::filesystem;
  const fs::path here = fs::current_path();
  const fs::path elsewhere = fs::path(test::temp_dir()) / "no-data-here";
  fs::create_directories(elsewhere);
  fs::current_path(elsewhere);
  std::string identity, missing_error;
  try {
    identity = load_environment("data/environments/shelf.json").identity;
    load_environment("data/environments/no-such-scene.json");
  } catch (const Error& e) {
    missing_error = e.what();
  }
  fs::current_path(here);
  EXPECT_EQ(identity, env_file("shelf").identity);
  EXPECT_EQ(missing_error.rfind("data/environments/no-such-scene.json:", 0), 0u) << missing_error;
}

// Robots too: `--robot ur5` is the bundled config; an unknown name lists the bundled robots.
TEST(Collision, BundledRobotsByName) {
  const RobotModel ur5 = load_robot("ur5");
  EXPECT_EQ(std::filesystem::path(ur5.files.config).filename(), "ur5.json");
  EXPECT_EQ(ur5.dof, 6);
  if (std::filesystem::exists("no-such-robot")) return;  // a file of that name here
  try {
    load_robot("no-such-robot");
    ADD_FAILURE() << "no-such-robot was loaded";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("no-such-robot: no such file, nor a bundled robot", 0), 0u) << message;
    EXPECT_NE(message.find("panda, ur5"), std::string::npos) << message;
  }
}

TEST(Collision, DerivedAllowedPairsAreAdjacentLinks) {
  const RobotModel& robot = test::panda();
  const AllowedPairsResult result = derive_allowed_pairs(robot, 2000, 1);
  int adjacent = 0;
  for (const LinkPairStats& p : result.pairs) {
    const int ba = robot.links[p.link_a].body, bb = robot.links[p.link_b].body;
    if (std::abs(ba - bb) <= 1) {
      EXPECT_EQ(p.reason, "adjacent");
      EXPECT_EQ(p.collisions, result.samples);  // the capsules overlap at every joint
      ++adjacent;
    } else {
      EXPECT_TRUE(p.reason.empty())
          << robot.links[p.link_a].name << "-" << robot.links[p.link_b].name;
      EXPECT_LT(p.collisions, result.samples);
    }
  }
  EXPECT_EQ(adjacent, 7);
  // Every derived pair is in the committed config.
  for (const LinkPairStats& p : result.pairs) {
    if (!p.reason.empty()) {
      EXPECT_TRUE(robot.geometry.is_allowed_pair(p.link_a, p.link_b));
    }
  }
}

}  // namespace
}  // namespace lazyboe
