#include "lazyboe/planning/world.h"

namespace lazyboe {

PlanningWorld::PlanningWorld(const RobotModel& robot, Environment environment,
                             const SimulationOptions& options, const EdgeMarker& marker)
    : env(std::move(environment)),
      collision(build_collision_model(robot, env)),
      sim(robot, collision, options),
      edge_marks(marker ? marker(env, collision) : nullptr) {}

}  // namespace lazyboe
