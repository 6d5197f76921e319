// RADIAL_NN over the bundle's edge start states: a k-d tree (nanoflann) built at load.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"

namespace lazyboe {

class EdgeStartIndex {
 public:
  explicit EdgeStartIndex(const BundleView& bundle);
  ~EdgeStartIndex();
  EdgeStartIndex(const EdgeStartIndex&) = delete;
  EdgeStartIndex& operator=(const EdgeStartIndex&) = delete;

  // Edges whose start lies within `radius` (Euclidean, joint space) of q, sorted by edge id so
  // results do not depend on the tree's traversal order. `out` is reused (no allocation once
  // it has grown).
  void within(const double* q, double radius, std::vector<std::pair<uint32_t, double>>& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lazyboe
