// Configurations inside pose goals and goal sets (resolve_goal, problem.h).
#include <algorithm>

#include "lazyboe/planning/end_pose_index.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {

namespace {

// Attempts of inverse kinematics per pose goal, of them at most kCoverageSeeds from the bundle's
// edge ends, and the configurations kept (enough for a direct command and the growth's goal
// bias; more only cost time).
constexpr int kIkAttempts = 48;
constexpr size_t kCoverageSeeds = 16;
constexpr int kKeptConfigurations = 6;

// Seeds: the start; the end states of the edges ending nearest the goal pose (configurations the
// bundle reaches, so the solutions it finds from them are too); then random configurations, the
// first half in the robot's region (where the bundle is), the rest within the joint limits.
void ik_seed(const RobotModel& robot, const JointVectorRef& start, const EndPoseIndex* ends,
             const std::vector<uint32_t>& near, int attempt, Random& rng, JointVector& q) {
  if (attempt == 0) {
    q = start;
    return;
  }
  const size_t covered = static_cast<size_t>(attempt - 1);
  if (covered < near.size()) {
    q = Eigen::Map<const JointVector>(ends->end_state(near[covered]), robot.dof);
    return;
  }
  const int random = attempt - 1 - static_cast<int>(near.size());
  const bool in_region = random < (kIkAttempts - 1 - static_cast<int>(near.size())) / 2;
  for (int i = 0; i < robot.dof; ++i) {
    q[i] = in_region ? rng.uniform(robot.region.lower[i], robot.region.upper[i])
                     : rng.uniform(robot.q_min[i], robot.q_max[i]);
  }
}

void resolve_pose(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                  uint64_t seed, const EndPoseIndexes* coverage, Goal& goal) {
  const RobotModel& robot = sim.robot;
  const PoseTarget target = goal.pose_target();
  const EndPoseIndex* ends = coverage ? &coverage->of(target.link) : nullptr;
  std::vector<uint32_t> near;
  if (ends) ends->nearest(target, kCoverageSeeds, near);
  Random rng(seed, 0x9e3779b97f4a7c15ULL);
  JointVector q(robot.dof);
  for (int a = 0; a < kIkAttempts; ++a) {
    if (static_cast<int>(goal.configurations.size()) >= kKeptConfigurations) break;
    ik_seed(robot, start, ends, near, a, rng, q);
    ++goal.attempts;
    if (!solve_ik(robot, ws.robot, target, q)) continue;
    ++goal.reached;
    const RolloutStatus status = check_state(sim, ws, q);
    if (status == RolloutStatus::Valid) goal.configurations.push_back(q);
    if (status == RolloutStatus::EndEffectorTilt) ++goal.tilted;
  }
}

}  // namespace

bool needs_configurations(const Goal& goal) {
  return goal.kind == Goal::Kind::Pose || goal.kind == Goal::Kind::Set;
}

void resolve_goal(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                  uint64_t seed, Goal& goal, const EndPoseIndexes* coverage) {
  goal.configurations.clear();
  goal.reached = goal.attempts = goal.tilted = 0;
  if (goal.kind == Goal::Kind::Pose) resolve_pose(sim, ws, start, seed, coverage, goal);
  for (Goal& m : goal.members) {
    if (m.kind == Goal::Kind::Joint) {
      if (check_state(sim, ws, m.q) == RolloutStatus::Valid) goal.configurations.push_back(m.q);
      continue;
    }
    if (m.kind == Goal::Kind::Pose) resolve_goal(sim, ws, start, seed, m, coverage);
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
