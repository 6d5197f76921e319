// What every planner shares: the planning problem (start, goal region, termination, seed), its
// validation, results and paths. A returned
// path is a sequence of commands; its trajectory comes from simulating them again from the
// exact start, with every check (realize_path).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lazyboe/robot/inverse_kinematics.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {
class EndPoseIndexes;
}

namespace lazyboe {

struct Goal {
  enum class Kind { Joint, Position, Pose, Set };
  Kind kind = Kind::Joint;
  JointVector q;                                       // Joint
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // Position, Pose: of `link`, base frame
  int link = -1;
  // rad (Euclidean in joint space), m (Position; Pose: of the position), or a Set's first
  // member's.
  double tolerance = 0.1;
  // Pose: the link's orientation, to within orientation_tolerance (rad), all of it or all but
  // the rotations about free_axis (base frame: any yaw about the vertical).
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  bool has_free_axis = false;
  Eigen::Vector3d free_axis = Eigen::Vector3d::UnitZ();
  double orientation_tolerance = 0.05;
  // Set: any member will do (several grasps of one object); members are not sets.
  std::vector<Goal> members;
  // Pose goals and sets (resolve_goal): configurations inside the goal region, within the joint
  // limits and free of collision, nearest the start first, which direct commands aim at; and
  // how many attempts of inverse kinematics reached the goal at all, and how many of those were
  // tilted beyond the task's end-effector limit (the others that were left out collide).
  std::vector<JointVector> configurations;
  bool resolved = false;
  int reached = 0, attempts = 0, tilted = 0;

