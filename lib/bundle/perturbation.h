// The perturbation analysis (paper, Methods C): for every edge, p perturbed copies of its start
// state re-simulated with the edge's own command by the shared Simulator. A perturbation is
// d = r u with u uniform on the unit sphere and r uniform in (0, theta], so |d| < theta/2 for
// half of them. Per edge:
//   P_lazy_prop = (valid rollouts ending within theta/2 of the stored end state) / (valid ones)
//                 (0 when none is valid: such an edge is never taken lazily)
//   P_collision = (rollouts failing the collision check) / p
// and the displacement-transfer statistics of the same valid rollouts: the largest residual
// |q^_f - (qf + d)| (the command from q0 + d predicted to end at qf + d) and the share of them
// with residual below theta/2 (P_lazy_prop under transfer).
// Perturbation j of edge i draws only from the stream (seed, i, j): any thread count gives the
// same numbers, and raising p later adds perturbations p_old..p_new-1 to the same counts.
#pragma once

#include <functional>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/common/checkpoint.h"
#include "lazyboe/sim/simulator.h"

namespace lazyboe {

struct PerturbSettings {
  double theta = 0.35;
  uint64_t perturbations = 16;
  uint64_t seed = 1;
};

struct EdgePerturbationCounts;

struct PerturbControl {
  int threads = 0;
  double checkpoint_seconds = 10;
  bool quiet = false;
  std::function<bool()> stop_requested;
  // Persists the analysis so far (unset: nothing is saved): `edges` were finished since the
  // previous save; `last` is true for the run's last save (complete, or interrupted).
  std::function<void(const Bundle&, const std::vector<size_t>& edges, bool last)> save_progress;
  std::function<void(uint64_t done, uint64_t total)> progress;  // finished edges, after each round
  CheckpointStats* stats = nullptr;  // receives what the saves cost, when set
  // Where a round's edges are perturbed. Unset: here, on `threads` threads, rounds of
  // max(16, 8 x threads) edges. Set (MPI, tools/mpi_offline.h): round_edges per round, and
  // run_round(edges, counts) completes counts[k] (holding edge edges[k]'s counts so far).
  size_t round_edges = 0;
  std::function<void(const std::vector<size_t>& edges, std::vector<EdgePerturbationCounts>& counts)>
      run_round;
};

// Draws perturbation j of edge `edge` (norm in (0, theta]).
JointVector perturbation_offset(const PerturbSettings& settings, int dof, uint64_t edge,
                                uint64_t j);

struct EdgePerturbationCounts {
  uint64_t done = 0, valid = 0, lazy = 0, collision = 0;
  double max_error = 0;  // valid > 0 only
  // Displacement transfer: residual |q^_f - (qf + d)| of the valid rollouts.
  uint64_t transfer_lazy = 0;     // residual < theta/2
  double transfer_max_error = 0;  // valid > 0 only
  double simulated_seconds = 0;
};

// The residuals of one perturbation of an edge (what perturb_edge counts).
struct PerturbationSample {
  JointVector offset;         // d
  RolloutStatus status{};     // of the rollout from q0 + d
  double error = 0;           // |q^_f - qf| (valid rollouts only)
  double transfer_error = 0;  // |q^_f - (qf + d)| (valid rollouts only)
};

// Simulates perturbation j of edge `edge` alone (the same rollout perturb_edge counts).
PerturbationSample perturb_sample(const Simulator& sim, SimulatorWorkspace& ws,
                                  const Bundle& bundle, size_t edge,
                                  const PerturbSettings& settings, uint64_t j);

// Runs perturbations [counts.done, settings.perturbations) of one edge, adding to `counts`.
void perturb_edge(const Simulator& sim, SimulatorWorkspace& ws, const Bundle& bundle, size_t edge,
                  const PerturbSettings& settings, EdgePerturbationCounts& counts);

// The same from the edge's data alone (an MPI rank receives them in a message): `edge` is the
// edge's index in the bundle, which seeds its perturbations.
struct EdgeCommand {
  const double* q0 = nullptr;  // dof values
  const double* qf = nullptr;  // dof values
  const double* knots = nullptr;
  int knot_rows = 0;
  double command_duration = 0;
};
void perturb_edge_command(const Simulator& sim, SimulatorWorkspace& ws, int dof,
                          const EdgeCommand& command, uint64_t edge,
                          const PerturbSettings& settings, EdgePerturbationCounts& counts);

// Edge e's counts so far, as perturb_edge continues them.
EdgePerturbationCounts counts_so_far(const Perturbation& p, size_t e);

// Sets up bundle.perturbation for `settings`: keeps the existing counts when theta and seed
// match and p does not shrink (they are extended), starts afresh when `replace` is set, and
// refuses otherwise with a message naming the difference. An analysis without the transfer
// statistics (written by an older lazyboe) is kept as it is when complete with these settings
// (the return value is then true: it lacks them), and refused, pointing to --replace, when it
// would have to be extended or continued: its counts cannot be extended consistently, and
// redoing it in place would checkpoint an incomplete analysis over a complete one.
bool prepare_perturbation(Bundle& bundle, const PerturbSettings& settings, bool replace,
                          const std::string& path);

enum class PerturbOutcome { Complete, Interrupted };

PerturbOutcome run_perturbation(const Simulator& sim, Bundle& bundle,
                                const PerturbSettings& settings, const PerturbControl& control);

}  // namespace lazyboe
