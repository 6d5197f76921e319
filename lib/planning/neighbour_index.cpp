#include "lazyboe/planning/neighbour_index.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <string>

#include "lazyboe/common/error.h"
#include "lazyboe/common/huge_pages.h"
#include "lazyboe/robot/types.h"

namespace lazyboe {

namespace {

constexpr int kMaxDepth = 64;  // a median split tree over 2^32 points is 29 deep

const double* point_rows(const BundleView& b, EdgePoint point) {
  if (b.size() == 0) return nullptr;
  return point == EdgePoint::Start ? b.q0(0) : b.qf(0);
}

// The tree over `count` rows of `dof` values: median splits in the dimension of the largest
// spread (estimated from about kSpreadSample points of a node, evenly spaced), ties between
// equal coordinates broken by id so that the tree depends on the points alone. The split itself
// runs on a contiguous (coordinate, id) copy: selecting through the ids is cache-bound.
class TreeBuilder {
 public:
  TreeBuilder(const double* rows, size_t count, int dof) : rows_(rows), dof_(dof) {
    order.resize(count);
    std::iota(order.begin(), order.end(), 0u);
    keys_.resize(count);
    nodes.reserve(2 * count / EdgeIndex::kLeafSize + 1);
    lower.assign(static_cast<size_t>(dof), 0.0);
    upper.assign(static_cast<size_t>(dof), 0.0);
    if (count > 0) bounds(0, static_cast<uint32_t>(count), 1, lower.data(), upper.data());
    make(0, static_cast<uint32_t>(count));
    std::vector<Key>().swap(keys_);  // scratch: the tree keeps only its arrays
  }

  std::vector<KdNode> nodes;
  std::vector<uint32_t> order;
  std::vector<double> lower, upper;

 private:
  static constexpr uint32_t kSpreadSample = 256;
  using Key = std::pair<double, uint32_t>;  // coordinate, id

  double at(uint32_t id, int dim) const { return rows_[size_t{id} * dof_ + dim]; }

  // The box of the points order[begin], order[begin + stride], ... below end.
  void bounds(uint32_t begin, uint32_t end, uint32_t stride, double* lo, double* hi) const {
    for (int d = 0; d < dof_; ++d) lo[d] = hi[d] = at(order[begin], d);
    for (uint32_t i = begin + stride; i < end; i += stride) {
      for (int d = 0; d < dof_; ++d) {
        lo[d] = std::min(lo[d], at(order[i], d));
        hi[d] = std::max(hi[d], at(order[i], d));
      }
    }
  }

  int widest_dimension(uint32_t begin, uint32_t end, uint32_t stride) const {
    std::array<double, kMaxDof> lo{}, hi{};
    bounds(begin, end, stride, lo.data(), hi.data());
    int widest = 0;
    for (int d = 1; d < dof_; ++d)
      if (hi[d] - lo[d] > hi[widest] - lo[widest]) widest = d;
    return widest;
  }

  // Splits order[begin, end) at its median in `dim`; false when all coordinates are equal.
  bool split(uint32_t begin, uint32_t end, int dim, KdNode& node) {
    const auto keys = keys_.begin() + begin, keys_end = keys_.begin() + end;
    for (uint32_t i = begin; i < end; ++i) keys_[i] = Key{at(order[i], dim), order[i]};
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(keys, keys_.begin() + mid, keys_end);
    const double high = keys_[mid].first;  // the smallest on the right, by nth_element
    double low = keys[0].first;
    for (uint32_t i = begin + 1; i < mid; ++i) low = std::max(low, keys_[i].first);
    if (low == high &&
        std::min_element(keys, keys_end)->first == std::max_element(keys, keys_end)->first)
      return false;
    for (uint32_t i = begin; i < end; ++i) order[i] = keys_[i].second;
    node = KdNode{low, high, 0, 0, static_cast<uint32_t>(dim), 0};
    return true;
  }

