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

// `count` problems with start and goal uniform in [lower, upper], both valid (within the joint
// limits, free of self- and environment collision) and farther apart than `tolerance` (a
// joint-space goal region of that radius). Deterministic for a seed.
std::vector<BenchProblem> sample_problems(const Simulator& sim, SimulatorWorkspace& ws,
                                          const JointVector& lower, const JointVector& upper,
                                          int count, double tolerance, uint64_t seed);

// Problems from a JSON Lines file in the query format (schemas/query.schema.json); planner,
// budget and seed fields are ignored. Throws Error naming the file and line of a bad query.
std::vector<BenchProblem> read_problems(const std::string& path, const Simulator& sim,
                                        SimulatorWorkspace& ws, const QueryDefaults& defaults);

// Writes problems in the query format (temporary file and rename).
void write_problems(const std::string& path, const RobotModel& robot,
                    const std::vector<BenchProblem>& problems);

}  // namespace lazyboe