  PoseTarget pose_target() const;  // Position, Pose
  // The configuration nearest q (Euclidean in joint space) and its distance; null and infinity
  // when there is none.
  std::pair<const JointVector*, double> nearest_configuration(const JointVectorRef& q) const;
  // Heuristic, in the unit of `tolerance`: the joint-space distance to q; the Cartesian
  // distance of the link to the position; for a pose the larger of the position error and the
  // orientation error weighted by tolerance / orientation_tolerance (so that the region is
  // distance <= tolerance); for a set the least of its members', each scaled to the first
  // member's tolerance.
  double distance(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const;
  bool contains(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const {
    return distance(robot, data, state) <= tolerance;
  }
};

// Whether resolve_goal finds configurations for the goal (pose goals and sets).
bool needs_configurations(const Goal& goal);

// Fills goal.configurations for a pose goal or a set (joint members: their q when valid), by
// inverse kinematics from `start`, from the end states of the bundle edges whose end poses are
// nearest the goal (`coverage`, when given), and from seeded random configurations of the
// robot's region and joint limits; sets goal.resolved. Deterministic in `seed`.
void resolve_goal(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                  uint64_t seed, Goal& goal, const EndPoseIndexes* coverage = nullptr);

// When a solve stops: its wall-clock budget has run out or, with stop_at_first, it has found a
// solution. (RRT, OMPL's RRT and KPIECE always stop at their first solution.)
// The longest accepted budget (about 11.6 days): far below where the deadline's nanosecond
// clock would overflow (about 9.2e9 s).
constexpr double kMaxBudgetSeconds = 1e6;

struct Termination {
  double budget = 5.0;  // wall-clock seconds, from the start of the solve, (0, kMaxBudgetSeconds]
  bool stop_at_first = false;
  // Set by the caller (from another thread) to stop the solve early, as a user's Ctrl-C does;
  // polled with the clock. Null: never.
  const std::atomic<bool>* cancel = nullptr;
  bool cancelled() const { return cancel && cancel->load(std::memory_order_relaxed); }
};

// One planning problem: from `start` (at rest) into the goal region, until `termination`, with
// the planner's random draws seeded by `seed`.
struct PlanningProblem {
  JointVector start;
  Goal goal;
  Termination termination;
  uint64_t seed = 1;
};

// What is wrong with a problem: the field at fault ("start", "goal.q", "goal.position",
// "goal.pose", "goal") and why. Empty field: nothing.
struct ProblemIssue {
  std::string field, what;
  bool any() const { return !field.empty(); }
};

// Every check a problem gets before any planner sees it: joint counts, the start and a joint
// goal inside the limits and collision-free, a position goal's link and reach, a positive
// tolerance, and a start not already in the goal.
ProblemIssue find_problem_issue(const Simulator& sim, SimulatorWorkspace& ws,
                                const PlanningProblem& problem);
// The same, throwing Error("<field>: <what>") for the first issue found.
void validate_problem(const Simulator& sim, SimulatorWorkspace& ws, const PlanningProblem& problem);

// One step of a path: a command (evenly spaced knots) applied from the previous step's end state.
struct PathStep {
  PathStep() = default;
  PathStep(int64_t edge, std::vector<double> command_knots, double duration)
      : bundle_edge(edge), knots(std::move(command_knots)), command_duration(duration) {}

  int64_t bundle_edge = -1;  // the bundle edge whose command this is, or -1 (RRT/SST, direct)
  std::vector<double> knots;
  double command_duration = 0;
  // The knots' times, s, from 0 to command_duration (a blended command's); empty: evenly
  // spaced, as a bundle edge's and a sampled command's are.
  std::vector<double> knot_times;
  CommandProfile profile(int dof) const {
    return {knots.data(), static_cast<int>(knots.size() / dof), dof, command_duration,
            knot_times.empty() ? nullptr : knot_times.data()};
  }
  // The planner's own valid simulation of this command from the previous step's end state (the
  // exact start for the first step) with the context's simulator, when it hands it over: the
  // post-processing takes it as the raw chain's instead of simulating the step again (issue
  // 27). `outcome_rows`, when not empty: that simulation's per-tick rows (TrajectorySamples::
  // ticks), so that a last step kept as it is needs no simulation either.
  std::optional<RolloutResult> outcome;
  std::vector<double> outcome_rows;
};

struct PlannerCounters {
  uint64_t nodes = 0;
  uint64_t simulations = 0;
  uint64_t lazy_edges = 0;
  uint64_t collision_checks = 0;
};

struct PlanResult {
  bool success = false;
  double time_to_first_solution = std::numeric_limits<double>::quiet_NaN();
  int n_solutions = 0;
  double best_cost = std::numeric_limits<double>::quiet_NaN();
  std::vector<PathStep> best_path;
  PlannerCounters counters;
  std::string failure;  // why there is no solution
  // Which part of the planner found the best path, for planners with several: "direct" (the
  // bundle planners' straight command, tried first), "waypoint" and "two_waypoints" (lazysp's
  // straight commands through one or two sampled waypoints, tried next), "bundle", "growth",
  // "connection", "approach" or "shortcut" (lazysp's search, growth, direct command into the
  // goal from a near state, the way in through an approach where that collided, or a
  // candidate's shortcut); "start" for any planner when the start already lay in the goal
  // region (the path of no motion); else empty.
  std::string found_by;
};

struct Trajectory {
  std::vector<double> t;
  std::vector<JointVector> q, dq;
  // Post-processed trajectories only (execution.h), else empty: the acceleration over the
  // control tick from each sample, and the commanded joint velocity.
  std::vector<JointVector> ddq, cmd;
  std::vector<int64_t> edges;  // bundle edge of each step (-1 for RRT/SST commands)
  double cost = 0;             // joint-space arc length, rad
  double duration = 0;
  int stops = 0;  // times it comes to rest between its start and its end
};

// Simulates `steps` from `start` with every check and returns the trajectory (samples every
// `sample_every` control ticks plus each step's end); throws Error naming the failing step
// when a step is not valid or the path does not end in the goal.
Trajectory realize_path(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                        const std::vector<PathStep>& steps, const Goal& goal, int sample_every);

class Deadline {
 public:
  explicit Deadline(double seconds)
      : start_(std::chrono::steady_clock::now()),
        end_(start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                          std::chrono::duration<double>(seconds))) {}
  bool passed() const { return std::chrono::steady_clock::now() >= end_; }
  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_, end_;
};

}  // namespace lazyboe
