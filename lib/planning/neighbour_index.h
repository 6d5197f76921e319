// RADIAL_NN over the bundle's edge start states (the planners' neighbourhoods) or end states
// (goal coverage): a k-d tree in flat arrays, built at load or mapped from the bundle's index
// file (edge_index_file.h), which holds the same arrays.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"

namespace lazyboe {

// The squared Euclidean distance between two joint vectors, summed in joint order: what the
// index calls the distance (a point is within a radius when this is strictly below its square),
// for scans that must answer exactly as the index does.
inline double squared_distance(const double* a, const double* b, int dof) {
  double d = 0;
  for (int k = 0; k < dof; ++k) {
    const double diff = a[k] - b[k];
    d += diff * diff;
  }
  return d;
}

// Edges with their squared distances, nearer first and equal distances by edge id: the order of
// EdgeIndex::nearest's result.
inline bool nearer_edge(const std::pair<uint32_t, double>& a,
                        const std::pair<uint32_t, double>& b) {
  return a.second < b.second || (a.second == b.second && a.first < b.first);
}

// Which state of every edge an index holds.
enum class EdgePoint { Start, End };

// One node of a k-d tree, as stored in memory and in the index file (32 bytes, no padding).
struct KdNode {
  static constexpr uint32_t kLeaf = 0xffffffffu;
  // Internal node: the largest coordinate `dim` of a point on the left (low) and the smallest
  // on the right (high); the children are nodes `first` (left) and `second`, both after this
  // one. Leaf (dim == kLeaf): the points order[first, second).
  double low = 0, high = 0;
  uint32_t first = 0, second = 0;
  uint32_t dim = kLeaf;
  uint32_t reserved = 0;
};
static_assert(sizeof(KdNode) == 32, "KdNode is a file format");

// A k-d tree's arrays, owned elsewhere: nodes in depth-first order (node 0 the root, leaves
// left to right covering order[] in sequence), the point ids leaf by leaf, and the points'
// bounding box (dof values each).
struct KdTreeArrays {
  const KdNode* nodes = nullptr;
  uint64_t node_count = 0;
  const uint32_t* order = nullptr;  // bundle size() ids, a permutation
  const double* lower = nullptr;
  const double* upper = nullptr;
};

// An index over the edge starts (the planners' neighbourhoods, queried thousands of times a
// solve) also keeps a copy of its points in leaf order, each leaf's by joint: dof doubles per
// edge of private memory for radius queries that read contiguous memory rather than rows
// spread over the bundle.
class EdgeIndex {
 public:
  static constexpr uint32_t kLeafSize = 16;

  // Builds the tree over the bundle's edge starts (or ends).
  explicit EdgeIndex(const BundleView& bundle, EdgePoint point = EdgePoint::Start);
  // A tree read from an index file: `arrays` point into `storage`, which the index keeps alive.
  // Throws Error (naming `where`) unless the arrays form a well-shaped tree over the bundle's
  // edges (every id once, leaves in sequence, children after parents, depth at most 64) with
  // every edge state inside its leaf's cell, so that it answers as a built tree would.
  EdgeIndex(const BundleView& bundle, EdgePoint point, const KdTreeArrays& arrays,
            std::shared_ptr<const void> storage, const std::string& where);
  ~EdgeIndex();
  EdgeIndex(const EdgeIndex&) = delete;
  EdgeIndex& operator=(const EdgeIndex&) = delete;

  EdgePoint point() const;
  const KdTreeArrays& arrays() const;  // for writing the tree to an index file

  // Edges whose start (end, for an EdgePoint::End index) lies within `radius` (Euclidean, joint
  // space) of q, with their squared distances, sorted by edge id so results do not depend on
  // the tree's shape. `out` is reused (no allocation once it has grown).
  void within(const double* q, double radius, std::vector<std::pair<uint32_t, double>>& out) const;
  // Whether some edge's start (end) lies within `radius` of q: the search stops at the first.
  bool any_within(const double* q, double radius) const;
  // The `count` edges whose start (end) lies nearest q within `radius`, nearest first (equal
  // distances by edge id), with their squared distances; `out` is reused.
  void nearest(const double* q, size_t count, double radius,
               std::vector<std::pair<uint32_t, double>>& out) const;

 private:
  // Fills `out` when it is not null (with the `nearest` nearest only, as a max-heap, when that
  // is not 0); returns whether some point was found.
  bool search(const double* q, double radius, std::vector<std::pair<uint32_t, double>>* out,
              size_t nearest = 0) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lazyboe
