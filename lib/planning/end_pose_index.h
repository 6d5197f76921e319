// Goal coverage for pose goals (issue 29): the pose of a link at every bundle edge's end state,
// in a k-d tree over the link's position (nanoflann), so that a pose goal finds the edges that
// end near it without a scan. Their end states seed inverse kinematics (goal_region.cpp), which
// then lands on configurations the bundle's edges reach.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/per_link.h"
#include "lazyboe/robot/inverse_kinematics.h"

namespace lazyboe {

class EndPoseIndex {
 public:
  // FK of every edge end (OpenMP threads; the result does not depend on their number).
  EndPoseIndex(const BundleView& bundle, const RobotModel& robot, int link);
  ~EndPoseIndex();
  EndPoseIndex(const EndPoseIndex&) = delete;
  EndPoseIndex& operator=(const EndPoseIndex&) = delete;

  int link() const { return link_; }
  const double* end_state(uint32_t edge) const { return bundle_.qf(edge); }
  size_t size() const { return rotations_.size(); }
  double build_seconds() const { return build_seconds_; }
  // Up to `count` edges whose end pose is nearest `target`, nearest first (ties by edge id), by
  // the pose goals' heuristic: the larger of the position error and the orientation error
  // weighted by position_tolerance / orientation_tolerance (problem.h). Ranked among the
  // kCandidates nearest by position. `out` is replaced.
  void nearest(const PoseTarget& target, size_t count, std::vector<uint32_t>& out) const;

  static constexpr size_t kCandidates = 64;

 private:
  struct Tree;
  const BundleView& bundle_;
  int link_;
  std::vector<double> positions_;  // x, y, z per edge
  std::vector<Eigen::Matrix3d> rotations_;
  std::unique_ptr<Tree> tree_;
  double build_seconds_ = 0;
};

// The end-pose indexes of a bundle, one per link a pose goal names, each built on first use.
class EndPoseIndexes : public PerLink<EndPoseIndex> {
 public:
  using PerLink::PerLink;
};

}  // namespace lazyboe
