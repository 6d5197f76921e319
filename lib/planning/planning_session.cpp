#include "lazyboe/planning/planning_session.h"

#include <chrono>

namespace lazyboe {
namespace {

using Clock = std::chrono::steady_clock;

SimulationOptions unsampled(SimulationOptions options) {
  options.sample_every = 0;
  return options;
}

// Is `env` the scene the bundle was built in (its files hash to the recorded content)?
bool is_build_scene(const Environment& env, const std::string& build_hash) {
  if (env.path.empty()) return false;
  try {
    return environment_identity(env) == build_hash;
  } catch (const std::exception&) {  // a file no longer readable: not provably the same
    return false;
  }
}

// The scene the bundle was built in, when its file is still there (else none: every obstacle of
// a new scene then marks).
std::shared_ptr<const Environment> build_scene(const BundleHeader& h) {
  try {
    return std::make_shared<const Environment>(load_bundle_environment(h, ""));
  } catch (const std::exception&) {
    return nullptr;
  }
}

// A new world's marks from the session's workspace index, for the obstacles the build scene did
// not have (the bundle's P_collision covers those it had); none in the build scene itself.
EdgeMarker session_marker(const WorkspaceIndexLoad& workspace, const RobotModel& robot,
                          const BundleHeader& h) {
  if (!workspace.index) return {};
  return [index = workspace.index, &robot, build_hash = h.env_hash, known = build_scene(h)](
             const Environment& env,
             const CollisionModel& collision) -> std::shared_ptr<const EdgeMarks> {
    if (is_build_scene(env, build_hash)) return nullptr;
    return std::make_shared<const EdgeMarks>(
        mark_edges(*index, robot, env, collision, known.get()));
  };
}

WorldPtr default_world(const BundleHeader& h, const RobotModel& robot,
                       const SimulationOptions& options, const std::string& env_path,
                       const EdgeMarker& marker) {
  Environment env = env_path.empty() ? load_bundle_environment(h, "") : load_environment(env_path);
  return std::make_shared<const PlanningWorld>(robot, std::move(env), options, marker);
}

// The session's worlds: its default, and every later one, marked by one marker.
SceneCache session_scenes(const BundleHeader& h, const RobotModel& robot,
                          const SimulationOptions& options, const std::string& env_path,
                          const WorkspaceIndexLoad& workspace,
                          const EndPoseIndexes& goal_coverage) {
  const EdgeMarker marker = session_marker(workspace, robot, h);
  return SceneCache(robot, options, default_world(h, robot, options, env_path, marker), marker,
                    &goal_coverage);
}

}  // namespace

PlanningSession::PlanningSession(const std::string& bundle_path, bool memory_map,
                                 const std::string& robot_path, const std::string& env_path)
    : started_(Clock::now()),
      bundle(BundleView::open(bundle_path, memory_map)),
      robot(load_bundle_robot(bundle.header(), robot_path)),
      settings(settings_from_header(bundle.header())),
      workspace(load_workspace_index(bundle, robot, memory_map)),
      end_poses(bundle, robot),
      link_motions(bundle, robot),
      scenes(session_scenes(bundle.header(), robot, unsampled(settings.simulation), env_path,
                            workspace, end_poses)),
      indexes(load_bundle_indexes(bundle, memory_map)),
      index(indexes.starts),
      end_index(indexes.ends),
      mean_displacement(mean_edge_displacement(bundle)),
      load_seconds(std::chrono::duration<double>(Clock::now() - started_).count()) {}

double bundle_theta(const BundleView& bundle) {
  return bundle.has_perturbation() ? bundle.perturbation_theta() : bundle.header().design_theta;
}

double mean_edge_displacement(const BundleView& bundle) {
  if (bundle.size() == 0) return 0;
  const int n = bundle.dof();
  double sum = 0;
  for (size_t e = 0; e < bundle.size(); ++e)
    sum += (Eigen::Map<const Eigen::VectorXd>(bundle.qf(e), n) -
            Eigen::Map<const Eigen::VectorXd>(bundle.q0(e), n))
               .norm();
  return sum / static_cast<double>(bundle.size());
}

PlanningContext bundle_context(const Simulator& sim, const BundleView& bundle,
                               const EdgeIndex& index, const EdgeIndex* end_index) {
  return bundle_context(sim, bundle, index, end_index, mean_edge_displacement(bundle));
}

PlanningContext bundle_context(const Simulator& sim, const BundleView& bundle,
                               const EdgeIndex& index, const EdgeIndex* end_index,
                               double mean_displacement) {
  const BuildSettings settings = settings_from_header(bundle.header());
  PlanningContext c{sim, &bundle, &index};
  c.end_index = end_index;
  c.theta = bundle_theta(bundle);
  c.mean_displacement = mean_displacement;
  c.sample_lower = settings.region_lower;
  c.sample_upper = settings.region_upper;
  c.command = settings.command;
  return c;
}

PlanningContext PlanningSession::context(const PlanningWorld& w) const {
  PlanningContext c = bundle_context(w.sim, bundle, index, &end_index, mean_displacement);
  c.scene_marks = w.edge_marks.get();
  c.end_poses = &end_poses;
  c.link_motions = &link_motions;
  return c;
}

}  // namespace lazyboe
