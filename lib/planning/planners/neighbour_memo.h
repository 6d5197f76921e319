// A memo of the radius queries of lazysp's lazy search (internal; not installed). The search is
// rebuilt from the real nodes every round, and most predicted states of a round recur in the
// next bit for bit (the same source and edges give the same sums), so their neighbourhoods are
// looked up rather than queried again. It answers exactly as the index does, in its order.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <utility>
#include <vector>

#include "lazyboe/planning/neighbour_index.h"

namespace lazyboe {

class NeighbourMemo {
 public:
  // Edge ids a state's neighbourhood holds: a view into the memo, valid until the next call.
  struct Span {
    const uint32_t* edges;
    size_t count;
  };

  // `max_edges`: edge ids kept in all (4 bytes each) before the memo starts again empty.
  NeighbourMemo(const EdgeIndex& index, double radius, int dof, size_t max_edges)
      : index_(index), radius_(radius), dof_(dof), max_edges_(max_edges) {}

  // The edges whose start lies within the radius of q (EdgeIndex::within's ids, in its order).
  Span within(const double* q) {
    const uint64_t h = hash(q);
    const auto it = slots_.find(h);
    if (it != slots_.end()) {
      const Entry& e = it->second;
      if (std::equal(q, q + dof_, states_.data() + e.state)) {
        ++hits_;
        return {edges_.data() + e.first, e.count};
      }
    }
    index_.within(q, radius_, found_);
    if (it == slots_.end()) return remember(h, q);
    // Another state with the same hash (rare): answered, not kept.
    scratch_.resize(found_.size());
    for (size_t k = 0; k < found_.size(); ++k) scratch_[k] = found_[k].first;
    return {scratch_.data(), scratch_.size()};
  }

  uint64_t hits() const { return hits_; }

 private:
  struct Entry {
    size_t state = 0, first = 0;
    size_t count = 0;
  };

  Span remember(uint64_t h, const double* q) {
    if (edges_.size() + found_.size() > max_edges_) {  // full: start again
      slots_.clear();
      edges_.clear();
      states_.clear();
    }
    const Entry e{states_.size(), edges_.size(), found_.size()};
    states_.insert(states_.end(), q, q + dof_);
    for (const auto& [edge, d2] : found_) edges_.push_back(edge);
    slots_.emplace(h, e);
    return {edges_.data() + e.first, e.count};
  }

  uint64_t hash(const double* q) const {
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    for (int i = 0; i < dof_; ++i) {
      uint64_t bits;
      std::memcpy(&bits, q + i, sizeof bits);
      h ^= bits + 0x9E3779B97F4A7C15ULL + (h << 6) + (h >> 2);
      h *= 0xBF58476D1CE4E5B9ULL;
      h ^= h >> 31;
    }
    return h;
  }

  const EdgeIndex& index_;
  const double radius_;
  const int dof_;
  const size_t max_edges_;
  std::unordered_map<uint64_t, Entry> slots_;
  std::vector<uint32_t> edges_;
  std::vector<double> states_;
  std::vector<std::pair<uint32_t, double>> found_;  // the index's answer
  std::vector<uint32_t> scratch_;
  uint64_t hits_ = 0;
};

}  // namespace lazyboe
