// Everything one process needs to plan on a bundle, built once and read-only afterwards (the
// Pinocchio "model" side; each thread brings its own SimulatorWorkspace): the bundle (memory-
// mapped, or read), its robot (checked against the identity stored in the bundle), its
// settings and the k-d trees over the edge starts and ends (mapped from the bundle's index
// file, or built); and apart from them the worlds it plans in (world.h: an environment, its
// collision model and the simulator), the bundle's own scene by default, any other scene for
// the same robot on request. Shared by lazyboe-query, lazyboe-bench and the Python module.
#pragma once

#include <chrono>
#include <string>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/bundle/scene.h"
#include "lazyboe/bundle/settings.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/planning/edge_index_file.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/planning/planner.h"
#include "lazyboe/planning/scene_cache.h"
#include "lazyboe/planning/workspace_index.h"

namespace lazyboe {

// theta of the bundle's perturbation analysis, or its design theta without one.
double bundle_theta(const BundleView& bundle);

// Mean joint-space displacement |qf - q0| of the bundle's edges, rad (0 for an empty bundle).
double mean_edge_displacement(const BundleView& bundle);

// The planning context of a bundle, for any holder of one (a session, a test, a front end):
// the simulator (of the world planned in), the bundle and its indexes, its mean edge
// displacement, and from the bundle's header its theta, sampling box and command family.
PlanningContext bundle_context(const Simulator& sim, const BundleView& bundle,
                               const EdgeIndex& index, const EdgeIndex* end_index = nullptr);
// The same with the mean edge displacement known (it reads every edge state to compute).
PlanningContext bundle_context(const Simulator& sim, const BundleView& bundle,
                               const EdgeIndex& index, const EdgeIndex* end_index,
                               double mean_displacement);

class PlanningSession {
 public:
  // Throws Error for a missing or corrupt bundle, or a robot that is not the bundle's. Empty
  // robot_path: the config named in the bundle. Empty env_path: the bundle's own environment
  // (the file named in the bundle, refused unless it still hashes to the recorded content);
  // otherwise any environment for the bundle's robot becomes the default world.
  PlanningSession(const std::string& bundle_path, bool memory_map, const std::string& robot_path,
                  const std::string& env_path);
  PlanningSession(const PlanningSession&) = delete;  // members refer to members
  PlanningSession& operator=(const PlanningSession&) = delete;

 private:
  const std::chrono::steady_clock::time_point started_;  // first: times the members below

 public:
  // What is mapped and shared, whatever the world (the model side):
  const BundleView bundle;
  const RobotModel robot;        // the bundle's, checked by content hash
  const BuildSettings settings;  // the bundle's simulation, command and region settings
  // The edge-to-workspace index beside the bundle (workspace_index.h): each world other than
  // the bundle's own scene gets its edge marks from it when it is made.
  const WorkspaceIndexLoad workspace;
  // Edge end poses per link, made at a pose goal's first use: goal coverage (end_pose_index.h).
  const EndPoseIndexes end_poses;
  // Per edge, how fast its stored motion moves a link, made at a task's first use (lazysp's
  // end-effector limits, edge_link_motion.h).
  const EdgeLinkMotions link_motions;
  // The worlds planned in (world.h): the default, and scenes queries name (by content).
  mutable SceneCache scenes;
  const BundleIndexes indexes;     // where they come from: indexes.source
  const EdgeIndex& index;          // edge start states: the planners' neighbourhoods
  const EdgeIndex& end_index;      // edge end states: goal coverage
  const double mean_displacement;  // mean_edge_displacement(bundle), for context()
  const double load_seconds;       // wall time of everything above

  const PlanningWorld& world() const { return *scenes.default_world(); }
  const Simulator& sim() const { return world().sim; }  // the default world's

  // bundle_context of the session's bundle and indexes in `world` (default: the default world).
  PlanningContext context() const { return context(world()); }
  PlanningContext context(const PlanningWorld& world) const;
  double default_theta() const { return bundle_theta(bundle); }
};

}  // namespace lazyboe
