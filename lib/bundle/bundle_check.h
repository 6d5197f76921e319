// The value checks every reader of a bundle runs on open (read_bundle for lazyboe-build
// --resume/--inspect and lazyboe-perturb; BundleView::open for lazyboe-query and lazyboe-bench):
// the offsets index their datasets, and every number is finite and within its range. One
// streaming pass over the arrays given; an array left null is not checked (the view does not
// check the trajectory samples, which never decide validity). The first problem is an Error
// naming the file, the dataset, the edge and the value.
#pragma once

#include <array>
#include <cassert>
#include <cstdint>
#include <string>

#include "lazyboe/bundle/bundle_format.h"

namespace lazyboe {

// A bundle's arrays, wherever they are (a Bundle in memory, a mapped file): per dataset of the
// table (bundle_format.h) a pointer, null when absent or not to be checked.
struct BundleArrays {
  uint64_t edges = 0, dof = 0, knot_rows = 0, sample_rows = 0;
  uint64_t perturbations = 0;  // p, the target per edge (with /perturbation)
  std::array<const void*, kBundleDatasetCount> data{};

  // The elements of dataset `id` (its table type is T), or null.
  template <typename T>
  const T* of(BundleDatasetId id) const {
    assert(bundle_dataset_spec(id).type == element_type_of<T>());
    return static_cast<const T*>(data[static_cast<size_t>(id)]);
  }
  void set(BundleDatasetId id, const void* array) { data[static_cast<size_t>(id)] = array; }
};

struct Bundle;
// The arrays of a bundle in memory (knot and sample rows from the sizes and dof).
BundleArrays arrays_of(const Bundle& bundle);

// The accepted ranges (schemas/bundle.md): joint positions within 1e3 rad (or m), velocities
// within 1e4 rad/s, durations in [0, 1e3] s, probabilities in [0, 1], errors >= 0 or NaN (no
// valid perturbation), counts consistent (valid <= done <= p, lazy <= valid, ...).
void check_bundle_arrays(const BundleArrays& arrays, const std::string& where);

}  // namespace lazyboe
