// Loading robot descriptions: the bundled Panda, capsule fusion, and generic chains (prismatic
// joints, fixed links, side branches, a chosen tip) from URDFs written here.
#include <gtest/gtest.h>

#include "lazyboe/common/error.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "test_util.h"

namespace lazyboe {
namespace {

TEST(RobotModel, PandaHasSevenJointsWithPublishedLimits) {
  const RobotModel& robot = test::panda();
  EXPECT_EQ(robot.name, "panda");
  ASSERT_EQ(robot.dof, 7);
  EXPECT_EQ(robot.joints[0].name, "panda_joint1");
  EXPECT_DOUBLE_EQ(robot.q_min[3], -3.0718);
  EXPECT_DOUBLE_EQ(robot.q_max[5], 3.7525);
  EXPECT_DOUBLE_EQ(robot.dq_max[4], 2.61);
  EXPECT_DOUBLE_EQ(robot.ddq_max[1], 7.5);
  EXPECT_DOUBLE_EQ(robot.dddq_max[6], 10000);
  EXPECT_DOUBLE_EQ(robot.tau_max[0], 87);
  EXPECT_DOUBLE_EQ(robot.tau_max[6], 12);
  EXPECT_DOUBLE_EQ(robot.dtau_max[2], 1000);
  EXPECT_EQ(robot.links.size(), 9u);  // link0 .. link8 (the flange)
  EXPECT_EQ(robot.links.back().name, "panda_link8");
  EXPECT_EQ(robot.links.back().body, 6);  // fixed to link7's body
  EXPECT_NEAR(robot.bodies[2].mass, 3.228604, 1e-12);
  EXPECT_NEAR(robot.bodies[3].com.y(), 1.04419e-01, 1e-12);
  EXPECT_GT(robot.geometry.margin, 0.0);
}

TEST(RobotModel, CylinderWithSphereCapsBecomesOneCapsule) {
  const RobotModel& robot = test::panda();
  ASSERT_EQ(robot.geometry.bodies.size(), 10u);  // Franka's ten coarse capsules
  for (const CollisionBody& c : robot.geometry.bodies)
    EXPECT_EQ(c.shape.type, ShapeType::Capsule) << c.name;
  const CollisionBody& link1 = robot.geometry.bodies[1];
  EXPECT_EQ(robot.links[link1.link].name, "panda_link1");
  EXPECT_NEAR(link1.shape.radius, 0.06, 1e-12);
  EXPECT_NEAR(link1.shape.length, 0.283, 1e-12);
  EXPECT_NEAR(link1.in_link.p.z(), -0.1915, 1e-12);
}

// A three-link test arm: revolute, prismatic, revolute, with a fixed sensor and a moving side
// branch (a gripper finger) that is not part of the chain.
const char* kArmUrdf = R"(<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="c"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="sensor"><inertial><origin xyz="0 0 0.02"/><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <link name="finger"><inertial><mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="10"/></joint>
  <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/><origin xyz="0.2 0 0"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.5" velocity="1" effort="10"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0.1 0 0" rpy="1.5707963267948966 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="10"/></joint>
  <joint name="mount" type="fixed"><parent link="c"/><child link="sensor"/><origin xyz="0 0 0.2"/></joint>
  <joint name="grip" type="prismatic"><parent link="c"/><child link="finger"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" velocity="0.1" effort="10"/></joint>
</robot>)";

std::string arm_config(const std::string& extra) {
  return R"({"schema_version": 1, "name": "arm", "urdf": "arm.urdf", )" + extra + R"(
    "joints": [
      {"name": "j1", "max_acceleration": 5, "max_jerk": 100, "max_torque_rate": 1000, "friction": {"model": "none"}},
      {"name": "j2", "max_acceleration": 5, "max_jerk": 100, "max_torque_rate": 1000, "friction": {"model": "none"}},
      {"name": "j3", "max_acceleration": 5, "max_jerk": 100, "max_torque_rate": 1000, "friction": {"model": "none"}}],
    "collision": {"margin": 0.005, "allowed_pairs": [["a", "c"]]}})";
}

TEST(RobotModel, GenericChainWithPrismaticJointAndFixedSensor) {
  test::write_temp_file("arm/arm.urdf", kArmUrdf);
  const RobotModel robot =
      load_robot(test::write_temp_file("arm/tip.json", arm_config(R"("tip_link": "sensor",)")));
  ASSERT_EQ(robot.dof, 3);
  EXPECT_EQ(robot.joints[1].type, JointType::Prismatic);
  EXPECT_EQ(robot.links.back().name, "sensor");
  // The sensor's mass joins link c's body: 1.5 kg with the centre of mass pulled up.
  EXPECT_NEAR(robot.bodies[2].mass, 1.5, 1e-12);
  EXPECT_NEAR(robot.bodies[2].com.z(), 0.5 * 0.22 / 1.5, 1e-12);
  EXPECT_EQ(robot.geometry.bodies.size(), 2u);
  EXPECT_TRUE(robot.geometry.is_allowed_pair(robot.link_index("a"), robot.link_index("c")));
}