  uint32_t make(uint32_t begin, uint32_t end) {
    const uint32_t self = static_cast<uint32_t>(nodes.size());
    nodes.emplace_back();
    KdNode node;
    const uint32_t sampled = std::max(1u, (end - begin) / kSpreadSample);
    // All sampled points equal in the widest sampled dimension: the exact widest one.
    if (end - begin <= EdgeIndex::kLeafSize ||
        !(split(begin, end, widest_dimension(begin, end, sampled), node) ||
          split(begin, end, widest_dimension(begin, end, 1), node))) {
      nodes[self].first = begin;
      nodes[self].second = end;
      return self;
    }
    const uint32_t mid = begin + (end - begin) / 2;
    node.first = make(begin, mid);
    node.second = make(mid, end);
    nodes[self] = node;
    return self;
  }

  const double* rows_;
  int dof_;
  std::vector<Key> keys_;
};

// What a search gives: every point within the radius, whether there is one (stopping at the
// first), or the `nearest` nearest within it. A template parameter, so that the radius query the
// planners run thousands of times a solve tests nothing in its inner loop that it does not need.
enum class SearchMode { Within, Any, Nearest };

// The search's state: the query, the squared radius, and the distance from q to the current
// node's cell per dimension (the incremental bound of Arya and Mount, as nanoflann does).
// Nearest: `out` is a max-heap of the nearest so far, and once it is full the radius shrinks to
// its farthest.
template <SearchMode Mode>
struct Search {
  const KdTreeArrays& tree;
  const double* rows;
  bool leaf_ordered;  // rows are Impl::leaf_rows, by leaf and column (else the bundle's rows)
  int dof;
  const double* q;
  double r2, prune;  // prune: r2 with a margin, so that rounding in the bound never drops a point
  std::array<double, kMaxDof> cell{};
  std::vector<std::pair<uint32_t, double>>* out;  // null for SearchMode::Any
  size_t nearest = 0;
  bool found = false;

  void leaf(const KdNode& n) {
    if (leaf_ordered) return leaf_columns(n);
    for (uint32_t i = n.first; i < n.second; ++i) {
      if (!take(i, squared_distance(q, rows + size_t{tree.order[i]} * dof, dof))) return;
    }
  }

  // A leaf stored by columns (EdgeIndex::Impl::order_rows): its points' distances a block of
  // kBlock at a time, in loops over the points the compiler vectorises, each summed in joint
  // order as squared_distance does (the same values to the bit).
  void leaf_columns(const KdNode& n) {
    constexpr uint32_t kBlock = 16;
    const uint32_t count = n.second - n.first;
    const double* columns = rows + size_t{n.first} * dof;
    for (uint32_t b = 0; b < count; b += kBlock) {
      const uint32_t m = std::min(kBlock, count - b);
      std::array<double, kBlock> d{};
      for (int k = 0; k < dof; ++k) {
        const double* column = columns + static_cast<size_t>(k) * count + b;
        const double qk = q[k];
        for (uint32_t j = 0; j < m; ++j) {
          const double diff = qk - column[j];
          d[j] += diff * diff;
        }
      }
      for (uint32_t j = 0; j < m; ++j) {
        if (!take(n.first + b + j, d[j])) return;
      }
    }
  }

  // Point i of the leaf order at squared distance d; false when the search is done (Any).
  bool take(uint32_t i, double d) {
    if constexpr (Mode == SearchMode::Nearest) {
      // Full of nearest ones, the radius is the farthest kept: a tie may still replace it by id.
      if (d > r2 || (d == r2 && out->size() < nearest)) return true;
      keep_nearest(tree.order[i], d);
    } else {
      if (d >= r2) return true;
      found = true;
      if constexpr (Mode == SearchMode::Any) return false;
      out->emplace_back(tree.order[i], d);
    }
    return true;
  }

  void keep_nearest(uint32_t id, double d) {
    if (out->size() == nearest) {
      if (!nearer_edge({id, d}, out->front())) return;
      std::pop_heap(out->begin(), out->end(), nearer_edge);
      out->pop_back();
    }
    out->emplace_back(id, d);
    std::push_heap(out->begin(), out->end(), nearer_edge);
    if (out->size() == nearest) {
      r2 = out->front().second;
      prune = r2 * (1 + 1e-9);
    }
  }

