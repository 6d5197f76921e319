#include "lazyboe/planning/world.h"

namespace lazyboe {

PlanningWorld::PlanningWorld(const RobotModel& robot, Environment environment,
                             const SimulationOptions& options)
    : env(std::move(environment)),
      collision(build_collision_model(robot, env)),
      sim(robot, collision, options) {}

}  // namespace lazyboe
