#include "lazyboe/bundle/settings.h"

namespace lazyboe {
namespace {

JointVector from_std(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

BuildSettings settings_from_header(const BundleHeader& h) {
  BuildSettings s;
  s.edges = h.target_edges;
  s.seed = h.seed;
  s.region_lower = from_std(h.region_lower);
  s.region_upper = from_std(h.region_upper);
  s.command.min_duration = h.min_duration;
  s.command.max_duration = h.max_duration;
  s.command.knot_interval = h.knot_interval;
  s.command.velocity_scale = h.velocity_scale;
  s.command.limit_scale = h.limit_scale;
  s.simulation.integrator = parse_integrator(h.integrator, "bundle header: integrator");
  s.simulation.substeps = h.substeps;
  s.simulation.sample_every = sample_every_ticks(h.sample_interval, h.control_rate);
  s.design_theta = h.design_theta;
  return s;
}

}  // namespace lazyboe
