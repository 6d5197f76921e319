// The edge bundle in memory: every per-edge array of the HDF5 file (schemas/bundle.md), plus
// the header held in the file's root attributes.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lazyboe {

struct BundleHeader {
  int schema_version = 1;
  std::string tool_version;
  bool complete = false;  // only a finished build is complete

  // Identity of the inputs: names, paths as given, and FNV-1a 64-bit content hashes (hex).
  std::string robot_name, robot_config, robot_hash;  // hash over config + URDF bytes
  std::string env_name, env_file, env_hash;
  int dof = 0;

  // Generation parameters.
  uint64_t seed = 0;
  uint64_t target_edges = 0;
  std::vector<double> region_lower, region_upper;  // sampling box of start states, size dof
  double min_duration = 0, max_duration = 0;       // command duration range, s
  double knot_interval = 0;                        // nominal spacing of velocity knots, s
  std::string integrator;                          // "euler" or "rk4"
  int substeps = 0;                                // integration steps per control period
  double velocity_scale = 0;                       // knot speed bound, fraction of dq_max
  double limit_scale = 0;                          // command accel/jerk bound, fraction of limits
  double control_rate = 0;                         // Hz
  double sample_interval = 0;                      // s between stored trajectory samples
  double design_theta = 0;                         // neighbourhood radius the bundle is made for

  // Summary (so far, for an incomplete build).
  uint64_t attempts = 0;  // attempts processed; edge k came from attempt edges.attempt[k]
  uint64_t valid = 0;
  std::map<std::string, uint64_t> rejected;  // reason -> count
  uint64_t start_resamples = 0;  // start states drawn again because they were in collision
  double simulated_seconds = 0;
  double wall_seconds = 0;
};

// The perturbation analysis of lazyboe-perturb (paper, Methods C): per edge, counts over
// perturbations of its start state by up to theta, and the probabilities derived from them.
struct Perturbation {
  bool present = false;
  bool complete = false;       // every edge has `perturbations` done
  double theta = 0;            // perturbation radius; lazy threshold theta/2
  uint64_t perturbations = 0;  // p, the target per edge
  uint64_t seed = 0;
  double wall_seconds = 0;
  double simulated_seconds = 0;
  // Per edge (N).
  std::vector<uint64_t> done;       // perturbations simulated so far
  std::vector<uint64_t> valid;      // of them, rollouts passing every check
  std::vector<uint64_t> lazy;       // of the valid ones, end-state error < theta/2
  std::vector<uint64_t> collision;  // rollouts that failed the collision check
  std::vector<double> max_error;    // over the valid ones (NaN when none), rad
  std::vector<double> p_lazy_prop;  // lazy / valid (0 when no perturbation was valid)
  std::vector<double> p_collision;  // collision / done
  // Displacement transfer: the edge's command from q0 + d is predicted to end at qf + d; the
  // transfer residual of a valid perturbation is |q^_f - (qf + d)|. Absent (has_transfer false,
  // the three arrays empty) in an analysis written before these statistics existed.
  bool has_transfer = false;
  std::vector<uint64_t> transfer_lazy;       // of the valid ones, transfer residual < theta/2
  std::vector<double> transfer_max_error;    // over the valid ones (NaN when none), rad
  std::vector<double> p_lazy_prop_transfer;  // transfer_lazy / valid (0 when none valid)
};

struct Bundle {
  BundleHeader header;
  Perturbation perturbation;  // empty until lazyboe-perturb runs
  // Per edge (N edges), row-major with dof columns where two-dimensional.
  std::vector<double> q0, qf;              // N x dof: start and end state (at rest)
  std::vector<double> duration;            // N: simulated duration including settling, s
  std::vector<double> command_duration;    // N: duration of the velocity command, s
  std::vector<uint64_t> attempt;           // N: attempt index (edge = f(seed, attempt))
  std::vector<uint64_t> knot_offset;       // N + 1: rows of `knots` of edge k: [off[k], off[k+1])
  std::vector<double> knots;               // K x dof: velocity knots, rad/s
  std::vector<uint64_t> sample_offset;     // N + 1: rows of the trajectory samples of edge k
  std::vector<float> sample_q, sample_dq;  // S x dof: states every sample_interval, and the end

  size_t size() const { return duration.size(); }
  int dof() const { return header.dof; }
};

}  // namespace lazyboe
