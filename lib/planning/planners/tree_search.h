// The tree search that RRT and SST share (internal; not installed): sample a state in the
// context's sampling box (or, with probability goal_bias, a joint goal), select a tree node for
// it, apply a random command of the context's command family from that node, and add the end
// state when the rollout is valid. SST (sst.cpp) overrides the hooks.
#pragma once

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/planning/search_tree.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {

// A node of the tree searches: a state reached by one of the search's own commands.
struct TreeNode : SearchNode {
  int command = -1;  // index into the search's commands (-1: the root)
};

// The node of `nodes` nearest to x (squared Euclidean distance; the first of equals) among
// those `live(v)` accepts; 0 when none does.
template <typename Node, typename Live>
int nearest_node(const std::vector<Node>& nodes, const JointVector& x, Live live) {
  int best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t v = 0; v < nodes.size(); ++v) {
    if (!live(static_cast<int>(v))) continue;
    const double d = (nodes[v].q - x).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = static_cast<int>(v);
    }
  }
  return best;
}

class TreeSearch {
 public:
  TreeSearch(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p,
             const ParameterValues& values);
  virtual ~TreeSearch() = default;

  PlanResult run();

 protected:
  // ---- Hooks (RRT's behaviour by default) ----
  virtual void start(const TreeNode& /*root*/) {}
  // The tree node to extend towards the sample x.
  virtual int select(const JointVector& x) { return nearest(x); }
  // Whether the new node c (not yet added) joins the tree.
  virtual bool admit(const TreeNode& /*c*/) { return true; }
  // Called once the admitted node is in the tree as `id`.
  virtual void added(int /*id*/) {}
  // RRT stops at its first solution.
  virtual bool stop_at_solution() const { return true; }

  // The nearest live node.
  int nearest(const JointVector& x);
  // A node that selection no longer considers (SST: inactive or pruned).
  void retire(int v) { retired_[v] = 1; }
  bool live(int v) const { return !retired_[v]; }
  // Children in the tree, per node (SST's pruning keeps it).
  std::vector<int>& children() { return children_; }

  const PlanningContext& ctx_;
  SearchState<TreeNode> s_;
  Random rng_;

 private:
  void sample(JointVector& x);
  int connect(int v);  // the goal node, or -1
  int add(TreeNode c, int from);

  double goal_bias_;
  std::vector<PathStep> commands_;
  std::vector<int> children_;
  std::vector<char> retired_;
};

// The context must have a sampling box of robot.dof joints.
void check_sampling_box(const PlanningContext& context, const std::string& planner);

// The base of the sampling planners (RRT, SST): setup checks the context's sampling box; each
// solve runs the planner's search.
class TreePlanner : public DeclaredPlanner {
 public:
  using DeclaredPlanner::DeclaredPlanner;

  void prepare(const PlanningContext& context) final { check_sampling_box(context, name()); }

  PlanResult solve(const PlanningProblem& problem, SimulatorWorkspace& ws, RolloutPool*) final {
    return search(context(), ws, problem);
  }

 protected:
  // One solve: the planner's own search.
  virtual PlanResult search(const PlanningContext& context, SimulatorWorkspace& ws,
                            const PlanningProblem& problem) = 0;
};

// A goal-biased sample: a joint goal with probability goal_bias, else uniform in the context's
// sampling box.
void sample_state(const PlanningContext& ctx, const PlanningProblem& problem, double goal_bias,
                  Random& rng, JointVector& x);

// goal_bias, as RRT and SST (ours and OMPL's) declare it.
ParameterSpec goal_bias_parameter();

}  // namespace lazyboe
