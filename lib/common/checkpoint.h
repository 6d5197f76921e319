// When long jobs write their checkpoints: at least `min_seconds` apart, and at least ten times
// as long apart as the last write took, so that checkpoints stay a small share of the run;
// min_seconds 0: at every call (after every round).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>

namespace lazyboe {

// What a run's saves cost: the checkpoints while it ran, and the last save (the whole file).
struct CheckpointStats {
  uint64_t checkpoints = 0;
  double checkpoint_seconds = 0, longest_checkpoint_seconds = 0;
  double last_save_seconds = 0;
};

class Checkpointer {
 public:
  Checkpointer(double min_seconds, std::function<void()> save)
      : min_seconds_(min_seconds),
        save_(std::move(save)),
        last_(std::chrono::steady_clock::now()) {}

  // The run's last save (complete or interrupted).
  void save_now() {
    save();
    stats_.last_save_seconds = cost_;
  }

  void save_if_due() {
    const double since =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count();
    // 0 asks for a checkpoint after every round (tests; incremental checkpoints are cheap).
    if (min_seconds_ > 0 && since < std::max(min_seconds_, 10 * cost_)) return;
    save();
    ++stats_.checkpoints;
    stats_.checkpoint_seconds += cost_;
    stats_.longest_checkpoint_seconds = std::max(stats_.longest_checkpoint_seconds, cost_);
  }

  const CheckpointStats& stats() const { return stats_; }

 private:
  void save() {
    const auto start = std::chrono::steady_clock::now();
    if (save_) save_();
    last_ = std::chrono::steady_clock::now();
    cost_ = std::chrono::duration<double>(last_ - start).count();
  }

  CheckpointStats stats_;
  double min_seconds_;
  std::function<void()> save_;
  std::chrono::steady_clock::time_point last_;
  double cost_ = 0;
};

}  // namespace lazyboe