  void visit(uint32_t node, double bound) {
    const KdNode& n = tree.nodes[node];
    if (n.dim == KdNode::kLeaf) return leaf(n);
    const double to_low = q[n.dim] - n.low, to_high = q[n.dim] - n.high;
    const bool left_first = to_low + to_high < 0;
    const double far_gap = left_first ? to_high * to_high : to_low * to_low;
    visit(left_first ? n.first : n.second, bound);
    if constexpr (Mode == SearchMode::Any) {
      if (found) return;
    }
    const double saved = cell[n.dim];
    const double far_bound = bound + far_gap - saved;
    if (far_bound <= prune) {
      cell[n.dim] = far_gap;
      visit(left_first ? n.second : n.first, far_bound);
      cell[n.dim] = saved;
    }
  }

  // Searches from the root, whose cell is the points' bounding box; returns whether a point
  // was found.
  bool run() {
    double bound = 0;
    for (int d = 0; d < dof; ++d) {
      const double gap = std::max({tree.lower[d] - q[d], q[d] - tree.upper[d], 0.0});
      cell[d] = gap * gap;
      bound += cell[d];
    }
    if (bound <= prune) visit(0, bound);
    if constexpr (Mode == SearchMode::Nearest) return !out->empty();
    return found;
  }
};

// Checks a tree read from a file in one walk: every node reached once from the root, children
// after their parent, depth bounded, leaves covering order[] in sequence, order[] a permutation
// of the ids; and every point inside its leaf's cell (the bounding box cut by the splits above
// it), so that searching the tree finds exactly what a scan finds.
class TreeCheck {
 public:
  TreeCheck(const KdTreeArrays& t, const double* rows, size_t points, int dof, std::string where)
      : t_(t), rows_(rows), points_(points), dof_(dof), where_(std::move(where)) {}

  void run() {
    if (t_.node_count == 0 || t_.node_count > 2 * points_ + 1) bad("node count");
    std::vector<bool> seen(points_, false);
    for (size_t i = 0; i < points_; ++i) {
      if (t_.order[i] >= points_ || seen[t_.order[i]]) bad("point order is not a permutation");
      seen[t_.order[i]] = true;
    }
    reached_.assign(t_.node_count, false);
    std::copy(t_.lower, t_.lower + dof_, lo_.begin());
    std::copy(t_.upper, t_.upper + dof_, hi_.begin());
    visit(0, 0);
    if (next_point_ != points_ || reached_count_ != t_.node_count)
      bad("leaves do not cover the points");
  }

 private:
  [[noreturn]] void bad(const std::string& what) const {
    fail(where_, "malformed k-d tree: " + what);
  }

  void leaf(const KdNode& n) {
    if (n.first != next_point_ || n.second < n.first || n.second > points_) bad("leaf range");
    next_point_ = n.second;
    // The leaf's rows lie anywhere in the bundle: ask for all of them before reading one.
    for (uint32_t i = n.first; i < n.second; ++i)
      __builtin_prefetch(rows_ + size_t{t_.order[i]} * dof_);
    for (uint32_t i = n.first; i < n.second; ++i) {
      const double* p = rows_ + size_t{t_.order[i]} * dof_;
      for (int d = 0; d < dof_; ++d)
        if (!(p[d] >= lo_[d] && p[d] <= hi_[d])) bad("a point outside its cell");
    }
  }

  void visit(uint64_t index, int depth) {
    if (reached_[index]) bad("a node with two parents");
    reached_[index] = true;
    ++reached_count_;
    const KdNode& n = t_.nodes[index];
    if (n.dim == KdNode::kLeaf) return leaf(n);
    if (n.dim >= static_cast<uint32_t>(dof_) || !(n.low <= n.high)) bad("split");
    if (n.first <= index || n.second <= index || n.first >= t_.node_count ||
        n.second >= t_.node_count || depth >= kMaxDepth)
      bad("child link");
    const double saved_hi = hi_[n.dim], saved_lo = lo_[n.dim];
    hi_[n.dim] = std::min(saved_hi, n.low);
    visit(n.first, depth + 1);
    hi_[n.dim] = saved_hi;
    lo_[n.dim] = std::max(saved_lo, n.high);
    visit(n.second, depth + 1);
    lo_[n.dim] = saved_lo;
  }

