// The worlds one session plans in: its default (the bundle's own scene, or the one given at
// start) and those queries name, by environment file or inline. Worlds are kept by content
// (Environment::identity: the parsed scene, so whitespace or key order do not count), so a
// scene named by many queries has its collision model built once; the most recently used
// `capacity` are kept, a world in use stays alive with its holders. Thread-safe.
#pragma once

#include <list>
#include <mutex>
#include <string>

#include "lazyboe/common/json_fields.h"
#include "lazyboe/planning/end_pose_index.h"
#include "lazyboe/planning/world.h"

namespace lazyboe {

class SceneCache {
 public:
  // `marker`: how each new world learns the edges it may block (world.h). `goal_coverage`: the
  // session's end-pose indexes, which seed the inverse kinematics of pose goals in every world
  // (read_query); null: none.
  SceneCache(const RobotModel& robot, const SimulationOptions& options, WorldPtr default_world,
             EdgeMarker marker = {}, const EndPoseIndexes* goal_coverage = nullptr,
             size_t capacity = 16);

  const WorldPtr& default_world() const { return default_world_; }
  const EndPoseIndexes* goal_coverage() const { return goal_coverage_; }
  // The world of an environment file (errors name the file and field).
  WorldPtr load(const std::string& path);
  // The world of an environment object held in memory (a query's inline "scene").
  WorldPtr inline_scene(const JsonField& scene);
  // The world of a parsed environment.
  WorldPtr world(Environment env);
  // `base`'s scene with a query's task (payload, end-effector limits); `base` itself for none.
  // It shares `base`'s edge marks (they depend on the scene alone).
  WorldPtr with_task(const WorldPtr& base, const Task& task);

 private:
  WorldPtr find(const std::string& identity);  // moved to the front; null if not kept (locked)
  WorldPtr keep(WorldPtr made);                // the kept world of made's identity (locked)

  const RobotModel& robot_;
  const SimulationOptions options_;
  const WorldPtr default_world_;
  const EdgeMarker marker_;
  const EndPoseIndexes* const goal_coverage_;
  const size_t capacity_;
  std::mutex mutex_;
  std::list<WorldPtr> recent_;  // most recently used first
};

}  // namespace lazyboe
