#include "lazyboe/planning/world.h"

#include <cstdio>

namespace lazyboe {

std::string task_identity(const Task& task) {
  std::string text = payload_identity(task.payload);
  const EndEffectorLimits& e = task.end_effector;
  if (!e.any()) return text;
  char limits[400];
  std::snprintf(limits, sizeof limits, "%send_effector %d %.17g %.17g %.17g [%.17g %.17g %.17g]",
                text.empty() ? "" : "\n", e.link, e.max_linear_speed, e.max_linear_acceleration,
                e.max_tilt, e.axis.x(), e.axis.y(), e.axis.z());
  return text + limits;
}

std::string world_identity(const std::string& env_identity, const Task& task) {
  return task.any() ? env_identity + "\n" + task_identity(task) : env_identity;
}

PlanningWorld::PlanningWorld(const RobotModel& bundle_robot, Environment environment,
                             const SimulationOptions& options, const EdgeMarker& marker,
                             const Task& world_task)
    : task(world_task),
      robot(with_payload(bundle_robot, task.payload)),
      env(std::move(environment)),
      identity(world_identity(env.identity, task)),
      collision(build_collision_model(robot, env)),
      sim(robot, collision, options, task.end_effector),
      edge_marks(marker ? marker(env, collision) : nullptr) {}

}  // namespace lazyboe
