// Post-processing of a returned path into a trajectory a robot can execute as it is (issue 14):
// a planner's path is a chain of rest-to-rest commands (bundle edges or sampled commands), each
// simulated with a settle at rest; our planners hand over their own simulation of each step
// (PathStep::outcome), so the raw chain is not simulated again (issue 27). This stage
//   1. shortcuts: replaces runs of steps by one direct, straight-line command between their
//      end states when that simulates valid and is shorter (farthest first, within a budget of
//      attempts);
//   2. blends: joins the steps' velocity knots into one command with knot times, drops the
//      intermediate settles and passes through each junction at a velocity between the two
//      steps' neighbouring knots, on shortened intervals that keep the commanded displacement;
//   3. simulates each joined command from rest with every check of the simulator (limits,
//      continuity, torque and torque rate, collision at margin spacing). A junction whose
//      blend fails keeps its stop: the command is split there into two rest-to-rest segments.
// The offset a blend introduces is predicted and corrected through displacement transfer (an
// edge's command from a shifted start ends shifted by the same amount): the end offset of a
// segment is added back into its last step's knots, and a segment starting off the raw chain
// is corrected by its start offset, so every segment ends near the raw chain's state and the
// last inside the goal region. When anything cannot be made valid, the raw chain is returned
// as it is. Deterministic: no randomness, no wall clock in any decision.
#pragma once

#include <optional>
#include <vector>

#include "lazyboe/planning/problem.h"

namespace lazyboe {

struct ExecutionOptions {
  bool blend = true;
  // The post-processing budget: direct commands tried by the shortcut pass (each is one
  // simulation plus at most max_corrections; 0: no shortcut pass). Blending needs no budget of
  // its own: at most about three simulations per junction.
  int shortcut_attempts = 12;
  int max_corrections = 2;             // re-simulations to correct a segment's end offset
  double correction_tolerance = 2e-3;  // rad (max norm): no correction below this end offset
  double end_tolerance = 0.01;         // rad: a segment may end this far from the raw chain
  // A correction round adds the residual to the last this many knots of the corrected range
  // only (0: the whole range, evenly), so that it goes on from the rollout's checkpoint before
  // them instead of simulating the range again.
  int correction_knots = 1;
  // A rollout that a correction may follow stops where its command ends; the settle's
  // displacement is predicted from that state (settle_displacement), and only when the predicted
  // end needs no correction is the settle simulated (going on from there, also with resume
  // false: the same rollout finished). A corrected round's end is then predicted, not measured;
  // the end the segment keeps is always simulated and checked. False: every round settles and
  // its real end decides.
  bool predict_settle = true;
  // A rollout goes on from an earlier one's checkpoint where their commands agree (false: every
  // rollout from its start; the same trajectories, for comparing).
  bool resume = true;
  CommandSampling limits;  // speed and limit fractions of the commands built here
  // Shortened junction intervals, as fractions of the original two: the first within the
  // commanded limits is simulated; a failure is tried once more with the last, then stops.
  std::vector<double> blend_scales = {0.5, 0.6, 0.7, 0.8, 0.9};
  // The shortcut pass looks at a candidate's joint-space line first (line_looks_free) and
  // simulates only those whose line is free; every kLooksPerAttempt candidates left out so use
  // one attempt of the budget (false: every candidate simulated, the trajectories as before the
  // look).
  bool look = true;
  // With the look: a candidate whose line looks free and is shorter than the run it replaces is
  // taken without a simulation of its own; the blend pass simulates it as part of its segment
  // (only the segment's end is corrected). At the first failed attempt of a segment holding
  // one, both passes run again with every shortcut simulated on its own (false: always so).
  bool looked_shortcuts = true;
  // A blocked look costs about 20-50 checked states, a simulation hundreds of ticks; the budget
  // still bounds the looks of a long path (m steps have about m^2 / 2 candidates).
  static constexpr int kLooksPerAttempt = 4;
};

// One rest-to-rest command of the executed trajectory: the joined knots of some steps.
struct ExecutionSegment {
  JointVector start;                  // at rest
  std::vector<double> times;          // knot times, s, from 0
  std::vector<double> knots;          // times.size() rows of dof velocities
  int first_step = 0, last_step = 0;  // the (post-shortcut) steps it joins
  RolloutResult result;               // its simulation from `start`
  bool uniform = false;               // evenly spaced knots, simulated as such (a raw step alone)
  CommandProfile profile(int dof) const {
    return {knots.data(), static_cast<int>(times.size()), dof, times.back(),
            uniform ? nullptr : times.data()};
  }
};

struct ExecutionStats {
  int raw_steps = 0;       // steps of the planner's path
  int steps = 0;           // after shortcutting
  int shortcuts = 0;       // runs of raw steps replaced by one direct command
  int looked_blocked = 0;  // shortcut candidates whose line collided: left out unsimulated
  int junctions = 0;       // between the steps after shortcutting
  int blends_kept = 0;     // junctions passed without stopping
  int stops = 0;           // junctions kept at rest (= junctions - blends_kept)
  // Rollouts simulated by this stage (raw steps the planner did not hand over included; one
  // stopped where its command ends and then finished counts once).
  int simulations = 0;
  long simulated_ticks = 0;  // control ticks of those rollouts (not those a resumed one skipped)
  // Ticks not simulated again: a rollout whose command agrees with an earlier one's from the
  // same start up to a knot (a correction round, a junction tried again or split into a stop,
  // a segment that begins with a shortcut) goes on from that one's state there.
  long resumed_ticks = 0;
  double seconds = 0;  // wall time of this stage (reported, never used in a decision)
  double raw_seconds =
      0;  // of which the raw chain (re-simulating steps the planner did not hand over)
  bool fell_back = false;  // the raw chain is returned as it is
  // An attempt at a segment holding a looked shortcut failed: both passes ran again with every
  // shortcut simulated on its own (ExecutionOptions::looked_shortcuts).
  bool shortcuts_simulated_again = false;
  double raw_duration = 0, raw_cost = 0;
  int raw_stops = 0;

