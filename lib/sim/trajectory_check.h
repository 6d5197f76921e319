// An independent check of a joint trajectory sampled at the control rate (t, q, dq per
// sample), from this project or anywhere else, against the robot config's limits as the
// Panda's controller checks a command stream at 1 kHz: position and velocity per sample;
// acceleration, jerk, torque and torque rate by finite differences and inverse dynamics (with
// the robot's friction model); self- and environment collision, checked as densely as the
// simulator does; start and end at rest. It uses nothing of how the trajectory was made (no
// command, no controller), only the samples. What is checked and how: docs/execution.md,
// "Checking a trajectory".
//
// As the simulator: a read-only TrajectoryChecker (shared by threads) and a per-thread
// TrajectoryCheckWorkspace. The checker needs no controller gains, so any robot config works.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "lazyboe/sim/simulator.h"

namespace lazyboe {

enum class TrajectoryLimit : uint8_t {
  Position,
  Velocity,      // |dq| of a sample, and |q_{k+1} - q_k| / dt (what a position interface sees)
  Acceleration,  // (dq_{k+1} - dq_k) / dt
  Jerk,          // difference of consecutive accelerations / dt, from and back to rest
  Torque,        // inverse dynamics of each control period
  TorqueRate,    // difference of consecutive torques / dt, from and back to holding torque g(q)
  StartAtRest,   // |dq| of the first sample
  EndAtRest,     // |dq| of the last sample
  SelfCollision,
  EnvCollision,
  // A task's end-effector limits (options.end_effector), as the simulator checks them: the
  // link's linear speed at each sample (Jacobian times dq), the change of that velocity between
  // samples / dt (from and back to rest), the tilt of its axis from the vertical.
  EndEffectorSpeed,
  EndEffectorAcceleration,
  EndEffectorTilt,
};
constexpr int kTrajectoryLimitCount = 13;
// The per-joint limits (Position .. TorqueRate), which have a peak fraction.
constexpr int kJointLimitCount = 6;
const char* trajectory_limit_name(TrajectoryLimit limit);

// Samples row-major (sample k, joint i at [k * dof + i]); nothing is copied.
struct TrajectoryView {
  int samples = 0;
  int dof = 0;
  const double* t = nullptr;
  const double* q = nullptr;
  const double* dq = nullptr;
};

struct TrajectoryCheckOptions {
  // At rest: every |dq| at most this (rad/s); the simulator's settle velocity.
  double rest_velocity = SimulationOptions().settle_velocity;
  // Relative precision the samples are trusted to: float32 (the simulator stores its samples
  // as float). Each estimate is compared with its limit plus the largest error that rounding of
  // the samples by this much can cause in it.
  double sample_precision = 0x1p-24;
  // |t_{k+1} - t_k - dt| allowed, s (t written with 10 significant digits).
  double time_tolerance = 1e-6;
  bool check_collision = true;
  EndEffectorLimits end_effector;  // none by default
};

struct TrajectoryViolation {
  TrajectoryLimit limit = TrajectoryLimit::Position;
  int sample = -1;   // the sample, or the first sample of the control period
  double time = 0;   // its time (between samples for a collision found in between)
  int joint = -1;    // 0-based; -1 for collisions
  int shape_a = -1;  // collisions: robot shape (CollisionModel::robot)
  int shape_b = -1;  // robot shape (self) or obstacle (env)
  double value = 0;  // the estimate (collisions: the exact distance, m)
  double bound = 0;  // the limit (collisions: the margin), rounding allowance excluded
};

struct TrajectoryCheckResult {
  bool valid = true;
  TrajectoryViolation violation;  // the first one in time, when not valid
  int samples = 0;
  double duration = 0;  // t of the last sample minus t of the first
  int collision_checks = 0;
  // Over the samples checked (up to the violation): the largest |value| / limit of each joint
  // limit (Position: distance from the middle of the range / half the range) and its joint.
  std::array<double, kJointLimitCount> peak_fraction{};
  std::array<int, kJointLimitCount> peak_joint{};
};

struct TrajectoryChecker {
  TrajectoryChecker(const RobotModel& robot, const CollisionModel& collision,
                    TrajectoryCheckOptions options = {});

  const RobotModel& robot;
  const CollisionModel& collision;
  TrajectoryCheckOptions options;
  double dt;              // control period, s
  JointVector lever_arm;  // the simulator's collision-check spacing rule
};

struct TrajectoryCheckWorkspace {
  explicit TrajectoryCheckWorkspace(const TrajectoryChecker& checker);
  RobotData robot;
  CollisionData collision;
};

// The first sample k >= 1 whose spacing t_k - t_{k-1} differs from the control period by more
// than options.time_tolerance; -1 when every spacing is right.
int first_bad_spacing(const TrajectoryChecker& checker, const TrajectoryView& traj);

// Checks the trajectory and returns its first violation. Throws Error when the trajectory
// cannot be checked: fewer than two samples, a dof other than the robot's, or a spacing other
// than the control period. Allocates nothing.
TrajectoryCheckResult check_trajectory(const TrajectoryChecker& checker,
                                       TrajectoryCheckWorkspace& ws, const TrajectoryView& traj);

// "jerk_limit at t = 1.234 s (sample 1234): joint 2 (panda_joint2) -1.2e4 rad/s^3, limit
// 3750" or "env_collision at t = ...: panda_link7 and obstacle 'table', distance ...".
std::string describe_violation(const TrajectoryChecker& checker, const TrajectoryViolation& v);

}  // namespace lazyboe
