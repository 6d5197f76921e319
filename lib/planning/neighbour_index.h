// RADIAL_NN over the bundle's edge start states (the planners' neighbourhoods) or end states
// (goal coverage): a k-d tree (nanoflann) built at load.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"

namespace lazyboe {

// Which state of every edge an index holds.
enum class EdgePoint { Start, End };

class EdgeIndex {
 public:
  explicit EdgeIndex(const BundleView& bundle, EdgePoint point = EdgePoint::Start);
  ~EdgeIndex();
  EdgeIndex(const EdgeIndex&) = delete;
  EdgeIndex& operator=(const EdgeIndex&) = delete;

  EdgePoint point() const;

  // Edges whose start (end, for an EdgePoint::End index) lies within `radius` (Euclidean, joint
  // space) of q, sorted by edge id so results do not depend on the tree's traversal order. `out` is
  // reused (no allocation once it has grown).
  void within(const double* q, double radius, std::vector<std::pair<uint32_t, double>>& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lazyboe
