// What every planner shares: the planning problem (start, goal region, budget), the planning
// context (one simulator, the bundle and its neighbour index), results and paths. A returned
// path is a sequence of commands; its trajectory comes from simulating them again from the
// exact start, with every check (realize_path).
#pragma once

#include <chrono>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

struct Goal {
  enum class Kind { Joint, Position };
  Kind kind = Kind::Joint;
  JointVector q;                                       // Joint
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // Position: of `link`, base frame
  int link = -1;
  double tolerance = 0.1;  // rad (Euclidean in joint space) or m

  // Heuristic: joint-space distance to q, or Cartesian distance of the link to the position.
  double distance(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const;
  bool contains(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const {
    return distance(robot, data, state) <= tolerance;
  }
};

struct PlannerParams {
  std::string planner = "lazyboe";  // lazyboe, boe, rrt, sst
  double theta = 0;                 // neighbourhood radius (bundle planners), rad
  double budget = 5.0;              // wall-clock seconds
  uint64_t seed = 1;
  bool stop_at_first = false;  // RRT always stops at its first solution
  // RRT and SST
  double goal_bias = 0.05;
  // SST: selection radius delta_BN and pruning radius delta_s = pruning_ratio * delta_BN
  double selection_radius = 0.2;
  double pruning_ratio = 1.0;
  JointVector sample_lower, sample_upper;  // state sampling box (default: the bundle's region)
  CommandSampling command;                 // control family of RRT/SST (default: the bundle's)
};

struct PlanningProblem {
  JointVector start;
  Goal goal;
  PlannerParams params;
};

// One step of a path: a command applied from the previous step's end state.
struct PathStep {
  int64_t bundle_edge = -1;  // the bundle edge whose command this is, or -1 (RRT/SST)
  std::vector<double> knots;
  double command_duration = 0;
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
};

struct Trajectory {
  std::vector<double> t;
  std::vector<JointVector> q, dq;
  std::vector<int64_t> edges;  // bundle edge of each step (-1 for RRT/SST commands)
  double cost = 0;             // joint-space arc length, rad
  double duration = 0;
};

// Shared, read-only planning context.
struct PlanningContext {
  const Simulator& sim;
  const BundleView* bundle = nullptr;  // null for planners that do not use one
  const EdgeStartIndex* index = nullptr;
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
