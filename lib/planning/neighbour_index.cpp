#include "lazyboe/planning/neighbour_index.h"

#include <algorithm>
#include <nanoflann.hpp>

namespace lazyboe {

namespace {

// nanoflann's view of the edge starts (or ends): `count` rows of `dof` values. The row pointer is
// taken once, not per coordinate: nanoflann reads a coordinate at a time in its inner loops.
struct EdgeRows {
  EdgePoint point;
  const double* rows;
  size_t count, dof;
  size_t kdtree_get_point_count() const { return count; }
  double kdtree_get_pt(size_t idx, size_t dim) const { return rows[idx * dof + dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, EdgeRows>,
                                                 EdgeRows, -1, uint32_t>;

}  // namespace

struct EdgeIndex::Impl {
  EdgeRows points;
  Tree tree;
  Impl(const BundleView& b, EdgePoint point)
      : points{point,
               b.size() == 0               ? nullptr
               : point == EdgePoint::Start ? b.q0(0)
                                           : b.qf(0),
               b.size(), static_cast<size_t>(b.dof())},
        tree(b.dof(), points, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
};

EdgeIndex::EdgeIndex(const BundleView& bundle, EdgePoint point)
    : impl_(std::make_unique<Impl>(bundle, point)) {}
EdgeIndex::~EdgeIndex() = default;

EdgePoint EdgeIndex::point() const { return impl_->points.point; }

void EdgeIndex::within(const double* q, double radius,
                       std::vector<std::pair<uint32_t, double>>& out) const {
  nanoflann::SearchParams params;
  params.sorted = false;
  impl_->tree.radiusSearch(q, radius * radius, out, params);  // squared distances for L2_Simple
  std::sort(out.begin(), out.end());
}

}  // namespace lazyboe
