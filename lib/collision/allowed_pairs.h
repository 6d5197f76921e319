// Deriving the allowed-collision pairs of a robot by sampling, as robot set-up tools do: a pair
// of links may be skipped by the self-collision check when the links are rigidly joined or
// adjacent (their capsules overlap at the joint by design), or when they collide in every
// sampled configuration (so the check could never tell anything).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

struct LinkPairStats {
  int link_a = 0, link_b = 0;
  long collisions = 0;  // samples in which the pair collided (margin included)
  std::string reason;   // "adjacent", "always", or empty when the pair must be checked
};

struct AllowedPairsResult {
  long samples = 0;
  std::vector<LinkPairStats> pairs;  // every pair of links that both carry collision geometry
};

AllowedPairsResult derive_allowed_pairs(const RobotModel& robot, long samples, uint64_t seed);

}  // namespace lazyboe
