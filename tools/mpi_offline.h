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

#include <cstdlib>
#include <string>

namespace lazyboe::mpi {

// Launched by mpirun / srun (their environment variables), and the world size they announce.
inline int launcher_world_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE", "SLURM_NTASKS"}) {
    const char* v = std::getenv(name);
    if (v && std::atoi(v) > 0 && std::string(name) != "SLURM_NTASKS") return std::atoi(v);
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
