// How each bundle edge's stored motion moves one link (issue 29, end-effector limits): the
// largest linear speed and acceleration of the link's origin, by finite differences of its
// positions at the stored samples (every sample_interval, from the edge's start at rest to its
// end). Differences average over the sample spacing, so both are lower bounds of the motion's
// peaks (up to the float precision of the samples): an edge whose figures break a task's limit
// breaks it when simulated from its own start, and applied near it (displacement transfer),
// very likely too. lazysp leaves such edges out of its lazy search (docs/task.md), from every
// state: the growth, which is not limited so, keeps the planner complete.
#pragma once

#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/per_link.h"

namespace lazyboe {

struct LinkMotion {
  float max_speed = 0;         // m/s
  float max_acceleration = 0;  // m/s^2
};

class EdgeLinkMotion {
 public:
  // Forward kinematics of every stored sample (OpenMP threads; the result does not depend on
  // their number).
  EdgeLinkMotion(const BundleView& bundle, const RobotModel& robot, int link);

  int link() const { return link_; }
  const LinkMotion& operator[](size_t edge) const { return motion_[edge]; }
  double build_seconds() const { return build_seconds_; }

 private:
  int link_;
  std::vector<LinkMotion> motion_;
  double build_seconds_ = 0;
};

// The tables of a bundle, one per link a task limits, each made at its first use.
class EdgeLinkMotions : public PerLink<EdgeLinkMotion> {
 public:
  using PerLink::PerLink;
};

}  // namespace lazyboe
