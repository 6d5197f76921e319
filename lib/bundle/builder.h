// Generating the edge bundle (paper, Methods A-B): random collision-free start states in a
// region, random varying velocity commands, simulated and validated by the shared Simulator.
// Attempt a is a function of (seed, a) alone; the bundle holds the valid attempts in attempt
// order, so its contents do not depend on the thread count, and an interrupted build resumed
// later equals an uninterrupted one.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/scene.h"
#include "lazyboe/bundle/settings.h"
#include "lazyboe/common/checkpoint.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

struct EdgeAttempt {
  RolloutStatus status = RolloutStatus::Valid;
  bool start_found = true;       // a collision-free start was found in the region
  uint64_t start_resamples = 0;  // starts drawn again because they were in collision
  JointVector q0, qf;
  double duration = 0, command_duration = 0;
  std::vector<double> knots;
  std::vector<float> sample_q, sample_dq;
  bool valid() const { return start_found && status == RolloutStatus::Valid; }
  const char* reason() const;
};

// How the build runs, not what it makes.
struct BuildControl {
  int threads = 0;                 // 0: all available
  double checkpoint_seconds = 10;  // at least this long between checkpoints
  bool quiet = false;
  // Stop a build whose first kHopelessAttempts attempts are almost all rejected
  // (BuildOutcome::Hopeless): a robot config or region that cannot work, said at once.
  bool stop_when_hopeless = true;
  std::function<bool()> stop_requested;  // polled between rounds
  // Persists the bundle so far (unset: nothing is saved); `last` is true for the run's last
  // save (complete, or interrupted), so that checkpoints can be incremental
  // (checkpoint_journal.h).
  std::function<void(const Bundle&, bool last)> save_progress;
  std::function<void(uint64_t done, uint64_t total)> progress;  // valid edges, after each round
  CheckpointStats* stats = nullptr;  // receives what the saves cost, when set
  // Where a round's attempts are computed. Unset: here, on `threads` threads, rounds of
  // max(64, 32 x threads) attempts. Set (MPI, tools/mpi_offline.h): round_attempts per round,
  // and run_round(first, results) fills results[k] with attempt first + k for every k.
  size_t round_attempts = 0;
  std::function<void(uint64_t first, std::vector<EdgeAttempt>& results)> run_round;
};

constexpr int kMaxStartSamples = 1000;  // per attempt, before it counts as start_in_collision

void generate_edge(const Simulator& sim, SimulatorWorkspace& ws, const BuildSettings& settings,
                   uint64_t attempt, EdgeAttempt& out);

// Attempts in parallel on a fixed set of threads, each with its own workspace.
class AttemptGenerator {
 public:
  AttemptGenerator(const Simulator& sim, const BuildSettings& settings, int threads);
  int threads() const { return threads_; }
  // out[k] = attempt first + k, for k < count.
  void generate(uint64_t first, size_t count, EdgeAttempt* out);

 private:
  const Simulator& sim_;
  const BuildSettings& settings_;
  int threads_;
  std::vector<SimulatorWorkspace> workspaces_;
};

// A new, empty bundle whose header describes the inputs and settings.
Bundle new_bundle(const RobotModel& robot, const Environment& env, const BuildSettings& settings);

// Refuses to resume `existing` with `wanted`: names the first parameter, robot or environment
// that differs.
void check_resume_compatible(const BundleHeader& existing, const BundleHeader& wanted,
                             const std::string& path);

// Fails (naming the region) when no collision-free start can be found in it.
void check_region(const Simulator& sim, const BuildSettings& settings);

// A build is hopeless when fewer than kHopelessValidShare of its first kHopelessAttempts
// attempts are valid (checked once, at that attempt: the same for any thread count).
constexpr uint64_t kHopelessAttempts = 2000;
constexpr double kHopelessValidShare = 0.02;

enum class BuildOutcome { Complete, Interrupted, Hopeless };

// Why a build's attempts fail: the leading rejection reasons with their shares of the attempts
// and what to change for the first, in one line.
std::string rejection_diagnosis(const BundleHeader& h);

// Grows `bundle` to settings.edges valid edges. Saves checkpoints as it goes and a last one
// at the end (complete) or on interruption or a hopeless start (incomplete).
BuildOutcome build_bundle(const Simulator& sim, const BuildSettings& settings, Bundle& bundle,
                          const BuildControl& control);

}  // namespace lazyboe
