// The query and result formats of lazyboe-query: JSON Lines, one query per line
// (schemas/query.schema.json) and one result per line (schemas/result.schema.json).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/registry.h"

namespace lazyboe {

struct Query {
  std::string id;
  int line = 0;
  std::string planner = "lazyboe";  // a name in the planner registry
  ParameterValues parameters;       // the planner's declared parameters the query sets
  PlanningProblem problem;
};

// Defaults for fields a query leaves out. (Planner parameters it leaves out take the planner's
// defaults, theta the bundle's.)
struct QueryDefaults {
  double budget = 5.0;
  double joint_tolerance = 0.1;
  double position_tolerance = 0.02;
};

// Parses one line (the id first, so even a bad query can be answered by id) and validates its
// problem (validate_problem's checks). A query may set any parameter a registered planner
// declares; those its planner does not declare are ignored. Throws Error("line N: field:
// what") for anything malformed, out of range, out of limits or in collision.
Query parse_query(const std::string& text, int line, const RobotModel& robot, const Simulator& sim,
                  SimulatorWorkspace& ws, const QueryDefaults& defaults, std::string& id_out);

enum class TrajectoryOutput { None, Inline, Csv };

// `execution`: the post-processing's figures when the trajectory is post-processed
// (execution.h); null for the raw chain (--raw), whose figures are then the trajectory's own.
nlohmann::json result_json(const Query& q, const PlanResult& r, const Trajectory* trajectory,
                           TrajectoryOutput mode, const std::string& csv_path,
                           const ExecutionStats* execution = nullptr);
nlohmann::json error_json(const std::string& id, int line, const std::string& planner,
                          const std::string& error);

// Writes a trajectory as CSV (t, q1..qn, dq1..dqn, and for a post-processed one
// ddq1..ddqn, cmd1..cmdn).
void write_trajectory_csv(const std::string& path, const Trajectory& trajectory);

}  // namespace lazyboe
