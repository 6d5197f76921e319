#include "lazyboe/collision/allowed_pairs.h"

#include <map>
#include <random>

#include "lazyboe/collision/collision_model.h"

namespace lazyboe {

AllowedPairsResult derive_allowed_pairs(const RobotModel& robot, long samples, uint64_t seed) {
  CollisionOptions options;
  options.ignore_allowed_pairs = true;
  const CollisionModel model = build_collision_model(robot, Environment{}, options);
  RobotData robot_data(robot);
  CollisionData data(model);

  std::map<std::pair<int, int>, long> collisions;  // link pair -> count
  for (const auto& [a, b] : model.self_pairs) {
    const int la = model.robot[a].link, lb = model.robot[b].link;
    collisions[{std::min(la, lb), std::max(la, lb)}] = 0;
  }

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  JointVector q(robot.dof);
  for (long s = 0; s < samples; ++s) {
    for (int i = 0; i < robot.dof; ++i)
      q[i] = robot.q_min[i] + unit(rng) * (robot.q_max[i] - robot.q_min[i]);
    forward_kinematics(robot, robot_data, q);
    update_collision_transforms(model, data, robot_data);
    std::map<std::pair<int, int>, bool> hit;
    for (const auto& [a, b] : model.self_pairs) {
      const int la = model.robot[a].link, lb = model.robot[b].link;
      const std::pair<int, int> key(std::min(la, lb), std::max(la, lb));
      if (!hit[key] && self_pair_collides(model, data, a, b)) hit[key] = true;
    }
    for (const auto& [key, collided] : hit) collisions[key] += collided ? 1 : 0;
  }

  AllowedPairsResult result;
  result.samples = samples;
  // Links rigidly joined (same body) are never tested; list them as adjacent too.
  std::map<std::pair<int, int>, long> all = collisions;
  for (size_t a = 0; a < model.robot.size(); ++a) {
    for (size_t b = 0; b < model.robot.size(); ++b) {
      const int la = model.robot[a].link, lb = model.robot[b].link;
      if (la < lb && model.robot[a].body == model.robot[b].body)
        all.emplace(std::make_pair(la, lb), -1);
    }
  }
  for (const auto& [key, count] : all) {
    LinkPairStats stats;
    stats.link_a = key.first;
    stats.link_b = key.second;
    stats.collisions = std::max(0L, count);
    const int body_a = robot.links[key.first].body, body_b = robot.links[key.second].body;
    if (count < 0 || std::abs(body_a - body_b) <= 1) {
      stats.reason = "adjacent";
    } else if (count == samples && samples > 0) {
      stats.reason = "always";
    }
    result.pairs.push_back(stats);
  }
  return result;
}

}  // namespace lazyboe
