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

#include "lazyboe/common/hash.h"
#include "lazyboe/planning/neighbour_index.h"

namespace lazyboe {

class NeighbourMemo {
 public:
  // Edge ids a state's neighbourhood holds: a view into the memo, valid until the next call.
  struct Span {
    const uint32_t* edges;
    size_t count;
  };

  // `max_bytes`: about what the memo may hold (its edge ids, states and slots) before it
  // starts again empty.
  NeighbourMemo(const EdgeIndex& index, double radius, int dof, size_t max_bytes)
      : index_(index), radius_(radius), dof_(dof), max_bytes_(max_bytes) {}

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
    if (bytes(slots_.size() + 1, edges_.size() + found_.size()) > max_bytes_) {  // full: again
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

  // A state's share: its coordinates, its entry and about a hash-map node.
  size_t bytes(size_t states, size_t ids) const {
    return ids * sizeof(uint32_t) + states * (dof_ * sizeof(double) + sizeof(Entry) + 32);
  }

  uint64_t hash(const double* q) const {
    uint64_t h = kKeySeed;
    for (int i = 0; i < dof_; ++i) {
      uint64_t bits;
      std::memcpy(&bits, q + i, sizeof bits);
      h = mix_key(h, bits);
    }
    return h;
  }

  const EdgeIndex& index_;
  const double radius_;
  const int dof_;
  const size_t max_bytes_;
  std::unordered_map<uint64_t, Entry> slots_;
  std::vector<uint32_t> edges_;
  std::vector<double> states_;
  std::vector<std::pair<uint32_t, double>> found_;  // the index's answer
  std::vector<uint32_t> scratch_;
  uint64_t hits_ = 0;
};

}  // namespace lazyboe
