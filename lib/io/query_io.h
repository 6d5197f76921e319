// The query and result formats of lazyboe-query: JSON Lines, one query per line
// (schemas/query.schema.json) and one result per line (schemas/result.schema.json).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/planning/request.h"
#include "lazyboe/planning/scene_cache.h"

namespace lazyboe {

struct Query {
  std::string id;
  int line = 0;
  PlanRequest request;
  // The scene it names ("scene": a file or an inline environment) with the query's task
  // (payload, end-effector limits); null: the caller's default.
  WorldPtr world;
};

// Defaults for fields a query leaves out. (Planner parameters it leaves out take the planner's
// defaults, theta the bundle's.)
struct QueryDefaults {
  double budget = 5.0;
  double joint_tolerance = 0.1;
  double position_tolerance = 0.02;
  double pose_position_tolerance = 0.01;  // m, of a pose goal
  double orientation_tolerance = 0.05;    // rad, of a pose goal
  ReturnOptions output;  // raw, sample_interval, shortcut_attempts (a tool's flags)
};

// Parses one line (the id first, so even a bad query can be answered by id) and validates its
// problem (validate_problem's checks) in its world: the scene it names, resolved through
// `scenes` (null: naming one is an error), or else `sim`'s. A query may set only parameters its
// planner declares. Throws Error("line N: field: what") for anything malformed, out of range,
// out of limits or in collision.
// `coverage`: the bundle's end poses for a pose goal's inverse kinematics when there are no
// `scenes` (whose goal_coverage() serves otherwise).
Query parse_query(const std::string& text, int line, const Simulator& sim, SimulatorWorkspace& ws,
                  const QueryDefaults& defaults, std::string& id_out, SceneCache* scenes = nullptr,
                  const EndPoseIndexes* coverage = nullptr);
// The same for a query held as JSON; `where` starts its errors ("line 3", "queries[2]"; empty:
// the field alone). `base`: the caller's world when it is not the session's default (`sim` is
// its simulator): a query's task (payload, end-effector limits) is added to it.
Query read_query(const nlohmann::json& doc, const std::string& where, const Simulator& sim,
                 SimulatorWorkspace& ws, const QueryDefaults& defaults,
                 SceneCache* scenes = nullptr, const WorldPtr& base = nullptr,
                 const EndPoseIndexes* coverage = nullptr);

enum class TrajectoryOutput { None, Inline, Csv };

// The result line of an answered query planned in `world`: the trajectory inline, as a CSV
// file's name (csv_path) or not at all, with the post-processing's figures unless it is raw.
nlohmann::json result_json(const Query& q, const PlanAnswer& a, const PlanningWorld& world,
                           TrajectoryOutput mode, const std::string& csv_path);
nlohmann::json error_json(const std::string& id, int line, const std::string& planner,
                          const std::string& error);

// Writes a trajectory as CSV (t, q1..qn, dq1..dqn, and for a post-processed one
// ddq1..ddqn, cmd1..cmdn).
void write_trajectory_csv(const std::string& path, const Trajectory& trajectory);

}  // namespace lazyboe