TEST(RobotModel, BranchingUrdfNeedsATipLink) {
  test::write_temp_file("arm/arm.urdf", kArmUrdf);
  const std::string message =
      test::robot_load_error(test::write_temp_file("arm/branch.json", arm_config("")));
  EXPECT_NE(message.find("branches at link 'c'"), std::string::npos) << message;
  EXPECT_NE(message.find("tip_link"), std::string::npos) << message;
}

// Found by fuzzing (tests/fuzz/regressions/urdf/): urdfdom accepts joints that form a loop the
// root cannot reach, where walking the chain up from the tip never ended (memory grew until
// std::bad_alloc); and a link that is the child of two joints, which urdfdom links into a
// cycle that is never freed. Both are refused before urdfdom reads the file, naming the joint,
// also when another element comes before <robot> (urdfdom reads the first <robot>, not the
// document's first element: that input leaked too).
TEST(RobotModel, JointLoopsAndLinksWithTwoParentsAreRefused) {
  const std::string j2 = R"(<joint name="j2" type="prismatic"><parent link="a"/>)";
  const std::string j3 = R"(<child link="c"/><origin xyz="0.1 0 0")";
  std::string loop = kArmUrdf, two_parents = kArmUrdf, own_parent = kArmUrdf;
  ASSERT_NE(loop.find(j2), std::string::npos);
  ASSERT_NE(two_parents.find(j3), std::string::npos);
  loop.replace(loop.find(j2), j2.size(), R"(<joint name="j2" type="prismatic"><parent link="c"/>)");
  two_parents.replace(two_parents.find(j3), j3.size(), R"(<child link="a"/><origin xyz="0.1 0 0")");
  own_parent.replace(own_parent.find(j2), j2.size(),
                     R"(<joint name="j2" type="prismatic"><parent link="b"/>)");
  std::string after_a_stray_element = own_parent;
  ASSERT_NE(after_a_stray_element.find("<robot"), std::string::npos);
  after_a_stray_element.insert(after_a_stray_element.find("<robot"), "<collision/>\n");
  for (const auto& [urdf, expected] : std::vector<std::pair<std::string, std::string>>{
           {loop, "the joints form a loop through link '"},
           {two_parents, "joint 'j3': link 'a' is already the child of joint 'j1'"},
           {own_parent, "joint 'j2': link 'b' is its own parent"},
           {after_a_stray_element, "joint 'j2': link 'b' is its own parent"}}) {
    test::write_temp_file("loop/arm.urdf", urdf);
    for (const std::string extra : {"", R"("tip_link": "c",)"}) {
      const std::string message =
          test::robot_load_error(test::write_temp_file("loop/arm.json", arm_config(extra)));
      EXPECT_NE(message.find("arm.urdf:"), std::string::npos) << message;
      EXPECT_NE(message.find(expected), std::string::npos) << message;
    }
  }
}

TEST(RobotModel, MovingSideBranchIsIgnoredAndListed) {
  test::write_temp_file("arm/arm.urdf", kArmUrdf);
  const RobotModel robot =
      load_robot(test::write_temp_file("arm/tip2.json", arm_config(R"("tip_link": "c",)")));
  // The fixed sensor still joins c's body; the finger behind a moving joint is left out.
  EXPECT_NEAR(robot.bodies[2].mass, 1.5, 1e-12);
  ASSERT_EQ(robot.ignored_links.size(), 1u);
  EXPECT_EQ(robot.ignored_links[0], "finger");
}

TEST(RobotModel, ConfigJointsMustMatchTheChain) {
  test::write_temp_file("arm/arm.urdf", kArmUrdf);
  std::string config = arm_config(R"("tip_link": "c",)");
  config.replace(config.find("\"j3\""), 4, "\"j9\"");
  const std::string message =
      test::robot_load_error(test::write_temp_file("arm/badjoint.json", config));
  EXPECT_NE(message.find("joints[2].name"), std::string::npos) << message;
  EXPECT_NE(message.find("j9"), std::string::npos) << message;
}

TEST(RobotModel, DataDirectoryCanBeOverridden) {
  EXPECT_NE(default_robot_path().find("robots/panda.json"), std::string::npos);
  setenv("LAZYBOE_DATA_DIR", "/somewhere/else", 1);
  EXPECT_EQ(default_robot_path(), "/somewhere/else/robots/panda.json");
  unsetenv("LAZYBOE_DATA_DIR");
}

}  // namespace
}  // namespace lazyboe
