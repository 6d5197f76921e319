#include "lazyboe/planning/edge_link_motion.h"

#include <algorithm>
#include <chrono>

#include "lazyboe/robot/kinematics.h"

namespace lazyboe {

namespace {

// One edge's figures: the link's positions at the stored samples, every `interval` from the
// start (at rest) and the end state at the edge's duration. The mean velocities
// over consecutive intervals differ by at most the peak acceleration times the time between
// their midpoints, so each difference over that time is a lower bound of the peak.
LinkMotion edge_motion(const BundleView& b, const RobotModel& robot, int link, size_t e,
                       double interval, RobotData& data, std::vector<Eigen::Vector3d>& p,
                       std::vector<double>& t) {
  const int n = b.dof();
  const size_t samples = b.sample_count(e);
  p.clear();
  t.clear();
  for (size_t k = 0; k < samples; ++k) {
    const JointVector q = Eigen::Map<const Eigen::VectorXf>(b.samples(e) + k * n, n).cast<double>();
    forward_kinematics(robot, data, q);
    p.push_back(link_pose(robot, data, link).p);
    const double uniform = static_cast<double>(k) * interval;
    t.push_back(k + 1 == samples && k > 0 ? b.duration(e) : uniform);
  }
  LinkMotion m;
  Eigen::Vector3d v_prev = Eigen::Vector3d::Zero();  // at rest at the start
  double t_mid_prev = 0;
  for (size_t k = 1; k < p.size(); ++k) {
    const double h = t[k] - t[k - 1];
    if (!(h > 0)) continue;                           // an end state at a sample's time
    const Eigen::Vector3d v = (p[k] - p[k - 1]) / h;  // the mean velocity over the interval
    const double t_mid = (t[k] + t[k - 1]) / 2;
    m.max_speed = std::max(m.max_speed, static_cast<float>(v.norm()));
    const double a = (v - v_prev).norm() / (t_mid - t_mid_prev);
    m.max_acceleration = std::max(m.max_acceleration, static_cast<float>(a));
    v_prev = v;
    t_mid_prev = t_mid;
  }
  if (p.size() > 1) {  // at rest again at the end
    const double a = v_prev.norm() / (t.back() - t_mid_prev);
    m.max_acceleration = std::max(m.max_acceleration, static_cast<float>(a));
  }
  return m;
}

}  // namespace

EdgeLinkMotion::EdgeLinkMotion(const BundleView& bundle, const RobotModel& robot, int link)
    : link_(link), motion_(bundle.size()) {
  const auto started = std::chrono::steady_clock::now();
  const double interval = bundle.header().sample_interval;
  const long edges = static_cast<long>(bundle.size());
  if (interval > 0) {
#pragma omp parallel
    {
      RobotData data(robot);
      std::vector<Eigen::Vector3d> p;
      std::vector<double> t;
#pragma omp for schedule(dynamic, 256)
      for (long e = 0; e < edges; ++e)
        motion_[e] = edge_motion(bundle, robot, link, e, interval, data, p, t);
    }
  }
  build_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
}

}  // namespace lazyboe
