// What the planning tests share, through the library (test_planners) and through lazyboe-query
// (test_query_cli): one small dense bundle (2000 edges in a small region, p = 4 perturbations),
// an easy start/goal pair among its edge starts, and an independent re-validation of returned
// trajectories (times, start, goal, limits, collision, continuity, edges; re-simulating a
// path's commands lands exactly on the trajectory's end).
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe::test {

// ------------------------------------------------------------------------------------------
// The bundle's parameters (lazyboe-build's defaults for everything else, default seeds)
// ------------------------------------------------------------------------------------------

constexpr int kEdges = 2000;
constexpr double kTheta = 0.45;
constexpr const char* kRegion = "-0.3:0.3,0.0:0.5,-0.3:0.3,-2.3:-1.7,-0.3:0.3,1.6:2.2,0.5:1.1";
constexpr uint64_t kPerturbations = 4;
constexpr double kTolerance = 0.3;  // of every query's goal

std::vector<double> vec(const JointVectorRef& q);
JointVector joint(const std::vector<double>& v);
std::string str(const JointVectorRef& q);  // "[q1, q2, ...]", 17 digits

SimulationOptions options_of(const BundleHeader& h);  // the bundle's simulation, no samples

// The bundle built through the library as lazyboe-build and lazyboe-perturb build it with the
// parameters above (the same edges, bit for bit: a bundle is a function of its settings), before
// and after the perturbation analysis.
struct SmallBundles {
  std::shared_ptr<const Bundle> unperturbed, perturbed;
};
SmallBundles build_small_bundles();

// ------------------------------------------------------------------------------------------
// The fixture: the bundle, its scene and the easy problems
// ------------------------------------------------------------------------------------------

struct PlanningFixture {
  PlanningFixture(std::shared_ptr<const Bundle> bundle, BundleView view);
  PlanningFixture(const PlanningFixture&) = delete;
  PlanningFixture& operator=(const PlanningFixture&) = delete;

  std::shared_ptr<const Bundle> bundle;
  const Bundle& data;  // *bundle
  RobotModel robot;    // the bundle's own robot and environment
  Environment env;
  CollisionModel collision;
  Simulator sim;
  BundleView view;
  EdgeIndex index{view};
  JointVector a, b;  // an easy pair: two edge starts 0.35-0.45 rad apart near the region's centre
  JointVector c;     // an edge start 0.7-0.85 rad from a: paths of several steps

  JointVector edge_start(size_t e) const;
};

// One fixture F per process, built on first use; a failure is reported by every test without
// building again.
template <typename F>
const F& shared_fixture() {
  static std::string failure;
  static const F* f = []() -> const F* {
    try {
      return new F();
    } catch (const std::exception& e) {
      failure = e.what();
      return nullptr;
    }
  }();
  if (!f) throw std::runtime_error("the test bundle could not be set up: " + failure);
  return *f;
}

// Our own planners, from the registry (OMPL's have a suite of their own, test_ompl): a planner
// added to the library is run by every test that loops over these.
std::vector<std::string> own_planners();
inline const std::vector<std::string> kPlanners = own_planners();

bool is_bundle_planner(const std::string& planner);
// `values` with direct = false for a planner that declares `direct`: tests of a search run the
// search, not the straight command tried before it (tested on its own in test_execution); and
// for lazysp connect_radius = 0 and candidate_shortcut = 0 unless given (its paths then are of bundle
// edges and growth commands only; the connection and the shortcut are tested on their own in
// test_planners).
ParameterValues searching(const std::string& planner, ParameterValues values = {});
double easy_budget(const std::string& planner);  // of the easy problem a -> b

// ------------------------------------------------------------------------------------------
// Independent re-validation of a trajectory
// ------------------------------------------------------------------------------------------

// A trajectory as lazyboe-query writes it inline in a result.
Trajectory trajectory_from_json(const nlohmann::json& r);

// Every problem found, one per line (at most a few per kind); empty when the trajectory is
// valid. Checks only what the trajectory itself shows, with the library's check_state.
std::string validate(const PlanningFixture& f, const Trajectory& traj, const JointVectorRef& start,
                     const JointVectorRef& goal, double tolerance, const std::string& planner);

// Simulates `commands` one after another from `start` (each from the previous simulated end)
// and compares the end and the total time with the trajectory's. Empty when they agree.
std::string resimulate(const PlanningFixture& f, const JointVectorRef& start,
                       const std::vector<CommandProfile>& commands, const Trajectory& traj);

std::vector<CommandProfile> bundle_commands(const PlanningFixture& f,
                                            const std::vector<int64_t>& edges);

// ------------------------------------------------------------------------------------------
// States outside the bundle's coverage
// ------------------------------------------------------------------------------------------

// The smallest distance from q to the starts (or ends) of every edge.
double nearest_distance(const PlanningFixture& f, const JointVectorRef& q, bool ends);

// A collision-free state within the limits whose first joint is moved by one of `offsets`
// from `base`, farther than `clearance` from every edge start (or end); empty when none is.
JointVector far_state(const PlanningFixture& f, const JointVectorRef& base,
                      const std::vector<double>& offsets, double clearance, bool ends);

// States beyond the coverage of the fixture's bundle, from the easy pair: a start farther than
// theta from every edge start, a goal farther than theta + tolerance from every edge end.
JointVector far_start_state(const PlanningFixture& f);
JointVector far_goal_state(const PlanningFixture& f);

}  // namespace lazyboe::test
