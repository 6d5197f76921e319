// URDF `continuous` joints (issue 28, item 2): loaded as revolute joints planned within the
// config's position_range (default [-2 pi, 2 pi]); a range on any other joint, a continuous
// joint without <limit>, or a bad range is one error naming the field; a query whose goal lies
// beyond +-pi on the continuous joint is planned through, and its executable trajectory passes
// the trajectory checker (what `lazyboe-robot validate-trajectory` runs).
#include <gtest/gtest.h>

#include <string>

#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/request.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/trajectory_check.h"
#include "test_util.h"

namespace lazyboe {
namespace {

// Two links turning about z (the second continuous) and a forearm out to the side.
const char* kUrdf = R"(<?xml version="1.0"?>
<robot name="turner">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0.15 0 0"/><geometry><sphere radius="0.03"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="2" effort="50"/></joint>
  <joint name="j2" type="continuous"><parent link="a"/><child link="b"/><origin xyz="0 0 0.2"/>
    <axis xyz="0 0 1"/><limit velocity="3" effort="50"/></joint>
</robot>)";

std::string config(const std::string& j1_extra, const std::string& j2_extra) {
  return R"({"schema_version": 1, "name": "turner", "urdf": "turner.urdf",
    "joints": [
      {"name": "j1", "max_acceleration": 10, "max_jerk": 500, "max_torque_rate": 5000,
       "friction": {"model": "none"})" +
         j1_extra + R"(},
      {"name": "j2", "max_acceleration": 10, "max_jerk": 500, "max_torque_rate": 5000,
       "friction": {"model": "none"})" +
         j2_extra + R"(}],
    "controller": {"type": "velocity_tracking", "kv": [3.5, 1.0], "ka": [0.07, 0.02],
                   "friction_feedforward": false},
    "collision": {"margin": 0.005, "allowed_pairs": []}})";
}

TEST(ContinuousJoint, LoadsWithTheDefaultRangeOrTheConfigs) {
  test::write_temp_file("turner/turner.urdf", kUrdf);
  const RobotModel plain = load_robot(test::write_temp_file("turner/plain.json", config("", "")));
  ASSERT_EQ(plain.dof, 2);
  EXPECT_FALSE(plain.joints[0].continuous);
  EXPECT_TRUE(plain.joints[1].continuous);
  EXPECT_EQ(plain.joints[1].type, JointType::Revolute);
  EXPECT_STREQ(joint_type_name(plain.joints[1]), "continuous");
  EXPECT_DOUBLE_EQ(plain.q_min[1], -kContinuousRange);
  EXPECT_DOUBLE_EQ(plain.q_max[1], kContinuousRange);
  const RobotModel ranged = load_robot(
      test::write_temp_file("turner/ranged.json", config("", R"(, "position_range": [-4, 5])")));
  EXPECT_DOUBLE_EQ(ranged.q_min[1], -4);
  EXPECT_DOUBLE_EQ(ranged.q_max[1], 5);
}

TEST(ContinuousJoint, BadRangesAndMissingLimitsAreOneLineErrors) {
  test::write_temp_file("turner/turner.urdf", kUrdf);
  const std::string on_revolute = test::robot_load_error(
      test::write_temp_file("turner/r1.json", config(R"(, "position_range": [-1, 1])", "")));
  EXPECT_NE(on_revolute.find("position_range"), std::string::npos) << on_revolute;
  EXPECT_NE(on_revolute.find("only a continuous joint"), std::string::npos) << on_revolute;
  for (const std::string bad : {R"([3, -3])", R"([1])", R"("wide")", R"([0, 1e9])"}) {
    const std::string message = test::robot_load_error(
        test::write_temp_file("turner/bad.json", config("", R"(, "position_range": )" + bad)));
    EXPECT_NE(message.find("position_range"), std::string::npos) << bad << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  std::string urdf = kUrdf;
  const std::string limit = R"(<limit velocity="3" effort="50"/>)";
  urdf.replace(urdf.find(limit), limit.size(), "");
  test::write_temp_file("nolimit/turner.urdf", urdf);
  const std::string message =
      test::robot_load_error(test::write_temp_file("nolimit/turner.json", config("", "")));
  EXPECT_NE(message.find("j2"), std::string::npos) << message;
  EXPECT_NE(message.find("limit"), std::string::npos) << message;
}

// From j2 = -2.5 to j2 = 3.8 rad: through and beyond +-pi, one turn and a sixth.
TEST(ContinuousJoint, AGoalBeyondPiIsPlannedThroughAndTheTrajectoryPassesTheChecker) {
  test::write_temp_file("turner/turner.urdf", kUrdf);
  const RobotModel robot = load_robot(test::write_temp_file("turner/plan.json", config("", "")));
  const Environment empty;
  const CollisionModel collision = build_collision_model(robot, empty);
  const Simulator sim(robot, collision, SimulationOptions());
  PlanningContext context(sim);
  context.sample_lower = robot.q_min;
  context.sample_upper = robot.q_max;
  SimulatorWorkspace ws(sim);
  for (const std::string planner : {"rrt", "sst"}) {
    SCOPED_TRACE(planner);
    PlanRequest request;
    request.planner = planner;
    request.problem.start = (JointVector(2) << 0.2, -2.5).finished();
    request.problem.goal.q = (JointVector(2) << -0.1, 3.8).finished();
    request.problem.goal.tolerance = 0.1;
    request.problem.termination.budget = 20 * test::time_scale();
    request.problem.termination.stop_at_first = true;
    request.output.sample_interval = sim.dt;  // every control tick, for the checker
    const PlanAnswer a = answer_request(context, request, ws);
    ASSERT_TRUE(a.result.success) << a.result.failure;
    double highest = -1e9;
    for (const JointVector& q : a.trajectory.q) highest = std::max(highest, q[1]);
    EXPECT_GT(highest, 3.7);
    std::vector<double> q, dq;
    for (size_t k = 0; k < a.trajectory.q.size(); ++k) {
      q.insert(q.end(), a.trajectory.q[k].data(), a.trajectory.q[k].data() + 2);
      dq.insert(dq.end(), a.trajectory.dq[k].data(), a.trajectory.dq[k].data() + 2);
    }
    const TrajectoryChecker checker(robot, collision);
    TrajectoryCheckWorkspace cws(checker);
    const TrajectoryView view{static_cast<int>(a.trajectory.t.size()), 2, a.trajectory.t.data(),
                              q.data(), dq.data()};
    const TrajectoryCheckResult r = check_trajectory(checker, cws, view);
    EXPECT_TRUE(r.valid) << describe_violation(checker, r.violation);
  }
}

}  // namespace
}  // namespace lazyboe
