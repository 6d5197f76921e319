// MPI for the offline tools (lazyboe-build, lazyboe-perturb; docs/scaling.md). Rank 0 is the
// tool as without MPI: it reads the command line and the files, writes every output and its
// checkpoints, and reports progress. Every round it hands each rank a share of the work (build:
// a block of attempt indices; perturb: the edges' data) and gathers the results back in order,
// so the file is the one a single process makes. The other ranks need only the robot and
// environment files (the paths rank 0 resolved, opened from their own working directory) and
// are refused, naming the file, when their content differs from rank 0's.
//
// A failure on any rank prints one line ("lazyboe-build: error: rank 2: ...") and ends the whole
// job with MPI_Abort, so no rank waits forever for a rank that is gone.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

namespace lazyboe::mpi {

// Launched by mpirun or srun (the variables their process managers set for each rank), and
// the world size they announce. Not SLURM_NTASKS: every process of a Slurm job has it, ranks
// started by srun or not.
inline int launcher_world_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"}) {
    const char* v = std::getenv(name);
    if (v && std::atoi(v) > 0) return std::atoi(v);
  }
  return 0;
}

}  // namespace lazyboe::mpi

#ifdef LAZYBOE_HAVE_MPI
#include <mpi.h>

#include <cstdio>
#include <vector>

#include "lazyboe/common/bytes.h"

namespace lazyboe::mpi {

struct World {
  int rank = 0, size = 1;
  bool active = false;
};

inline World& world() {
  static World w;
  return w;
}

inline void init(int& argc, char**& argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  World& w = world();
  MPI_Comm_rank(MPI_COMM_WORLD, &w.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &w.size);
  w.active = true;
}

inline void finalize() {
  if (world().active) MPI_Finalize();
  world().active = false;
}

// One line, then the whole job ends (every rank, whatever it is waiting for).
[[noreturn]] inline void abort_job(const char* tool, const std::string& message) {
  std::fprintf(stderr, "%s: error: rank %d: %s\n", tool, world().rank, message.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::_Exit(1);
}

// Rank 0's bytes to every rank.
inline void broadcast(std::string& bytes) {
  uint64_t n = bytes.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  bytes.resize(n);
  if (n) MPI_Bcast(bytes.data(), static_cast<int>(n), MPI_BYTE, 0, MPI_COMM_WORLD);
}

// Every rank's bytes to rank 0 (in rank order; rank 0's own entry is its `mine`).
inline std::vector<std::string> gather(const std::string& mine) {
  const World& w = world();
  int n = static_cast<int>(mine.size());
  std::vector<int> sizes(w.rank == 0 ? w.size : 0), displs;
  MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  if (w.rank == 0) {
    displs.resize(w.size);
    size_t total = 0;
    for (int r = 0; r < w.size; ++r) {
      displs[r] = static_cast<int>(total);
      total += static_cast<size_t>(sizes[r]);
    }
    all.resize(total);
  }
  MPI_Gatherv(mine.data(), n, MPI_BYTE, all.data(), sizes.data(), displs.data(), MPI_BYTE, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> out;
  if (w.rank == 0)
    for (int r = 0; r < w.size; ++r) out.push_back(all.substr(displs[r], sizes[r]));
  return out;
}

// Rank 0's parts[r] to rank r (parts is read on rank 0 only).
inline std::string scatter(const std::vector<std::string>& parts) {
  const World& w = world();
  std::vector<int> sizes, displs;
  std::string all;
  if (w.rank == 0) {
    for (const std::string& p : parts) {
      displs.push_back(static_cast<int>(all.size()));
      sizes.push_back(static_cast<int>(p.size()));
      all += p;
    }
  }
  int n = 0;
  MPI_Scatter(sizes.data(), 1, MPI_INT, &n, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string mine(static_cast<size_t>(n), '\0');
  MPI_Scatterv(all.data(), sizes.data(), displs.data(), MPI_BYTE, mine.data(), n, MPI_BYTE, 0,
               MPI_COMM_WORLD);
  return mine;
}

}  // namespace lazyboe::mpi
#endif

#include "tool_main.h"

namespace lazyboe::mpi {

// The offline tools' main. Launched by mpirun/srun (or with --mpi): rank 0 runs `body` (the
// tool, which sends the other ranks their job; `job_sent` says whether it did) and the other
// ranks `serve`; a failure on any rank ends the job (abort_job). Built without MPI: refuses
// --mpi or a launch with several ranks, in one line, and otherwise runs `body`.
template <class Body, class Serve>
int run_tool_on_ranks(const char* tool, bool mpi_required, int& argc, char**& argv, Body&& body,
                      Serve&& serve, const bool& job_sent) {
  const int launched = launcher_world_size();
#ifdef LAZYBOE_HAVE_MPI
  if (launched > 0 || mpi_required) {
    // From the start (a SIGUSR1 during the set-up must not kill a rank): rank 0 stops the job
    // with a save at its first round; the others, once they know they are not rank 0, ignore it.
    std::signal(SIGUSR1, lazyboe::detail::on_stop_signal);
    init(argc, argv);
    if (world().rank != 0) {
      std::signal(SIGUSR1, SIG_IGN);
      try {
        serve();
      } catch (const std::exception& e) {
        abort_job(tool, e.what());
      }
      finalize();
      return 0;
    }
    const int code = run_tool(tool, body);
    if (code != 0 && code != 130) MPI_Abort(MPI_COMM_WORLD, code);  // the others wait for it
    if (!job_sent) {
      std::string nothing;  // rank 0 had nothing to do: the others end too
      broadcast(nothing);
    }
    finalize();
    return code;
  }
#else
  (void)argc;
  (void)argv;
  (void)serve;
  (void)job_sent;
  if (mpi_required || launched > 1) {
    std::fprintf(stderr,
                 "%s: error: %s, but this %s was built without MPI (install libopenmpi-dev and "
                 "rebuild)\n",
                 tool, mpi_required ? "--mpi given" : "launched by mpirun/srun with several ranks",
                 tool);
    return 1;
  }
#endif
  return run_tool(tool, body);
}

}  // namespace lazyboe::mpi