  // A rollout that went on from a checkpoint at tick `resumed_at` simulated only the rest.
  void count(const RolloutResult& r, int resumed_at = 0) {
    ++simulations;
    simulated_ticks += r.ticks - resumed_at;
    resumed_ticks += resumed_at;
  }
};

struct ExecutableTrajectory {
  Trajectory trajectory;                   // with ddq and cmd; edges: the planner's bundle edges
  std::vector<ExecutionSegment> segments;  // empty when fell_back
  ExecutionStats stats;
};

// The executable trajectory of a returned path, sampled every `sample_every` control ticks
// (1: the control rate) plus each segment's end. The first sample is the exact start at rest,
// the last at rest inside the goal. Throws Error as realize_path does when the raw path itself
// fails re-validation.
ExecutableTrajectory make_executable(const Simulator& sim, SimulatorWorkspace& ws,
                                     const JointVectorRef& start,
                                     const std::vector<PathStep>& steps, const Goal& goal,
                                     const ExecutionOptions& options, int sample_every);

// The simulator of the returned segments that end at a kept stop: `sim` with settle_for_stop,
// since the next segment starts from exactly zero velocity, so the arm must be able to stop
// dead there. The last segment, after which the arm holds its position under the controller,
// and the raw chain keep `sim`'s settle, as the planners simulated them. It may settle for up
// to kExecutionSettleTime after the command.
constexpr double kExecutionSettleTime = 3.0;  // s
Simulator execution_simulator(const Simulator& sim);

// The displacement still to come when a command ends at (q, dq) and the arm settles: the
// controller holds g(q) + kv (0 - dq) and the friction brakes, so M ddq = -(K_v + F) dq
// integrates, with M about constant over the settle's small motion, to (K_v + F)^-1 M dq (F: the
// friction's slope at rest; C(q, dq) dq is second order in the small dq). `data`: scratch.
JointVector settle_displacement(const Simulator& sim, RobotData& data, const JointVector& q,
                                const JointVector& dq);

// What answer_request (request.h) returns for a solved problem: the
// executable trajectory, its figures in `stats`, or with `raw` the planner's edge chain as
// realize_path gives it (`stats` untouched).
Trajectory returned_trajectory(const Simulator& sim, SimulatorWorkspace& ws,
                               const PlanningProblem& problem, const std::vector<PathStep>& path,
                               bool raw, const ExecutionOptions& options, int sample_every,
                               ExecutionStats& stats);

// Fraction of the command limits (limit_scale) a direct command with a junction at either end
// uses, so that a blend of the junction fits within them (at the limits none would).
constexpr double kJunctionRoom = 0.7;

// A joint-space straight line from rest by `displacement` to rest, as fast as `limits` allow the
// commanded velocity, acceleration and jerk (N intervals: knots 0, v, ..., v, 0); false when
// the displacement is (numerically) zero.
bool direct_command(const RobotModel& robot, const CommandSampling& limits,
                    const JointVectorRef& displacement, double dt, std::vector<double>& times,
                    std::vector<double>& knots);

// The direct command from the problem's start to its joint goal, or to the configuration of a
// pose goal or goal set nearest the start (direct_command within `limits`), simulated with every
// check from the start with `sim`'s settle: the step with that simulation as its outcome (valid
// or not) and its per-tick rows. A configuration of a pose goal is a point to land near: when
// the command lands outside the goal it is corrected by the miss and simulated again, up to
// kDirectCorrections times. `simulations` (when given) gets how many it ran. None for a
// position goal (no joint target to aim at) or a goal at the start.
constexpr int kDirectCorrections = 3;
// The same from `from` to `target`; corrected while it lands outside `land_in` (null: never).
std::optional<PathStep> direct_step_to(const Simulator& sim, SimulatorWorkspace& ws,
                                       const CommandSampling& limits, const JointVectorRef& from,
                                       const JointVector& target, const Goal* land_in,
                                       int* simulations = nullptr);
// Straight commands from `points[0]` through each later point, the junctions between them
// blended (ExecutionOptions::blend_scales, the first within options.limits; each command within
// kJunctionRoom of them), joined into one command with knot times (PathStep::knot_times), as
// the post-processing would join them, simulated with every check from points[0] and, while it
// lands outside `land_in`, corrected by the miss in its last command's knots (up to
// kDirectCorrections times): one rollout where the chain of rest-to-rest commands and then
// its blend would be two. The step with its last simulation and rows (valid or not); none when
// a junction cannot be blended within the limits or two points coincide. `simulations` (when
// given) gets how many it ran.
std::optional<PathStep> blended_step_through(const Simulator& sim, SimulatorWorkspace& ws,
                                             const ExecutionOptions& options,
                                             const std::vector<JointVector>& points,
                                             const Goal& land_in, int* simulations = nullptr);
// What direct_step aims at: the joint goal, or a pose goal's configuration `target`; null when
// it has no such configuration.
const JointVector* direct_target(const Goal& goal, int target);
// `target`: which of a pose goal's configurations (0: the nearest the start).
std::optional<PathStep> direct_step(const Simulator& sim, SimulatorWorkspace& ws,
                                    const CommandSampling& limits, const PlanningProblem& problem,
                                    int* simulations = nullptr, int target = 0);

// Whether a step with an outcome ends valid at rest inside the goal region.
bool solves(const Simulator& sim, SimulatorWorkspace& ws, const PathStep& step, const Goal& goal);

// A look at a direct command before simulating it: whether the states of the joint-space line
// from `from` to `to`, evenly spaced at most kLineLookStep apart, its end included (not `from`:
// the command starts there), pass the simulator's check of a state (limits, collisions, tilt). A
// direct command moves from rest to rest along that line within its tracking error, so one whose
// line collides is not worth a simulation (a look at a state costs about what one control tick
// does; a simulation, hundreds of ticks). `checks`, when given, gets the states checked added.
constexpr double kLineLookStep = 0.05;  // rad (Euclidean, joint space)
bool line_looks_free(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& from,
                     const JointVectorRef& to, uint64_t* checks = nullptr);

// Whether the direct step solves the problem: a problem that needs no planning.
bool solved_by_direct_command(const Simulator& sim, SimulatorWorkspace& ws,
                              const CommandSampling& limits, const PlanningProblem& problem);

}  // namespace lazyboe
