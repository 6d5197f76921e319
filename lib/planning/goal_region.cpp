// Configurations inside pose goals and goal sets (resolve_goal, problem.h).
#include <algorithm>

#include "lazyboe/planning/problem.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {

namespace {

// Attempts of inverse kinematics per pose goal, and the configurations kept (enough for a
// direct command and the growth's goal bias; more only cost time).
constexpr int kIkAttempts = 48;
constexpr int kKeptConfigurations = 6;

// Seeds: the start, then random configurations, the first half in the robot's region (where the
// bundle is), the rest within the joint limits.
void ik_seed(const RobotModel& robot, const JointVectorRef& start, int attempt, Random& rng,
             JointVector& q) {
  if (attempt == 0) {
    q = start;
    return;
  }
  const bool in_region = attempt < kIkAttempts / 2;
  for (int i = 0; i < robot.dof; ++i) {
    q[i] = in_region ? rng.uniform(robot.region_lower[i], robot.region_upper[i])
                     : rng.uniform(robot.q_min[i], robot.q_max[i]);
  }
}

void resolve_pose(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                  uint64_t seed, Goal& goal) {
  const RobotModel& robot = sim.robot;
  const PoseTarget target = goal.pose_target();
  Random rng(seed, 0x9e3779b97f4a7c15ULL);
  JointVector q(robot.dof);
  for (int a = 0; a < kIkAttempts; ++a) {
    if (static_cast<int>(goal.configurations.size()) >= kKeptConfigurations) break;
    ik_seed(robot, start, a, rng, q);
    ++goal.attempts;
    if (!solve_ik(robot, ws.robot, target, q)) continue;
    ++goal.reached;
    if (check_state(sim, ws, q) == RolloutStatus::Valid) goal.configurations.push_back(q);
  }
}

}  // namespace

bool needs_configurations(const Goal& goal) {
  return goal.kind == Goal::Kind::Pose || goal.kind == Goal::Kind::Set;
}

void resolve_goal(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                  uint64_t seed, Goal& goal) {
  goal.configurations.clear();
  goal.reached = goal.attempts = 0;
  if (goal.kind == Goal::Kind::Pose) resolve_pose(sim, ws, start, seed, goal);
  for (Goal& m : goal.members) {
    if (m.kind == Goal::Kind::Joint) {
      if (check_state(sim, ws, m.q) == RolloutStatus::Valid) goal.configurations.push_back(m.q);
      continue;
    }
    if (m.kind == Goal::Kind::Pose) resolve_goal(sim, ws, start, seed, m);
    goal.configurations.insert(goal.configurations.end(), m.configurations.begin(),
                               m.configurations.end());
  }
  std::stable_sort(goal.configurations.begin(), goal.configurations.end(),
                   [&](const JointVector& a, const JointVector& b) {
                     return (a - start).norm() < (b - start).norm();
                   });
  goal.resolved = true;
}

}  // namespace lazyboe
