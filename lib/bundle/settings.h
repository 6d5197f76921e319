// The settings that decide a bundle's contents, and their record in its header.
#pragma once

#include <cstdint>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/sim/command_profile.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

// Everything that decides the bundle's contents (all stored in its header).
struct BuildSettings {
  uint64_t edges = 100000;
  uint64_t seed = 1;
  JointVector region_lower, region_upper;
  CommandSampling command;
  SimulationOptions simulation;
  double design_theta = 0.35;
};

// The settings a bundle header records (for resuming, and for re-simulating its edges). Throws
// Error for an integrator name other than "euler" or "rk4".
BuildSettings settings_from_header(const BundleHeader& header);

}  // namespace lazyboe