  const KdTreeArrays& t_;
  const double* rows_;
  size_t points_;
  int dof_;
  std::string where_;
  std::vector<bool> reached_;
  std::array<double, kMaxDof> lo_{}, hi_{};
  uint64_t next_point_ = 0, reached_count_ = 0;
};

}  // namespace

struct EdgeIndex::Impl {
  EdgePoint point;
  const double* rows;
  int dof;
  KdTreeArrays arrays;
  std::shared_ptr<const void> storage;  // what `arrays` point into
  // An index over the edge starts (the planners' neighbourhoods, queried thousands of times a
  // solve) keeps its points again in leaf order, so that a leaf's scan reads contiguous memory
  // instead of rows spread over the bundle: cache misses were most of a radius query's time.
  // dof doubles per edge; the end index (goal coverage, a few queries a solve) reads the bundle.
  HugePageArray<double> leaf_rows = {};

  // Each leaf's points are stored by columns: its first joint's values, then its second's...
  // (Search::leaf_columns reads them a block at a time).
  void order_rows(size_t count) {
    if (rows == nullptr || point != EdgePoint::Start) return;
    leaf_rows = HugePageArray<double>(count * static_cast<size_t>(dof));
    for (uint64_t v = 0; v < arrays.node_count; ++v) {
      const KdNode& n = arrays.nodes[v];
      if (n.dim != KdNode::kLeaf) continue;
      const size_t points = n.second - n.first;
      double* columns = leaf_rows.data() + size_t{n.first} * dof;
      for (size_t j = 0; j < points; ++j)
        for (int k = 0; k < dof; ++k)
          columns[k * points + j] = rows[size_t{arrays.order[n.first + j]} * dof + k];
    }
  }
};

EdgeIndex::EdgeIndex(const BundleView& bundle, EdgePoint point)
    : impl_(std::make_unique<Impl>(
          Impl{point, point_rows(bundle, point), bundle.dof(), KdTreeArrays{}, nullptr})) {
  auto built = std::make_shared<TreeBuilder>(impl_->rows, bundle.size(), bundle.dof());
  impl_->arrays = KdTreeArrays{built->nodes.data(), built->nodes.size(), built->order.data(),
                               built->lower.data(), built->upper.data()};
  impl_->storage = std::move(built);
  impl_->order_rows(bundle.size());
}

EdgeIndex::EdgeIndex(const BundleView& bundle, EdgePoint point, const KdTreeArrays& arrays,
                     std::shared_ptr<const void> storage, const std::string& where)
    : impl_(std::make_unique<Impl>(
          Impl{point, point_rows(bundle, point), bundle.dof(), arrays, std::move(storage)})) {
  TreeCheck(arrays, impl_->rows, bundle.size(), bundle.dof(), where).run();
  impl_->order_rows(bundle.size());
}

EdgeIndex::~EdgeIndex() = default;

EdgePoint EdgeIndex::point() const { return impl_->point; }
const KdTreeArrays& EdgeIndex::arrays() const { return impl_->arrays; }

bool EdgeIndex::search(const double* q, double radius,
                       std::vector<std::pair<uint32_t, double>>* out, size_t nearest) const {
  const Impl& m = *impl_;
  if (m.rows == nullptr) return false;
  const double r2 = radius * radius, prune = r2 * (1 + 1e-9);
  const bool leaf_ordered = !m.leaf_rows.empty();
  const double* rows = leaf_ordered ? m.leaf_rows.data() : m.rows;
  if (out == nullptr) {
    return Search<SearchMode::Any>{m.arrays, rows, leaf_ordered, m.dof, q, r2, prune, {}, out}
        .run();
  }
  if (nearest == 0) {
    return Search<SearchMode::Within>{m.arrays, rows, leaf_ordered, m.dof, q, r2, prune, {}, out}
        .run();
  }
  return Search<SearchMode::Nearest>{m.arrays, rows,  leaf_ordered, m.dof, q,
                                     r2,       prune, {},           out,   nearest}
      .run();
}

void EdgeIndex::within(const double* q, double radius,
                       std::vector<std::pair<uint32_t, double>>& out) const {
  out.clear();
  search(q, radius, &out);
  std::sort(out.begin(), out.end());
}

bool EdgeIndex::any_within(const double* q, double radius) const {
  return search(q, radius, nullptr);
}

void EdgeIndex::nearest(const double* q, size_t count, double radius,
                        std::vector<std::pair<uint32_t, double>>& out) const {
  out.clear();
  if (count == 0) return;
  search(q, radius, &out, count);
  std::sort_heap(out.begin(), out.end(), nearer_edge);
}

}  // namespace lazyboe
