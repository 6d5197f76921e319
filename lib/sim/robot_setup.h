// A robot config written from a URDF (lazyboe-robot init): the chain (from the URDF, the options
// or an SRDF group), limits the URDF lacks derived from those it has by stated rules, controller
// gains computed from the model and checked by simulating a velocity step on every joint, the
// allowed collision pairs (sampled, plus an SRDF's disabled pairs), and the mesh representation.
// Every rule is stated in the config's descriptions and in the report.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

// The rules for what a URDF does not say (docs/robot-description.md, "lazyboe-robot init").
constexpr double kAccelerationPerVelocity = 5;   // 1/s: full speed in 0.2 s
constexpr double kJerkPerAcceleration = 100;     // 1/s: full acceleration in 10 ms
constexpr double kTorqueRatePerEffort = 10;      // 1/s: full effort in 0.1 s
constexpr double kStepTrackingTolerance = 0.25;  // of the step's velocity

struct RobotSetupOptions {
  std::string urdf_path;
  std::string srdf_path;   // optional: the chain of a group and the disabled collision pairs
  std::string srdf_group;  // empty: the first group with a <chain>
  std::vector<std::string> package_path;  // folders for package:// meshes
  std::string base_link, tip_link;        // empty: the SRDF's chain, else the URDF's defaults
  std::string name;                       // empty: the URDF file's name without extension
  MeshRepresentation meshes = MeshRepresentation::Fitted;
  std::vector<std::string> exact_links;   // mesh links kept exact whatever `meshes` says
  std::vector<std::string> convex_links;  // mesh links checked as their convex hulls
  double margin = 0.01;                   // m
  double time_constant = 0.05;            // velocity loop at the largest joint inertia, s
  long pair_samples = 20000;              // configurations sampled for the allowed pairs
  long inertia_samples = 1000;            // configurations sampled for the gains
  uint64_t seed = 1;
  std::string out_path;  // where the config goes: its relative paths start from its folder
};

// One joint's velocity step from a configuration of typical inertia: the rollout's outcome and the
// largest velocity tracking error as a fraction of the step.
struct StepCheck {
  std::string joint;
  RolloutStatus status = RolloutStatus::Valid;
  double tracking_error = 0;
  bool passed() const {
    return status == RolloutStatus::Valid && tracking_error <= kStepTrackingTolerance;
  }
};

struct RobotSetup {
  nlohmann::ordered_json config;   // ready to write, fields in the documented order
  std::vector<std::string> notes;  // what was assumed or derived, one line each
  std::vector<StepCheck> steps;
};

// Throws Error naming the file and element for a URDF or SRDF the config cannot be made from.
RobotSetup make_robot_config(const RobotSetupOptions& options);

// The configuration of typical inertia: of `samples` configurations drawn in the robot's
// sampling region (seeded), the one whose mass-matrix diagonal is nearest the per-joint median
// (in log, so that every joint counts alike). Where the bundle's edges typically start; the
// middle of the limits can be a singular pose (an arm straight up) whose small inertias make
// the coupled loops far livelier than anywhere a rollout starts.
JointVector typical_inertia_configuration(const RobotModel& robot, uint64_t seed, long samples);

// Simulates, for each joint in turn, a velocity step of 0.3 x its limit (0.25 s minimum-jerk
// ramps, 0.5 s held) from `start` (init: the configuration of typical inertia) with the other
// joints commanded still, checking limits but not collisions.
std::vector<StepCheck> check_velocity_steps(const RobotModel& robot, const JointVector& start);

}  // namespace lazyboe
