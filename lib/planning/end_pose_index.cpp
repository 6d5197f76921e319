#include "lazyboe/planning/end_pose_index.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <nanoflann.hpp>

namespace lazyboe {

namespace {

// nanoflann's view of the flat positions.
struct PositionCloud {
  const std::vector<double>& xyz;
  size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  double kdtree_get_pt(size_t i, size_t dim) const { return xyz[3 * i + dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

}  // namespace

struct EndPoseIndex::Tree {
  using Index =
      nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PositionCloud>,
                                          PositionCloud, 3, uint32_t>;
  explicit Tree(const std::vector<double>& xyz)
      : cloud{xyz}, index(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
  PositionCloud cloud;
  Index index;
};

EndPoseIndex::EndPoseIndex(const BundleView& bundle, const RobotModel& robot, int link)
    : bundle_(bundle), link_(link), positions_(3 * bundle.size()), rotations_(bundle.size()) {
  const auto started = std::chrono::steady_clock::now();
  const long n = static_cast<long>(bundle.size());
#pragma omp parallel
  {
    RobotData data(robot);
#pragma omp for schedule(static)
    for (long e = 0; e < n; ++e) {
      forward_kinematics(robot, data, Eigen::Map<const JointVector>(bundle.qf(e), robot.dof));
      const Pose pose = link_pose(robot, data, link);
      for (int c = 0; c < 3; ++c) positions_[3 * e + c] = pose.p[c];
      rotations_[e] = pose.R;
    }
  }
  tree_ = std::make_unique<Tree>(positions_);
  build_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
}

EndPoseIndex::~EndPoseIndex() = default;

void EndPoseIndex::nearest(const PoseTarget& target, size_t count,
                           std::vector<uint32_t>& out) const {
  out.clear();
  const size_t k = std::min(kCandidates, size());
  std::vector<uint32_t> ids(k);
  std::vector<double> squared(k);
  ids.resize(tree_->index.knnSearch(target.position.data(), k, ids.data(), squared.data()));
  const double weight = target.position_tolerance / target.orientation_tolerance;
  std::vector<std::pair<double, uint32_t>> ranked;
  for (const uint32_t e : ids) {
    const Pose pose{rotations_[e], Eigen::Map<const Eigen::Vector3d>(&positions_[3 * e])};
    const PoseError error = pose_error(target, pose);
    const double turn = target.has_orientation ? error.orientation * weight : 0.0;
    ranked.emplace_back(std::max(error.position, turn), e);
  }
  std::sort(ranked.begin(), ranked.end());
  for (size_t i = 0; i < std::min(count, ranked.size()); ++i) out.push_back(ranked[i].second);
}

}  // namespace lazyboe
