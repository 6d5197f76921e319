// `lazyboe-robot init` (issue 28, item 3) and the shipped UR5 (item 5): the config init writes
// from the UR5's URDF is the one shipped, and info, check, build, perturb and query accept it
// with no edits, in every bundled environment; the gains init computes track a velocity step on
// every joint; an SRDF gives the chain and its disabled pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/sim/random.h"
#include "lazyboe/sim/robot_setup.h"
#include "test_util.h"

namespace lazyboe {
namespace {

const std::string kInit = " init --urdf " + test::source_path("data/robots/ur5/ur5.urdf") +
                          " --package-path " + test::source_path("data/robots/ur5") +
                          " --tip-link tool0 --name ur5 --convex-links upper_arm_link";

TEST(RobotInit, WritesTheShippedUr5ConfigAndItsGainsTrackEveryJoint) {
  const std::string out = test::temp_dir() + "/ur5.json";
  const test::CommandResult r =
      test::run(test::tool_path("lazyboe-robot") + kInit + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("<- check"), std::string::npos) << r.err;  // every step tracked
  EXPECT_NE(r.err.find("velocity step on elbow_joint"), std::string::npos) << r.err;
  nlohmann::json written = nlohmann::json::parse(test::read_file(out));
  nlohmann::json shipped =
      nlohmann::json::parse(test::read_file(test::source_path("data/robots/ur5.json")));
  for (const char* path_field : {"urdf", "package_path"}) {  // relative to each config's folder
    written.erase(path_field);
    shipped.erase(path_field);
  }
  EXPECT_EQ(written, shipped) << "data/robots/ur5.json is not what init writes: run it again";
}

// An unknown --meshes is one line naming the option and the three representations.
TEST(RobotInit, AnUnknownMeshRepresentationIsOneLine) {
  const std::string out = test::temp_dir() + "/round.json";
  const test::CommandResult r =
      test::run(test::tool_path("lazyboe-robot") + kInit + " --meshes round --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--meshes: unknown mesh representation 'round' (expected fitted, exact or "
                       "convex)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;  // one line
}

TEST(RobotInit, TheUr5IsAcceptedByEveryToolInEveryBundledEnvironment) {
  const std::string robot = " --robot " + test::source_path("data/robots/ur5.json");
  const std::string dir = test::temp_dir();
  EXPECT_EQ(test::run(test::tool_path("lazyboe-robot") + " info" + robot).exit_code, 0);
  test::write_temp_file("ur5-q.csv", "q1,q2,q3,q4,q5,q6\n0.5,-1.2,1.0,-1.4,-1.57,0\n");
  for (const char* env : {"table", "shelf", "empty"}) {
    const test::CommandResult r =
        test::run(test::tool_path("lazyboe-robot") + " check" + robot + " --env " + env + " --in " +
                  dir + "/ur5-q.csv --out " + dir + "/ur5-" + env + ".csv");
    EXPECT_EQ(r.exit_code, 0) << env << ": " << r.err;
  }
  const std::string bundle = dir + "/ur5.h5";
  const test::CommandResult build =
      test::run(test::watchdog(120) + test::tool_path("lazyboe-build") + robot +
                " --edges 150 --threads 2 --quiet --out " + bundle);
  ASSERT_EQ(build.exit_code, 0) << build.err;
  const test::CommandResult perturb =
      test::run(test::watchdog(120) + test::tool_path("lazyboe-perturb") + " --bundle " + bundle +
                " --perturbations 2 --quiet");
  ASSERT_EQ(perturb.exit_code, 0) << perturb.err;
  test::write_temp_file(
      "ur5-q.jsonl",
      R"({"id": "over-the-table", "start": [0.5, -1.2, 1.0, -1.4, -1.57, 0], "goal": {"q": [-0.5, -1.0, 0.8, -1.4, -1.57, 0.5], "tolerance": 0.3}, "planner": "lazysp", "budget": 5.0, "seed": 1})"
      "\n");
  const test::CommandResult query =
      test::run(test::watchdog(60) + test::tool_path("lazyboe-query") + " --bundle " + bundle +
                " --queries " + dir + "/ur5-q.jsonl --out " + dir + "/ur5-r.jsonl --quiet");
  ASSERT_EQ(query.exit_code, 0) << query.err;
  const nlohmann::json result = nlohmann::json::parse(test::read_file(dir + "/ur5-r.jsonl"));
  EXPECT_TRUE(result.at("success").get<bool>()) << result.dump();
}

// A two-link arm with an SRDF naming a group's chain and a disabled pair.
TEST(RobotInit, AnSrdfGivesTheChainAndItsDisabledPairs) {
  test::write_temp_file("srdf/arm.urdf", R"(<?xml version="1.0"?>
<robot name="arm">
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision></link>
  <link name="b"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0.15 0 0"/><geometry><sphere radius="0.03"/></geometry></collision></link>
  <link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="2" effort="50"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="2" effort="50"/></joint>
  <joint name="j3" type="fixed"><parent link="b"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
</robot>)");
  const std::string srdf = test::write_temp_file("srdf/arm.srdf", R"(<?xml version="1.0"?>
<robot name="arm">
  <group name="hand"><link name="tool"/></group>
  <group name="arm"><chain base_link="base" tip_link="b"/></group>
  <group_state name="home" group="arm"><joint name="j1" value="0"/></group_state>
  <disable_collisions link1="base" link2="b" reason="Never"/>
  <disable_collisions link1="base" link2="elsewhere" reason="Never"/>
</robot>)");
  RobotSetupOptions o;
  o.urdf_path = test::temp_dir() + "/srdf/arm.urdf";
  o.srdf_path = srdf;
  o.out_path = test::temp_dir() + "/srdf/arm.json";
  o.pair_samples = 500;
  const RobotSetup setup = make_robot_config(o);
  EXPECT_EQ(setup.config.at("tip_link"), "b");
  EXPECT_EQ(setup.config.at("joints").size(), 2u);
  const nlohmann::json pairs = setup.config.at("collision").at("allowed_pairs");
  EXPECT_NE(std::find(pairs.begin(), pairs.end(), nlohmann::json({"base", "b"})), pairs.end())
      << pairs.dump();
  for (const StepCheck& s : setup.steps) EXPECT_TRUE(s.passed()) << s.joint;
  o.srdf_group = "hand";
  try {
    make_robot_config(o);
    ADD_FAILURE() << "a group without a chain was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("group 'hand' has no <chain>"), std::string::npos)
        << e.what();
  }
}

// The gains' feed-forward and the step check use a configuration of typical inertia: for the
// UR5 its mass-matrix diagonal is nearer the per-joint medians over the joint limits (drawn here
// with another seed; distance in log) than 90% of the drawn configurations are, where the
// middle of the limits (the arm stretched out) puts the shoulder's M_ii above its 90th
// percentile; and the shipped ka is M_ii there (to init's 3 significant digits).
TEST(RobotInit, GainsAndStepsUseAConfigurationOfTypicalInertia) {
  const RobotModel robot = load_robot(test::source_path("data/robots/ur5.json"));
  RobotModel whole = robot;  // init samples the joint limits
  whole.region = {robot.q_min, robot.q_max};
  const JointVector typical = typical_inertia_configuration(whole, 1, 1000);
  RobotData data(robot);
  const int n = robot.dof;
  std::vector<JointVector> logs;
  Random rng(77, 0);
  JointVector q(n);
  for (int s = 0; s < 2000; ++s) {
    for (int i = 0; i < n; ++i) q[i] = rng.uniform(robot.q_min[i], robot.q_max[i]);
    logs.push_back(mass_matrix(robot, data, q).diagonal().array().log().matrix());
  }
  JointVector median(n);
  std::vector<double> column(logs.size());
  for (int i = 0; i < n; ++i) {
    for (size_t s = 0; s < logs.size(); ++s) column[s] = logs[s][i];
    std::sort(column.begin(), column.end());
    median[i] = column[column.size() / 2];
    if (i == 0) {
      const JointVector middle = (robot.q_min + robot.q_max) / 2;
      EXPECT_GT(std::log(mass_matrix(robot, data, middle)(0, 0)), column[column.size() * 9 / 10])
          << "the middle of the limits is not typical";
    }
  }
  const JointVector at_typical = mass_matrix(robot, data, typical).diagonal();
  const double distance = (at_typical.array().log().matrix() - median).norm();
  size_t nearer = 0;
  for (const JointVector& l : logs) nearer += (l - median).norm() < distance;
  EXPECT_LT(nearer, logs.size() / 10) << "distance " << distance;
  for (int i = 0; i < n; ++i)
    EXPECT_NEAR(robot.controller.ka[i], at_typical[i], 0.005 * at_typical[i])
        << robot.joints[i].name;
}

}  // namespace
}  // namespace lazyboe
