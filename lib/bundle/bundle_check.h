// The value checks every reader of a bundle runs on open (read_bundle for lazyboe-build
// --resume/--inspect and lazyboe-perturb; BundleView::open for lazyboe-query and lazyboe-bench):
// the offsets index their datasets, and every number is finite and within its range. One
// streaming pass over the arrays given; an array left null is not checked (the view does not
// read the trajectory samples, which the planners never use). The first problem is an Error
// naming the file, the dataset, the edge and the value.
#pragma once

#include <cstdint>
#include <string>

namespace lazyboe {

struct BundleArrays {
  uint64_t edges = 0, dof = 0, knot_rows = 0, sample_rows = 0;
  const double* q0 = nullptr;                // edges x dof
  const double* qf = nullptr;                // edges x dof
  const double* duration = nullptr;          // edges
  const double* command_duration = nullptr;  // edges
  const uint64_t* knot_offset = nullptr;     // edges + 1
  const uint64_t* sample_offset = nullptr;   // edges + 1
  const double* knots = nullptr;             // knot_rows x dof
  const float* sample_q = nullptr;           // sample_rows x dof
  const float* sample_dq = nullptr;          // sample_rows x dof
  // /perturbation, when present.
  uint64_t perturbations = 0;  // p, the target per edge
  const uint64_t *done = nullptr, *valid = nullptr, *lazy = nullptr, *collision = nullptr,
                 *transfer_lazy = nullptr;
  const double *max_error = nullptr, *p_lazy_prop = nullptr, *p_collision = nullptr,
               *transfer_max_error = nullptr, *p_lazy_prop_transfer = nullptr;
};

// The accepted ranges (schemas/bundle.md): joint positions within 1e3 rad (or m), velocities
// within 1e4 rad/s, durations in [0, 1e3] s, probabilities in [0, 1], errors >= 0 or NaN (no
// valid perturbation), counts consistent (valid <= done <= p, lazy <= valid, ...).
void check_bundle_arrays(const BundleArrays& arrays, const std::string& where);

}  // namespace lazyboe
