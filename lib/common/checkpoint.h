// When long jobs write their checkpoints: at least `min_seconds` apart, and at least ten times
// as long apart as the last write took, so that rewriting a large file stays a small share of
// the run.
#pragma once

#include <algorithm>
#include <chrono>
#include <functional>

namespace lazyboe {

class Checkpointer {
 public:
  Checkpointer(double min_seconds, std::function<void()> save)
      : min_seconds_(min_seconds),
        save_(std::move(save)),
        last_(std::chrono::steady_clock::now()) {}

  void save_now() {
    const auto start = std::chrono::steady_clock::now();
    if (save_) save_();
    last_ = std::chrono::steady_clock::now();
    cost_ = std::chrono::duration<double>(last_ - start).count();
  }

  void save_if_due() {
    const double since =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count();
    if (since >= std::max(min_seconds_, 10 * cost_)) save_now();
  }

 private:
  double min_seconds_;
  std::function<void()> save_;
  std::chrono::steady_clock::time_point last_;
  double cost_ = 0;
};

}  // namespace lazyboe
