// The bundle the edge_index fuzz target's inputs are indexes of: 300 edges of 7 joints, their
// states on a coarse grid (duplicates and shared coordinates, as real bundles have after the
// settle), everything else minimal. A function of nothing, so the committed seeds (its index
// files, tests/fuzz/corpus/edge_index) stay valid.
#pragma once

#include <memory>

#include "lazyboe/bundle/bundle.h"

namespace lazyboe::fuzz {

inline std::shared_ptr<const Bundle> edge_index_bundle() {
  constexpr int kDof = 7;
  constexpr size_t kEdges = 300;
  auto b = std::make_shared<Bundle>();
  b->header.complete = true;
  b->header.dof = kDof;
  b->header.region_lower.assign(kDof, -1.0);
  b->header.region_upper.assign(kDof, 1.0);
  b->knot_offset = {0};
  b->sample_offset = {0};
  uint64_t state = 12345;
  const auto grid = [&] {  // a small LCG: -1, -0.75, ..., 1
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>((state >> 33) % 9) / 4.0 - 1.0;
  };
  for (size_t e = 0; e < kEdges; ++e) {
    for (int j = 0; j < kDof; ++j) b->q0.push_back(grid());
    for (int j = 0; j < kDof; ++j) b->qf.push_back(grid());
    for (int r = 0; r < 2 * kDof; ++r) b->knots.push_back(0.0);
    b->knot_offset.push_back(b->knot_offset.back() + 2);
    b->sample_offset.push_back(0);
    b->duration.push_back(0.5);
    b->command_duration.push_back(0.4);
    b->attempt.push_back(e);
  }
  return b;
}

}  // namespace lazyboe::fuzz
