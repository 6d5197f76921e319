// lazyboe-perturb across MPI ranks (mpi_offline.h): rank 0 holds the bundle; every round it
// splits the round's edges into one contiguous block per rank, sends each rank its edges' data
// (start and end state, command: about 0.45 kB per edge) with their counts so far, perturbs its
// own block on its threads, and gathers the counts back (64 bytes per edge).
#pragma once
#ifdef LAZYBOE_HAVE_MPI

#include <omp.h>

#include <memory>
#include <string>
#include <vector>

#include "lazyboe/bundle/perturbation.h"
#include "lazyboe/common/bytes.h"
#include "lazyboe/common/journal.h"
#include "mpi_build.h"
#include "mpi_offline.h"

namespace lazyboe::mpi {

inline std::string perturb_job(const BundleScene& scene, const BundleHeader& h,
                               const PerturbSettings& s, const SimulationOptions& options) {
  std::string out;
  ByteWriter w(out);
  put_scene_inputs(w, scene.robot.files.config, scene.env.path, h);
  w.put(s);
  w.put(options);
  w.put<int64_t>(h.dof);
  return out;
}

// Block r of `count` edges: [begin(r), begin(r + 1)).
inline size_t block_begin(size_t count, int r) {
  return count * static_cast<size_t>(r) / static_cast<size_t>(world().size);
}

class PerturbRanks {
 public:
  PerturbRanks(const Simulator& sim, const Bundle& b, const PerturbSettings& s, int threads)
      : sim_(sim), b_(b), s_(s), threads_(threads > 0 ? threads : omp_get_max_threads()) {
    for (int t = 0; t < threads_; ++t) workspaces_.emplace_back(sim);
  }

  void attach(PerturbControl& control) {
    control.round_edges =
        std::max<size_t>(16, 8 * static_cast<size_t>(threads_)) * static_cast<size_t>(world().size);
    control.run_round = [this](const std::vector<size_t>& edges,
                               std::vector<EdgePerturbationCounts>& counts) {
      run_round(edges, counts);
    };
  }

 private:
  void run_round(const std::vector<size_t>& edges, std::vector<EdgePerturbationCounts>& counts) {
    const size_t n = edges.size();
    const int dof = b_.dof();
    uint64_t go = 1;
    MPI_Bcast(&go, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    std::vector<std::string> parts(world().size);
    for (int r = 1; r < world().size; ++r) {
      ByteWriter w(parts[r]);
      const size_t from = block_begin(n, r), to = block_begin(n, r + 1);
      w.put<uint64_t>(to - from);
      for (size_t k = from; k < to; ++k) {
        const size_t e = edges[k];
        w.put<uint64_t>(e);
        w.put(counts[k]);
        w.put_array(&b_.q0[e * dof], dof);
        w.put_array(&b_.qf[e * dof], dof);
        w.put(b_.command_duration[e]);
        const uint64_t k0 = b_.knot_offset[e], k1 = b_.knot_offset[e + 1];
        w.put_array(&b_.knots[k0 * dof], (k1 - k0) * dof);
      }
    }
    scatter(parts);
    const long own = static_cast<long>(block_begin(n, 1));
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 1)
    for (long k = 0; k < own; ++k)
      perturb_edge(sim_, workspaces_[omp_get_thread_num()], b_, edges[k], s_, counts[k]);
    const std::vector<std::string> back = gather("");
    for (int r = 1; r < world().size; ++r) {
      ByteReader in(back[r].data(), back[r].size(), "rank " + std::to_string(r));
      for (size_t k = block_begin(n, r); k < block_begin(n, r + 1); ++k)
        counts[k] = in.get<EdgePerturbationCounts>();
    }
  }

  const Simulator& sim_;
  const Bundle& b_;
  PerturbSettings s_;
  int threads_;
  std::vector<SimulatorWorkspace> workspaces_;
};

// Rank 0 under MPI: sends the job and attaches the ranks to `control` (null without MPI).
inline std::unique_ptr<PerturbRanks> start_perturb_ranks(const BundleScene& scene,
                                                         const Simulator& sim, const Bundle& b,
                                                         const PerturbSettings& s,
                                                         const SimulationOptions& options,
                                                         PerturbControl& control) {
  if (!world().active) return nullptr;
  std::string job = perturb_job(scene, b.header, s, options);
  broadcast(job);
  auto ranks = std::make_unique<PerturbRanks>(sim, b, s, control.threads);
  ranks->attach(control);
  return ranks;
}

inline void stop_perturb_ranks() {
  uint64_t go = 0;
  MPI_Bcast(&go, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
}

// Ranks other than 0: perturb the edges each round brings until told to stop.
inline void serve_perturb(int threads) {
  std::string job;
  broadcast(job);
  if (job.empty()) return;
  ByteReader r(job.data(), job.size(), "job");
  const SceneInputs inputs = get_scene_inputs(r);
  const PerturbSettings s = r.get<PerturbSettings>();
  const SimulationOptions options = r.get<SimulationOptions>();
  const int dof = static_cast<int>(r.get<int64_t>());
  RankScene scene;
  load_rank_scene(scene, inputs, options);
  const int nthreads = threads > 0 ? threads : omp_get_max_threads();
  std::vector<SimulatorWorkspace> workspaces;
  for (int t = 0; t < nthreads; ++t) workspaces.emplace_back(*scene.sim);
  for (;;) {
    uint64_t go = 0;
    MPI_Bcast(&go, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    if (!go) return;
    const std::string mine = scatter({});
    ByteReader in(mine.data(), mine.size(), "round");
    const uint64_t n = in.get<uint64_t>();
    std::vector<uint64_t> edge(n);
    std::vector<EdgePerturbationCounts> counts(n);
    std::vector<std::vector<double>> q0(n), qf(n), knots(n);
    std::vector<double> duration(n);
    for (uint64_t k = 0; k < n; ++k) {
      edge[k] = in.get<uint64_t>();
      counts[k] = in.get<EdgePerturbationCounts>();
      q0[k] = in.get_vector<double>();
      qf[k] = in.get_vector<double>();
      duration[k] = in.get<double>();
      knots[k] = in.get_vector<double>();
    }
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1)
    for (long k = 0; k < static_cast<long>(n); ++k) {
      EdgeCommand c;
      c.q0 = q0[k].data();
      c.qf = qf[k].data();
      c.knots = knots[k].data();
      c.knot_rows = static_cast<int>(knots[k].size() / dof);
      c.command_duration = duration[k];
      perturb_edge_command(*scene.sim, workspaces[omp_get_thread_num()], dof, c, edge[k], s,
                           counts[k]);
    }
    crash_point("rank-round");
    std::string bytes;
    ByteWriter w(bytes);
    for (const EdgePerturbationCounts& c : counts) w.put(c);
    gather(bytes);
  }
}

}  // namespace lazyboe::mpi

#endif
