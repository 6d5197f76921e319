#include "lazyboe/planning/scene_cache.h"

namespace lazyboe {

SceneCache::SceneCache(const RobotModel& robot, const SimulationOptions& options,
                       WorldPtr default_world, EdgeMarker marker,
                       const EndPoseIndexes* goal_coverage, size_t capacity)
    : robot_(robot),
      options_(options),
      default_world_(std::move(default_world)),
      marker_(std::move(marker)),
      goal_coverage_(goal_coverage),
      capacity_(capacity) {}

WorldPtr SceneCache::load(const std::string& path) { return world(load_environment(path)); }

WorldPtr SceneCache::inline_scene(const JsonField& scene) {
  return world(environment_from_json(scene, ""));
}

WorldPtr SceneCache::find(const std::string& identity) {
  for (auto it = recent_.begin(); it != recent_.end(); ++it) {
    if ((*it)->identity != identity) continue;
    recent_.splice(recent_.begin(), recent_, it);
    return recent_.front();
  }
  return nullptr;
}

WorldPtr SceneCache::world(Environment env) {
  if (env.identity == default_world_->env.identity) return default_world_;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (WorldPtr known = find(env.identity)) return known;
  }
  // Built outside the lock (FCL's geometry can take milliseconds); of two threads that built
  // one new scene at once, the first to come back is kept and given to both.
  return keep(std::make_shared<const PlanningWorld>(robot_, std::move(env), options_, marker_));
}

WorldPtr SceneCache::with_task(const WorldPtr& base, const Task& task) {
  if (!task.any()) return base;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (WorldPtr known = find(world_identity(base->env.identity, task))) return known;
  }
  const auto marks = base->edge_marks;
  const EdgeMarker same = [marks](const Environment&, const CollisionModel&) { return marks; };
  return keep(std::make_shared<const PlanningWorld>(robot_, base->env, options_, same, task));
}

WorldPtr SceneCache::keep(WorldPtr made) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (WorldPtr known = find(made->identity)) return known;
  recent_.push_front(made);
  if (recent_.size() > capacity_) recent_.pop_back();
  return made;
}

}  // namespace lazyboe
