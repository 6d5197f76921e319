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
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

// Which edges of a bundle a new world may block (workspace_index.h): given by the session that
// makes its worlds; returns null when it does not know (no workspace index) or need not (the
// bundle's own scene, whose P_collision the bundle holds).
using EdgeMarker =
    std::function<std::shared_ptr<const EdgeMarks>(const Environment&, const CollisionModel&)>;

class PlanningWorld {
 public:
  // Throws Error (naming the environment) when it names a link the robot does not have.
  PlanningWorld(const RobotModel& robot, Environment environment, const SimulationOptions& options,
                const EdgeMarker& marker = {});
  PlanningWorld(const PlanningWorld&) = delete;  // the simulator refers to members
  PlanningWorld& operator=(const PlanningWorld&) = delete;

  const Environment env;
  const CollisionModel collision;
  const Simulator sim;
  // The bundle edges this world may block, for the planners' collision prior; null: none known.
  const std::shared_ptr<const EdgeMarks> edge_marks;
};

using WorldPtr = std::shared_ptr<const PlanningWorld>;

}  // namespace lazyboe
