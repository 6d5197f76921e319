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

#include <memory>
#include <string>

#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

class PlanningWorld {
 public:
  // Throws Error (naming the environment) when it names a link the robot does not have.
  PlanningWorld(const RobotModel& robot, Environment environment, const SimulationOptions& options);
  PlanningWorld(const PlanningWorld&) = delete;  // the simulator refers to members
  PlanningWorld& operator=(const PlanningWorld&) = delete;

  const Environment env;
  const CollisionModel collision;
  const Simulator sim;
};

using WorldPtr = std::shared_ptr<const PlanningWorld>;

}  // namespace lazyboe
