// The forward model f of the paper: a rollout of the robot's dynamics following a joint-velocity
// command profile, tracked by the joint controller of the robot config, integrated with RK4 at
// the control rate (torques held between control ticks), and validated at every tick:
// position, velocity, acceleration, torque limits; continuity (jerk, torque rate, also at the
// start and end, where the robot is at rest); self- and environment collision, checked densely
// enough that no point of the robot moves more than the collision margin between two checks.
//
// Simulator is built once and read-only (shared by threads); each thread owns a
// SimulatorWorkspace. Every planner and tool uses this one simulator.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lazyboe/collision/collision_model.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/sim/command_profile.h"
#include "lazyboe/sim/end_effector.h"

namespace lazyboe {

enum class RolloutStatus : uint8_t {
  Valid,
  PositionLimit,
  VelocityLimit,
  AccelerationLimit,
  JerkLimit,
  TorqueLimit,
  TorqueRateLimit,
  SelfCollision,
  EnvCollision,
  NotSettled,
  EndEffectorSpeed,
  EndEffectorAcceleration,
  EndEffectorTilt,
};
constexpr int kRolloutStatusCount = 13;
const char* rollout_status_name(RolloutStatus status);

// RK4: 4th order, 4 forward-dynamics evaluations per step. SemiImplicitEuler: 1st order and
// symplectic (velocity first, then position with the new velocity), 1 evaluation per step.
enum class Integrator : uint8_t { RK4, SemiImplicitEuler };

// "rk4" or "euler", as on the command line and in bundle headers.
const char* integrator_name(Integrator integrator);
// The inverse; throws Error("<where>: expected euler or rk4, got '<name>'").
Integrator parse_integrator(const std::string& name, const std::string& where);

struct SimulationOptions {
  Integrator integrator = Integrator::RK4;
  int substeps = 1;               // integration steps per control period
  double settle_velocity = 1e-3;  // at rest when every |dq| is below this (rad/s)
  double max_settle_time = 1.0;   // after the command ends, s
  // At rest also means: the arm could stop dead at the next tick (the next command starts from
  // exactly zero velocity) within the acceleration, jerk and half the torque-rate limit (the
  // other half is the next command's first tick). For trajectories that are executed, where
  // that velocity jump between two rest-to-rest commands is real; bundle edges and the
  // planners keep the paper's settle (off), so edges and their end states do not change.
  bool settle_for_stop = false;
  int sample_every = 20;  // control ticks between stored trajectory samples (0: none)
};

// Stored-sample spacing: control ticks <-> seconds. sample_every_ticks rounds to the nearest
// tick, so an interval below half a control period gives 0 (no samples; callers that need
// samples take std::max(1, ...)).
int sample_every_ticks(double interval_s, double control_rate);
double sample_interval_seconds(int ticks, double control_rate);
// sample_every_ticks for an interval that must be a whole number of control periods (0 is);
// throws Error("<where>: must be a multiple of the control period (<period> s)") otherwise.
int exact_sample_every_ticks(double interval_s, double control_rate, const std::string& where);

// Per joint: a bound on the motion of any point of the robot's collision shapes per unit
// motion of that joint, so that lever_arm . |q1 - q0| bounds every point's path for a small
// joint motion (the collision-check spacing rule).
JointVector collision_lever_arms(const RobotModel& robot, const CollisionModel& collision);

struct Simulator {
  Simulator(const RobotModel& robot, const CollisionModel& collision, SimulationOptions options,
            EndEffectorLimits end_effector = {});

  const RobotModel& robot;
  const CollisionModel& collision;
  SimulationOptions options;
  EndEffectorLimits end_effector;  // a task's, checked at every tick when any()
  double dt;                       // control period, s
  JointVector lever_arm;  // per joint: bound on any robot point's motion per unit joint motion
};

struct SimulatorWorkspace {
  explicit SimulatorWorkspace(const Simulator& sim);
  RobotData robot;
  CollisionData collision;
};

struct RolloutResult {
  RolloutStatus status = RolloutStatus::Valid;
  JointVector qf;       // final state (at rest when valid and not stopped)
  double duration = 0;  // simulated time, s
  int ticks = 0;        // control ticks simulated
  int collision_checks = 0;
  double path_length = 0;  // arc length of the motion in joint space, rad
  bool stopped = false;    // at RolloutResume::stop_at (valid so far, not at rest)
  bool valid() const { return status == RolloutStatus::Valid; }
};

// Optional output of a rollout: states every `every` control ticks (0: the simulator's
// options.sample_every), plus the final state. `ticks`, when given, gets every control tick
// in double precision, one row of 4 dof values per tick from the start (tick 0) to the final
// state: q, dq, ddq (the acceleration over the tick that follows; over the last tick for the
// final state) and the commanded joint velocity.
struct TrajectorySamples {
  std::vector<float>* q = nullptr;
  std::vector<float>* dq = nullptr;
  int every = 0;
  std::vector<double>* ticks = nullptr;
};

// A rollout's state at the start of a control tick: enough to go on from there exactly as the
// rollout it was saved from (bit for bit), from the same start, for a command that agrees with
// that rollout's command at every earlier tick, with a simulator that agrees with its
// simulator until the command ends (same_until_settling; issue 27: simulate only what changed).
struct RolloutCheckpoint {
  int tick = -1;  // -1: none saved
  JointVector q, dq, tau_prev, ddq_prev;
  double moved = 0;       // the collision-check spacing's path since the last check
  RolloutResult partial;  // collision checks and path length so far
  Eigen::Vector3d end_effector_velocity = Eigen::Vector3d::Zero();
  size_t tick_values = 0;  // TrajectorySamples::ticks values up to that tick
};

// Optional: `from` continues a saved rollout (the caller's samples.ticks must hold its rows up
// to the checkpoint, from->tick_values values, and no float samples are taken); `saved` gets
// the state at the start of each tick of `save_at` (increasing) that the rollout gets to.
struct RolloutResume {
  const RolloutCheckpoint* from = nullptr;
  const std::vector<int>* save_at = nullptr;
  std::vector<RolloutCheckpoint>* saved = nullptr;
  // A tick to stop at, after saving a checkpoint due there (-1: none): the result is then
  // `stopped`, valid so far but not at rest; going on from that checkpoint gives the rest.
  int stop_at = -1;
};

// Whether rollouts of `a` and `b` agree tick for tick until their command ends: the same robot,
// collision model, integration and task limits; only the settle may differ (settle_velocity,
// max_settle_time and settle_for_stop act once the command has ended).
bool same_until_settling(const Simulator& a, const Simulator& b);

// The first tick whose command time (tick * dt, as simulate computes it) is not before t by a
// margin: a command changed from time t on leaves every earlier tick as it was.
int ticks_before(const Simulator& sim, double t);

// Simulates from rest at q0 (or on from resume.from). Stops at the first violation, or at
// resume.stop_at (`stopped`). Allocates nothing when the sample vectors have capacity.
RolloutResult simulate(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& q0,
                       const CommandProfile& profile, TrajectorySamples samples = {},
                       RolloutResume resume = {});

// Limits and collision of a single configuration at rest (for start states and queries).
RolloutStatus check_state(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& q);

}  // namespace lazyboe
