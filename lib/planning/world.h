// The world a query is planned in, apart from the bundle (Pinocchio keeps its GeometryModel apart
// from the Model the same way): an environment, the robot's collision model in it, and the
// simulator over the two. Bundle edges are commands and their dynamics, true in any scene;
// only collisions change with the world, and every planner checks them through this simulator.
//
// A world is made in milliseconds from the session's robot and settings, is read-only once made
// and is shared by threads (hold it by shared_ptr: the simulator refers to its members). A
// SimulatorWorkspace made for one world of a robot serves every world of that robot: its
// collision data holds only the robot's own shapes.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/planning/workspace_index.h"
#include "lazyboe/robot/payload.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

// Which edges of a bundle a new world may block (workspace_index.h): given by the session that
// makes its worlds; returns null when it does not know (no workspace index) or need not (the
// bundle's own scene, whose P_collision the bundle holds).
using EdgeMarker =
    std::function<std::shared_ptr<const EdgeMarks>(const Environment&, const CollisionModel&)>;

// What a query's task adds to the world (issue 29): a payload the arm carries, which changes
// the dynamics every command is simulated with, and end-effector limits every tick is checked
// against. The bundle is not rebuilt: its edges are commands, simulated again in this world
// before any is returned.
struct Task {
  Payload payload;
  EndEffectorLimits end_effector;
  bool any() const { return payload.any() || end_effector.any(); }
};
// A canonical text of the task; empty for none.
std::string task_identity(const Task& task);
// What a world of this scene and task is kept by: the scene's identity, then the task's.
std::string world_identity(const std::string& env_identity, const Task& task);

class PlanningWorld {
 public:
  // Throws Error (naming the environment) when it names a link the robot does not have.
  PlanningWorld(const RobotModel& robot, Environment environment, const SimulationOptions& options,
                const EdgeMarker& marker = {}, const Task& task = {});
  PlanningWorld(const PlanningWorld&) = delete;  // the simulator refers to members
  PlanningWorld& operator=(const PlanningWorld&) = delete;

  const Task task;
  const RobotModel robot;  // the session's robot, carrying the task's payload
  const Environment env;
  // The environment's identity and the task's: what the session's scene cache keeps it by.
  const std::string identity;
  const CollisionModel collision;
  const Simulator sim;
  // The bundle edges this world may block, for the planners' collision prior; null: none known.
  const std::shared_ptr<const EdgeMarks> edge_marks;
};

using WorldPtr = std::shared_ptr<const PlanningWorld>;

}  // namespace lazyboe
