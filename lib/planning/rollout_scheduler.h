// Rollouts of one expansion, run ahead of time on a RolloutPool. Once the node a bundle search
// expands is real, every rollout the rest of its expansion needs starts at that node's state,
// so they are independent: they run in waves of up to kWavePerThread per pool thread, in
// expansion order, and the search takes them in that order exactly as if it had run them
// itself. The search's results therefore do not depend on the number of threads; only when it
// stops (first solution, budget) can the rest of a wave go unused.
//
// Rollout lengths vary widely (a collision can end one at once): a wave of one per thread keeps
// threads waiting on the longest. 8 per thread balanced best (docs/performance.md), running
// about 5 % more rollouts than waves of one.
#pragma once

#include <cstddef>
#include <vector>

#include "lazyboe/sim/rollout_pool.h"

namespace lazyboe {

constexpr int kWavePerThread = 8;

class RolloutScheduler {
 public:
  // Disabled (every rollout is the search's own) without a pool or with a pool of one thread.
  RolloutScheduler(const Simulator& sim, RolloutPool* pool)
      : sim_(&sim), pool_(pool && pool->threads() > 1 ? pool : nullptr) {}

  bool enabled() const { return pool_ != nullptr; }

  // A new expansion of `node` with `count` neighbours; nothing is planned yet.
  void begin(int node, size_t count) {
    node_ = node;
    state_.assign(count, State::Unplanned);
    planned_ = false;
  }
  int node() const { return node_; }
  bool planned() const { return planned_; }

  // The node is real from neighbour k on: marks which of neighbours k.. will need a rollout
  // from it (`needed(j)`). Called once per expansion.
  template <class Needed>
  void plan(size_t k, Needed needed) {
    planned_ = true;
    for (size_t j = k; j < state_.size(); ++j) state_[j] = needed(j) ? State::Needed : State::None;
  }

  // Neighbour k's rollout from q0 (the node's state): run now in a wave with the next needed
  // ones unless an earlier wave ran it. `command(j)` is neighbour j's command.
  template <class Command>
  const RolloutResult& take(size_t k, const double* q0, Command command) {
    if (state_[k] != State::Done) run_wave(k, q0, command);
    state_[k] = State::None;  // used
    return results_[k];
  }

  // Rollouts run by the pool so far (used or not).
  size_t rollouts_run() const { return rollouts_run_; }

 private:
  enum class State : unsigned char { Unplanned, None, Needed, Done };

  template <class Command>
  void run_wave(size_t k, const double* q0, Command command) {
    wave_.clear();
    tasks_.clear();
    const size_t limit = static_cast<size_t>(kWavePerThread) * pool_->threads();
    for (size_t j = k; j < state_.size() && wave_.size() < limit; ++j) {
      if (j != k && state_[j] != State::Needed) continue;
      wave_.push_back(j);
      tasks_.push_back({q0, command(j)});
    }
    if (results_.size() < state_.size()) results_.resize(state_.size());
    wave_results_.resize(wave_.size());
    pool_->run(*sim_, tasks_.data(), wave_results_.data(), static_cast<int>(wave_.size()));
    rollouts_run_ += wave_.size();
    for (size_t w = 0; w < wave_.size(); ++w) {
      results_[wave_[w]] = wave_results_[w];
      state_[wave_[w]] = State::Done;
    }
  }

  const Simulator* sim_;  // the search's world
  RolloutPool* pool_;
  int node_ = -1;
  bool planned_ = false;
  std::vector<State> state_;
  std::vector<size_t> wave_;
  std::vector<RolloutTask> tasks_;
  std::vector<RolloutResult> results_, wave_results_;
  size_t rollouts_run_ = 0;
};

}  // namespace lazyboe
