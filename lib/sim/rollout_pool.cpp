#include "lazyboe/sim/rollout_pool.h"

#include <chrono>
#include <string>

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

// Spins until done() or for about kSpin, whichever is first; true if done(). The rollouts of a
// batch differ by milliseconds, and a thread that went to sleep on a virtual machine can take
// as long again to be woken: spins of 0.2 and 2 ms made two threads slower than one on the
// 2-core VM of docs/performance.md, 10 ms did not (libgomp's default spin is of that order).
template <typename Done>
bool spin_until(Done done) {
  constexpr auto kSpin = std::chrono::milliseconds(10);
  const auto until = std::chrono::steady_clock::now() + kSpin;
  for (int i = 0;; ++i) {
    if (done()) return true;
    if ((i & 63) == 63 && std::chrono::steady_clock::now() > until) return false;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
}

}  // namespace

RolloutPool::RolloutPool(const Simulator& sim, int threads) : dof_(sim.robot.dof) {
  if (threads < 1) fail("threads", "must be at least 1, got " + std::to_string(threads));
  workspaces_.reserve(threads);
  for (int t = 0; t < threads; ++t) workspaces_.emplace_back(sim);
  workers_.reserve(threads - 1);
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this, t] { worker(t); });
}

RolloutPool::~RolloutPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_.store(true);
  }
  batch_ready_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void RolloutPool::run_tasks(int slot) {
  const Simulator& sim = *sim_;
  const int n = sim.robot.dof;
  for (int k; (k = next_task_.fetch_add(1, std::memory_order_relaxed)) < count_;) {
    // simulate() throws nothing for valid inputs; an exception on a worker would end the
    // process, so the batch's first is handed to the caller.
    try {
      results_[k] = simulate(sim, workspaces_[slot],
                             Eigen::Map<const Eigen::VectorXd>(tasks_[k].q0, n), tasks_[k].command);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
  }
}

void RolloutPool::worker(int slot) {
  uint64_t seen = 0;
  for (;;) {
    auto next = [&] {
      return stopping_.load(std::memory_order_acquire) ||
             generation_.load(std::memory_order_acquire) != seen;
    };
    if (!spin_until(next)) {
      std::unique_lock<std::mutex> lock(mutex_);
      batch_ready_.wait(lock, next);
    }
    if (stopping_.load(std::memory_order_acquire)) return;
    seen = generation_.load(std::memory_order_acquire);
    run_tasks(slot);
    if (workers_busy_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      std::lock_guard<std::mutex> lock(mutex_);  // the caller may be about to wait
      batch_done_.notify_one();
    }
  }
}

void RolloutPool::run(const Simulator& sim, const RolloutTask* tasks, RolloutResult* results,
                      int count) {
  if (count <= 0) return;
  if (sim.robot.dof != dof_) fail("RolloutPool::run", "a simulator of another robot");
  rollouts_ += count;
  sim_ = &sim;
  tasks_ = tasks;
  results_ = results;
  count_ = count;
  error_ = nullptr;
  next_task_.store(0, std::memory_order_relaxed);
  const bool wake = count > 1 && !workers_.empty();
  if (wake) {
    workers_busy_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
    {
      std::lock_guard<std::mutex> lock(mutex_);  // no worker between its check and its wait
      generation_.fetch_add(1, std::memory_order_release);
    }
    batch_ready_.notify_all();
  }
  run_tasks(0);
  if (wake) {
    auto done = [&] { return workers_busy_.load(std::memory_order_acquire) == 0; };
    if (!spin_until(done)) {
      std::unique_lock<std::mutex> lock(mutex_);
      batch_done_.wait(lock, done);
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

}  // namespace lazyboe
