// The planning problems of a study: pairs of collision-free random start and goal
// configurations in a box (the bundle's sampling region), as in the paper's evaluation, or the
// problems of an earlier study read back from its problems.jsonl (query format).
#pragma once

#include <string>
#include <vector>

#include "lazyboe/io/query_io.h"

namespace lazyboe {

struct BenchProblem {
  std::string id;
  JointVector start;
  Goal goal;
};

// How drawn problems give their goals: a joint-space region around the goal configuration, or
// the pose of the tip there (docs/task.md), its configurations found with `coverage`.
struct ProblemGoals {
  bool pose = false;
  double position_tolerance = 0.01, orientation_tolerance = 0.05;  // m, rad
  const EndPoseIndexes* coverage = nullptr;
};

// `count` problems with start and goal uniform in [lower, upper], both valid (within the joint
// limits, free of self- and environment collision) and farther apart than `tolerance` (a
// joint-space goal region of that radius; with goals.pose, the tip pose at the goal
// configuration instead, drawn again when its inverse kinematics finds no valid configuration).
// For a seed, pose goals are at the configurations of the joint goals, but for those redrawn.
std::vector<BenchProblem> sample_problems(const Simulator& sim, SimulatorWorkspace& ws,
                                          const JointVector& lower, const JointVector& upper,
                                          int count, double tolerance, uint64_t seed,
                                          const ProblemGoals& goals = {});

// Problems from a JSON Lines file in the query format (schemas/query.schema.json); planner and
// budget fields are ignored (a seed only seeds a pose goal's inverse kinematics), and a scene or
// a task is refused (a study plans in one world: lazyboe-bench --env, --payload,
// --end-effector-limits). Pose goals are resolved with `coverage`, as drawn ones are. Throws
// Error naming the file and line of a bad query.
std::vector<BenchProblem> read_problems(const std::string& path, const Simulator& sim,
                                        SimulatorWorkspace& ws, const QueryDefaults& defaults,
                                        const EndPoseIndexes* coverage = nullptr);

// Writes problems in the query format (temporary file and rename).
void write_problems(const std::string& path, const RobotModel& robot,
                    const std::vector<BenchProblem>& problems);

}  // namespace lazyboe
