// Independent rollouts run side by side: one SimulatorWorkspace per thread. A search hands over
// a batch of (start, command) pairs and gets each result in the slot of its pair, so what it
// does with them cannot depend on the number of threads. The pool owns its worker threads for
// its whole life (plain std::threads, not OpenMP: a pool is used from inside the query tool's
// OpenMP jobs, where a nested OpenMP region starts new threads every time). Between batches a
// worker spins for up to 10 ms (a search hands over its next batch within microseconds; a
// sleeping virtual CPU can take milliseconds to wake), then sleeps. Running a batch allocates
// nothing.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "lazyboe/sim/simulator.h"

namespace lazyboe {

struct RolloutTask {
  const double* q0 = nullptr;  // start configuration at rest, robot.dof values
  CommandProfile command;
};

class RolloutPool {
 public:
  // threads >= 1: the calling thread and threads - 1 workers, each with a workspace for
  // `sim`'s robot (so for every world of that robot, world.h).
  RolloutPool(const Simulator& sim, int threads);
  ~RolloutPool();
  RolloutPool(const RolloutPool&) = delete;
  RolloutPool& operator=(const RolloutPool&) = delete;

  int threads() const { return static_cast<int>(workspaces_.size()); }

  // results[k] = simulate(sim, ws, tasks[k].q0, tasks[k].command) for k < count, on all the
  // pool's threads; `sim` is of the pool's robot, in any world. One batch at a time: run is not
  // to be called concurrently on one pool.
  void run(const Simulator& sim, const RolloutTask* tasks, RolloutResult* results, int count);

  // Rollouts run so far (used or not by the caller).
  uint64_t rollouts() const { return rollouts_; }

 private:
  void worker(int slot);
  void run_tasks(int slot);  // takes tasks of the current batch until none is left

  const int dof_;                   // of the pool's robot
  const Simulator* sim_ = nullptr;  // the current batch's
  uint64_t rollouts_ = 0;
  std::vector<SimulatorWorkspace> workspaces_;  // [0]: the calling thread's
  std::vector<std::thread> workers_;

  // The current batch: its fields are written before generation_ is raised (release) and read
  // by a worker after it has seen the new generation (acquire). mutex_ and the condition
  // variables only serve threads that have stopped spinning.
  std::mutex mutex_;
  std::condition_variable batch_ready_, batch_done_;
  std::atomic<uint64_t> generation_{0};
  std::atomic<bool> stopping_{false};
  std::atomic<int> workers_busy_{0};
  const RolloutTask* tasks_ = nullptr;
  RolloutResult* results_ = nullptr;
  int count_ = 0;
  std::atomic<int> next_task_{0};
  std::exception_ptr error_;  // the batch's first, under mutex_
};

}  // namespace lazyboe
