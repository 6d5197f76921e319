#include "lazyboe/bundle/perturbation.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "lazyboe/common/checkpoint.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/progress.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {
namespace {

std::string exact(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Keeps perturbation streams apart from the build's attempt streams for the same seed.
constexpr uint64_t kPerturbSalt = 0x7065727475726221ULL;  // "perturb!"

void set_probabilities(Perturbation& p, size_t e) {
  p.p_lazy_prop[e] = p.valid[e] ? static_cast<double>(p.lazy[e]) / p.valid[e] : 0.0;
  p.p_collision[e] = p.done[e] ? static_cast<double>(p.collision[e]) / p.done[e] : 0.0;
  p.p_lazy_prop_transfer[e] =
      p.valid[e] ? static_cast<double>(p.transfer_lazy[e]) / p.valid[e] : 0.0;
}

}  // namespace

JointVector perturbation_offset(const PerturbSettings& s, int dof, uint64_t edge, uint64_t j) {
  Random rng(s.seed ^ kPerturbSalt, (edge << 24) ^ j);
  JointVector d(dof);
  double norm = 0;
  do {
    for (int i = 0; i < dof; ++i) d[i] = rng.normal();
    norm = d.norm();
  } while (norm < 1e-12);
  const double r = s.theta * (1.0 - rng.uniform());  // in (0, theta]
  return d * (r / norm);
}

namespace {

struct EdgeInputs {
  JointVector q0, qf;
  CommandProfile profile;
};

// An edge's command as pointers into the bundle (or into a rank's copy of it, MPI).
EdgeCommand edge_command(const Bundle& b, size_t e) {
  const int n = b.dof();
  EdgeCommand command;
  command.q0 = &b.q0[e * n];
  command.qf = &b.qf[e * n];
  command.knots = &b.knots[b.knot_offset[e] * n];
  command.knot_rows = static_cast<int>(b.knot_offset[e + 1] - b.knot_offset[e]);
  command.command_duration = b.command_duration[e];
  return command;
}

EdgeInputs edge_inputs(const EdgeCommand& command, int dof) {
  return EdgeInputs{
      Eigen::Map<const Eigen::VectorXd>(command.q0, dof),
      Eigen::Map<const Eigen::VectorXd>(command.qf, dof),
      CommandProfile{command.knots, command.knot_rows, dof, command.command_duration}};
}

// Perturbation j of an edge: the rollout from q0 + d and both residuals of its end.
PerturbationSample sample(const Simulator& sim, SimulatorWorkspace& ws, const EdgeInputs& in,
                          const PerturbSettings& s, int dof, size_t e, uint64_t j,
                          double* simulated) {
  PerturbationSample out;
  out.offset = perturbation_offset(s, dof, e, j);
  const JointVector start = in.q0 + out.offset;
  const RolloutResult r = simulate(sim, ws, start, in.profile);
  if (simulated) *simulated += r.duration;
  out.status = r.status;
  if (r.valid()) {
    out.error = (r.qf - in.qf).norm();
    out.transfer_error = (r.qf - (in.qf + out.offset)).norm();
  }
  return out;
}

}  // namespace

PerturbationSample perturb_sample(const Simulator& sim, SimulatorWorkspace& ws, const Bundle& b,
                                  size_t e, const PerturbSettings& s, uint64_t j) {
  return sample(sim, ws, edge_inputs(edge_command(b, e), b.dof()), s, b.dof(), e, j, nullptr);
}

void perturb_edge(const Simulator& sim, SimulatorWorkspace& ws, const Bundle& b, size_t e,
                  const PerturbSettings& s, EdgePerturbationCounts& c) {
  perturb_edge_command(sim, ws, b.dof(), edge_command(b, e), e, s, c);
}

EdgePerturbationCounts counts_so_far(const Perturbation& p, size_t e) {
  EdgePerturbationCounts c;
  c.done = p.done[e];
  c.valid = p.valid[e];
  c.lazy = p.lazy[e];
  c.collision = p.collision[e];
  c.max_error = p.valid[e] ? p.max_error[e] : 0.0;
  c.transfer_lazy = p.transfer_lazy[e];
  c.transfer_max_error = p.valid[e] ? p.transfer_max_error[e] : 0.0;
  c.simulated_seconds = 0;
  return c;
}

void perturb_edge_command(const Simulator& sim, SimulatorWorkspace& ws, int dof,
                          const EdgeCommand& command, uint64_t e, const PerturbSettings& s,
                          EdgePerturbationCounts& c) {
  const EdgeInputs in = edge_inputs(command, dof);
  for (uint64_t j = c.done; j < s.perturbations; ++j) {
    const PerturbationSample r = sample(sim, ws, in, s, dof, e, j, &c.simulated_seconds);
    ++c.done;
    if (r.status == RolloutStatus::SelfCollision || r.status == RolloutStatus::EnvCollision) {
      ++c.collision;
    } else if (r.status == RolloutStatus::Valid) {
      c.max_error = c.valid ? std::max(c.max_error, r.error) : r.error;
      c.transfer_max_error =
          c.valid ? std::max(c.transfer_max_error, r.transfer_error) : r.transfer_error;
      ++c.valid;
      if (r.error < s.theta / 2) ++c.lazy;
      if (r.transfer_error < s.theta / 2) ++c.transfer_lazy;
    }
  }
}

bool prepare_perturbation(Bundle& b, const PerturbSettings& s, bool replace,
                          const std::string& path) {
  Perturbation& p = b.perturbation;
  const size_t n = b.size();
  if (p.present && !replace) {
    if (p.theta != s.theta) {
      fail(path, "holds a perturbation analysis for theta " + exact(p.theta) +
                     "; use --replace to discard it and start one for theta " + exact(s.theta));
    }
    if (p.seed != s.seed) {
      fail(path, "holds a perturbation analysis with seed " + std::to_string(p.seed) +
                     "; use the same --seed to extend it, or --replace to start over");
    }
    if (s.perturbations < p.perturbations) {
      fail(path, "holds " + std::to_string(p.perturbations) +
                     " perturbations per edge already; use --replace to start over with fewer");
    }
    const bool complete =
        std::all_of(p.done.begin(), p.done.end(), [&](uint64_t d) { return d >= s.perturbations; });
    if (p.has_transfer) {
      p.perturbations = s.perturbations;
      p.complete = complete;
      return false;
    }
    // Written before the transfer statistics: kept when there is nothing to add (it still
    // serves the stored lazy model), never redone in place (a checkpoint would replace a
    // complete analysis with an incomplete one).
    if (complete && s.perturbations == p.perturbations) {
      p.complete = true;
      return true;
    }
    fail(path,
         "holds a perturbation analysis written before the transfer statistics, which "
         "cannot be extended or continued; use --replace to redo it (the file keeps its "
         "analysis until the new one's first checkpoint)");
  }
  p = Perturbation{};
  p.present = true;
  p.theta = s.theta;
  p.perturbations = s.perturbations;
  p.seed = s.seed;
  p.done.assign(n, 0);
  p.valid.assign(n, 0);
  p.lazy.assign(n, 0);
  p.collision.assign(n, 0);
  p.max_error.assign(n, std::numeric_limits<double>::quiet_NaN());
  p.p_lazy_prop.assign(n, 0.0);
  p.p_collision.assign(n, 0.0);
  p.has_transfer = true;
  p.transfer_lazy.assign(n, 0);
  p.transfer_max_error.assign(n, std::numeric_limits<double>::quiet_NaN());
  p.p_lazy_prop_transfer.assign(n, 0.0);
  p.complete = n == 0;
  return false;
}

// One edge's counts of a round, into the analysis.
static void apply_counts(const EdgePerturbationCounts& c, size_t e, Perturbation& p) {
  p.done[e] = c.done;
  p.valid[e] = c.valid;
  p.lazy[e] = c.lazy;
  p.collision[e] = c.collision;
  p.max_error[e] = c.valid ? c.max_error : std::numeric_limits<double>::quiet_NaN();
  p.transfer_lazy[e] = c.transfer_lazy;
  p.transfer_max_error[e] =
      c.valid ? c.transfer_max_error : std::numeric_limits<double>::quiet_NaN();
  p.simulated_seconds += c.simulated_seconds;
  set_probabilities(p, e);
}

PerturbOutcome run_perturbation(const Simulator& sim, Bundle& b, const PerturbSettings& s,
                                const PerturbControl& control) {
  Perturbation& p = b.perturbation;
  const size_t n = b.size();
  if (!p.present || !p.has_transfer)
    fail("run_perturbation", "the analysis is not prepared (call prepare_perturbation first)");
  const bool local = !control.run_round;
  const int threads = !local ? 1 : control.threads > 0 ? control.threads : omp_get_max_threads();
  std::vector<SimulatorWorkspace> workspaces;
  workspaces.reserve(threads);
  for (int t = 0; t < threads; ++t) workspaces.emplace_back(sim);

  // Edges still short of p perturbations, in edge order.
  std::vector<size_t> pending;
  for (size_t e = 0; e < n; ++e) {
    if (p.done[e] < s.perturbations) pending.push_back(e);
  }
  Progress progress("lazyboe-perturb", n, control.quiet);
  const double wall_before = p.wall_seconds;
  bool last = false;
  size_t applied = 0, saved = 0;  // pending[0, applied) have their results in `p`
  std::vector<size_t> since_save;
  Checkpointer checkpoints(control.checkpoint_seconds, [&] {
    p.wall_seconds = wall_before + progress.elapsed();
    if (!control.save_progress) return;
    since_save.assign(pending.begin() + saved, pending.begin() + applied);
    control.save_progress(b, since_save, last);
    saved = applied;
  });
  auto save = [&](bool complete) {
    p.complete = complete;
    last = true;
    checkpoints.save_now();
  };
  size_t finished = n - pending.size();
  const size_t round =
      local ? std::max<size_t>(16, 8 * static_cast<size_t>(threads)) : control.round_edges;
  if (round == 0) fail("run_perturbation", "round_edges must be > 0");
  std::vector<EdgePerturbationCounts> counts(round);
  std::vector<size_t> round_list;
  progress.update(finished);
  if (control.progress) control.progress(finished, n);
  for (size_t start = 0; start < pending.size(); start += round) {
    if (control.stop_requested && control.stop_requested()) {
      progress.finish();
      save(false);
      if (control.stats) *control.stats = checkpoints.stats();
      return PerturbOutcome::Interrupted;
    }
    const size_t count = std::min(round, pending.size() - start);
    if (local) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
      for (long k = 0; k < static_cast<long>(count); ++k) {
        const size_t e = pending[start + k];
        counts[k] = counts_so_far(p, e);
        perturb_edge(sim, workspaces[omp_get_thread_num()], b, e, s, counts[k]);
      }
    } else {
      round_list.assign(pending.begin() + start, pending.begin() + start + count);
      counts.resize(count);
      for (size_t k = 0; k < count; ++k) counts[k] = counts_so_far(p, round_list[k]);
      control.run_round(round_list, counts);
    }
    for (size_t k = 0; k < count; ++k) apply_counts(counts[k], pending[start + k], p);
    applied = start + count;
    finished += count;
    progress.update(finished);
    if (control.progress) control.progress(finished, n);
    if (finished < n) checkpoints.save_if_due();
  }
  progress.finish();
  save(true);
  if (control.stats) *control.stats = checkpoints.stats();
  return PerturbOutcome::Complete;
}

}  // namespace lazyboe
