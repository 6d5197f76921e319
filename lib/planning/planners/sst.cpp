#include "lazyboe/planning/planners/sst.h"

#include <limits>

#include "lazyboe/planning/planners/tree_search.h"

namespace lazyboe {
namespace {

class SstSearch : public TreeSearch {
 public:
  SstSearch(const PlanningContext& ctx, SimulatorWorkspace& ws, const PlanningProblem& p,
            const ParameterValues& values)
      : TreeSearch(ctx, ws, p, values),
        delta_bn_(values.get("selection_radius")),
        delta_s_(values.get("pruning_ratio") * values.get("selection_radius")) {}

 private:
  struct Witness {
    JointVector q;
    int representative;
  };

  void start(const TreeNode& root) override { witnesses_.push_back({root.q, 0}); }

  // Best-Near: the lowest-cost active node within delta_BN, else the nearest.
  int select(const JointVector& x) override {
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    const std::vector<TreeNode>& nodes = s_.nodes();
    for (size_t v = 0; v < nodes.size(); ++v) {
      if (!live(static_cast<int>(v))) continue;
      if ((nodes[v].q - x).norm() <= delta_bn_ && nodes[v].cost < best_cost) {
        best_cost = nodes[v].cost;
        best = static_cast<int>(v);
      }
    }
    return best >= 0 ? best : nearest(x);
  }

  // A node joins when it is the first or the cheapest near its witness (a new witness when
  // none is within delta_s); the representative it replaces becomes inactive.
  bool admit(const TreeNode& c) override {
    witness_ = nearest_witness(c.q);
    if (witness_ < 0 || (witnesses_[witness_].q - c.q).norm() > delta_s_) {
      witnesses_.push_back({c.q, -1});
      witness_ = static_cast<int>(witnesses_.size()) - 1;
    }
    const int rep = witnesses_[witness_].representative;
    if (rep >= 0 && s_.node(rep).cost <= c.cost) return false;  // not better locally: drop
    if (rep >= 0) {
      retire(rep);  // inactive: no longer its witness's representative
      prune_upwards(rep);
    }
    return true;
  }

  // The node and its now childless ancestors, upwards, are removed from the tree while
  // inactive.
  void prune_upwards(int v) {
    std::vector<int>& children = this->children();
    pruned_.resize(s_.nodes().size(), 0);
    while (v > 0 && !live(v) && !pruned_[v] && children[v] == 0) {
      pruned_[v] = 1;
      const int parent = s_.node(v).parent;
      --children[parent];
      v = parent;
    }
  }

  void added(int id) override { witnesses_[witness_].representative = id; }
  bool stop_at_solution() const override { return false; }

  int nearest_witness(const JointVector& q) const {
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t w = 0; w < witnesses_.size(); ++w) {
      const double d = (witnesses_[w].q - q).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(w);
      }
    }
    return best;
  }

  const double delta_bn_, delta_s_;
  std::vector<Witness> witnesses_;
  int witness_ = -1;          // of the node being admitted
  std::vector<char> pruned_;  // removed from the tree (retired, and no children left)
};

class Sst final : public TreePlanner {
 public:
  using TreePlanner::TreePlanner;

 private:
  PlanResult search(const PlanningContext& context, SimulatorWorkspace& ws,
                    const PlanningProblem& problem) override {
    return SstSearch(context, ws, problem, values()).run();
  }
};

}  // namespace

ParameterSpec selection_radius_parameter() {
  return real_parameter("selection_radius", 0.2, 0, true, "SST's selection radius delta_BN, rad");
}

ParameterSpec pruning_ratio_parameter() {
  return real_parameter("pruning_ratio", 1.0, 0, true,
                        "SST's pruning radius delta_s as a multiple of the selection radius");
}

PlannerInfo sst_planner_info() {
  PlannerInfo info;
  info.name = "sst";
  info.description = "Stable Sparse RRT: Best-Near selection and witness pruning; anytime";
  info.parameters = {goal_bias_parameter(), selection_radius_parameter(),
                     pruning_ratio_parameter()};
  info.make = planner_factory<Sst>(info);
  return info;
}

}  // namespace lazyboe
