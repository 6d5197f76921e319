// The planner interface, in OMPL's spirit: a planner is made with its declared parameters
// (registry.h), set up once per planning context, solves one problem at a time under a
// termination condition, and is cleared. Every planner shares the context's one simulator,
// and so its validity checks: planners differ only in their search.
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/edge_link_motion.h"
#include "lazyboe/planning/end_pose_index.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/workspace_index.h"
#include "lazyboe/sim/command_profile.h"
#include "lazyboe/sim/rollout_pool.h"

namespace lazyboe {

// Shared, read-only planning context: the simulator, and for the bundle planners the bundle
// and its neighbour index (and, optionally, an index of the edges' end states: without it the
// goal coverage check scans every end state); what sampling planners need (the state sampling box
// and command family; by default the bundle's); the default neighbourhood radius.
struct PlanningContext {
  explicit PlanningContext(const Simulator& simulator, const BundleView* edge_bundle = nullptr,
                           const EdgeIndex* edge_index = nullptr)
      : sim(simulator), bundle(edge_bundle), index(edge_index) {}

  const Simulator& sim;
  const BundleView* bundle = nullptr;      // null for planners that do not use one
  const EdgeIndex* index = nullptr;        // over the edges' start states
  const EdgeIndex* end_index = nullptr;    // over their end states (goal coverage); optional
  double theta = 0;                        // the bundle's theta, rad (0: none)
  double mean_displacement = 0;            // mean |qf - q0| of the bundle's edges, rad (0: none)
  JointVector sample_lower, sample_upper;  // state sampling box
  CommandSampling command;                 // control family of the sampling planners
  // The bundle edges the world may block (its workspace-index marks), when the world is not the
  // bundle's own scene; null: the bundle's P_collision (its build scene's) is the prior.
  const EdgeMarks* scene_marks = nullptr;
  // The bundle's edge end poses (pose goals' coverage: resolve_goal's seeds); null: none.
  const EndPoseIndexes* end_poses = nullptr;
  // How the edges' stored motions move a link (a task's end-effector limits); null: none.
  const EdgeLinkMotions* link_motions = nullptr;
};

// The prior probability that bundle edge `e` collides in the context's world: 1 for an edge an
// obstacle new to the bundle may block (the world's workspace-index marks), otherwise the edge's
// P_collision from the bundle's perturbation analysis (its build scene's obstacles; 0 without an
// analysis). It steers the searches; simulation decides.
inline double collision_prior(const PlanningContext& c, size_t e) {
  if (c.scene_marks && c.scene_marks->may_collide(e)) return 1.0;
  return c.bundle->has_perturbation() ? c.bundle->p_collision(e) : 0.0;
}

class Planner {
 public:
  virtual ~Planner() = default;

  // Checks that the context has what the planner needs (a bundle, perturbation data, a
  // sampling box) and resolves parameters whose default comes from it. Throws Error naming
  // what is missing. The context must outlive the planner's solves.
  virtual void setup(const PlanningContext& context) = 0;
  // A planner keeps a pointer to its context: a temporary would dangle.
  void setup(const PlanningContext&& context) = delete;

  // Plans one problem (validate_problem first: a planner assumes a valid one) until its
  // termination condition. `ws` is the calling thread's workspace; `pool`, when given and of
  // several threads, may run independent rollouts in parallel (the answer does not change).
  virtual PlanResult solve(const PlanningProblem& problem, SimulatorWorkspace& ws,
                           RolloutPool* pool = nullptr) = 0;

  // Forgets everything but the setup (our planners keep no state between solves).
  virtual void clear() {}
};

// What a planner needs of its context, declared once in its PlannerInfo (registry.h).
struct PlannerNeeds {
  bool bundle = false;        // an edge bundle and its neighbour index
  bool perturbation = false;  // the bundle's perturbation analysis (lazyboe-perturb)
  bool ompl = false;          // a build with OMPL
};

// A planner's name and needs as its PlannerInfo declares them: handed to the planners its
// factory makes (planner_factory), so that each is written once.
struct PlannerIdentity {
  std::string name;
  PlannerNeeds needs;
};

// The base of the library's planners (as OMPL's base::Planner keeps its name and parameters):
// the parameter values the registry checked and completed, the identity its PlannerInfo
// declared, and the context of the last setup. A planner derived from it implements prepare
// (setup's checks) and solve.
class DeclaredPlanner : public Planner {
 public:
  DeclaredPlanner(const ParameterValues& values, PlannerIdentity identity)
      : values_(values), identity_(std::move(identity)) {}

  using Planner::setup;  // keeps the deleted temporary overload visible
  // Runs prepare (throws Error naming what the context lacks), then keeps the context.
  void setup(const PlanningContext& context) final {
    prepare(context);
    context_ = &context;
  }

  const std::string& name() const { return identity_.name; }
  const PlannerNeeds& needs() const { return identity_.needs; }

 protected:
  const ParameterValues& values() const { return values_; }
  // What setup checks and resolves of the context (what the planner needs of it).
  virtual void prepare(const PlanningContext& /*context*/) {}
  // The context of the last setup; throws Error("<name>: solve before setup") before any.
  const PlanningContext& context() const;

 private:
  ParameterValues values_;
  PlannerIdentity identity_;
  const PlanningContext* context_ = nullptr;
};

}  // namespace lazyboe
