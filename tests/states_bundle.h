// A complete bundle that holds given edge states and nothing else of note (two zero knots per
// edge, fixed durations, no samples): what the k-d tree code reads, for the edge_index fuzz
// target and bench_index, which make their states without simulating.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>

#include "lazyboe/bundle/bundle.h"

namespace lazyboe::test {

// `edges` edges of `dof` joints; next() gives the states in order: q0 of edge 0, qf of edge 0,
// q0 of edge 1, ...; the sampling region's box is [lower, upper] in every joint.
inline std::shared_ptr<const Bundle> states_bundle(size_t edges, int dof, double lower,
                                                   double upper,
                                                   const std::function<double()>& next) {
  auto b = std::make_shared<Bundle>();
  b->header.complete = true;
  b->header.dof = dof;
  b->header.region_lower.assign(dof, lower);
  b->header.region_upper.assign(dof, upper);
  b->knot_offset = {0};
  b->sample_offset = {0};
  for (size_t e = 0; e < edges; ++e) {
    for (int j = 0; j < dof; ++j) b->q0.push_back(next());
    for (int j = 0; j < dof; ++j) b->qf.push_back(next());
    b->knots.resize(b->knots.size() + 2 * static_cast<size_t>(dof), 0.0);
    b->knot_offset.push_back(b->knot_offset.back() + 2);
    b->sample_offset.push_back(0);
    b->duration.push_back(0.5);
    b->command_duration.push_back(0.4);
    b->attempt.push_back(e);
  }
  return b;
}

}  // namespace lazyboe::test
