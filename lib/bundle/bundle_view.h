// Read-only access to a bundle for planning: the per-edge datasets the planners use are
// memory-mapped straight from the HDF5 file (contiguous datasets, at the offsets HDF5 reports),
// so opening reads almost nothing, processes share one copy in the page cache, and a bundle
// larger than RAM still works. A dataset that cannot be mapped (chunked, compressed, or not
// aligned for its type) is read into memory instead, with a warning. A view can also be made
// of a bundle already in memory (tests, front ends that build their own), validated the same way.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_check.h"
#include "lazyboe/bundle/bundle_format.h"
#include "lazyboe/sim/command_profile.h"

namespace lazyboe {

// Unmaps a read-only file mapping of `bytes` bytes.
struct FileUnmap {
  size_t bytes = 0;
  void operator()(void* address) const;
};

class BundleView {
 public:
  // Throws Error for a missing, corrupt or incomplete bundle. `allow_mmap = false` reads
  // every dataset into memory (the fallback path, also used to compare both).
  static BundleView open(const std::string& path, bool allow_mmap = true);
  // A view into `bundle`'s arrays, which it keeps alive; `name` stands for the path in path()
  // and in errors. Throws Error for an inconsistent (check_bundle) or incomplete bundle.
  static BundleView from_memory(std::shared_ptr<const Bundle> bundle, std::string name);

  const std::string& path() const { return path_; }
  const BundleHeader& header() const { return header_; }
  size_t size() const { return edges_; }
  int dof() const { return header_.dof; }

  const double* q0(size_t edge) const { return f64(Id::Q0) + edge * dof(); }
  const double* qf(size_t edge) const { return f64(Id::Qf) + edge * dof(); }
  double duration(size_t edge) const { return f64(Id::Duration)[edge]; }
  CommandProfile command(size_t edge) const;

  bool has_perturbation() const { return has_perturbation_; }
  double perturbation_theta() const { return perturbation_theta_; }
  double p_lazy_prop(size_t edge) const { return f64(Id::PLazyProp)[edge]; }
  double p_collision(size_t edge) const { return f64(Id::PCollision)[edge]; }
  // The transfer statistics of the analysis (lazyboe-perturb since they exist): false for an
  // analysis written before them, or without a (finished) analysis.
  bool has_transfer() const { return has_transfer_; }
  double p_lazy_prop_transfer(size_t edge) const { return f64(Id::PLazyPropTransfer)[edge]; }
  double transfer_max_error(size_t edge) const { return f64(Id::TransferMaxError)[edge]; }

  // The per-edge arrays themselves (size() values each), for zero-copy views (the Python
  // module); null when the bundle has none (no analysis, or no transfer statistics).
  const double* duration_data() const { return f64(Id::Duration); }
  const double* command_duration_data() const { return f64(Id::CommandDuration); }
  const double* p_lazy_prop_data() const { return f64(Id::PLazyProp); }
  const double* p_collision_data() const { return f64(Id::PCollision); }
  const double* p_lazy_prop_transfer_data() const { return f64(Id::PLazyPropTransfer); }
  const double* transfer_max_error_data() const { return f64(Id::TransferMaxError); }

  // The stored trajectory samples of an edge: sample_count(edge) rows of dof floats, the states
  // every sample_interval of the header and the end state (none when it is 0).
  size_t sample_count(size_t edge) const {
    const uint64_t* offset = arrays_.of<uint64_t>(Id::SampleOffset);
    return offset[edge + 1] - offset[edge];
  }
  const float* samples(size_t edge) const {
    return arrays_.of<float>(Id::SampleQ) + arrays_.of<uint64_t>(Id::SampleOffset)[edge] * dof();
  }

  bool memory_mapped() const { return all_mapped_; }  // every dataset mapped
  // Asks the kernel to read the trajectory samples of a mapped file ahead, without waiting, once
  // per view (lazysp's look reads the samples of the edges it considers; on a cold page cache
  // its first queries waited on the disk). Nothing for a view in memory.
  void read_samples_ahead() const;
  // The checksums stored with the q0 and qf datasets, "<q0> <qf>": what ties an index file
  // (edge_index_file.h) to these edge states. Empty for a file written before checksums and
  // for an in-memory view.
  const std::string& states_checksum() const { return states_checksum_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  using Id = BundleDatasetId;
  BundleView() = default;
  const double* f64(Id id) const { return arrays_.of<double>(id); }
  template <typename T>
  const T* attach(long file, const std::string& dataset, const std::vector<uint64_t>& dims,
                  bool allow_mmap);
  void attach_datasets(long file, const BundleRows& rows, bool allow_mmap);
  bool holds(const BundleDatasetSpec& spec) const;  // the view has the dataset's group
  // What both ways of making a view check and decide once the arrays are attached.
  void check_knot_ranges() const;
  void check_values() const;
  bool use_perturbation(bool complete);

  std::string path_;
  BundleHeader header_;
  size_t edges_ = 0;
  // The read-only mapping of the whole file (unmapped with the view) and datasets read into
  // memory instead (or the in-memory bundle viewed).
  std::unique_ptr<void, FileUnmap> map_;
  std::unique_ptr<std::once_flag> samples_ahead_ = std::make_unique<std::once_flag>();
  bool all_mapped_ = false;
  std::vector<std::shared_ptr<const void>> owned_;
  std::vector<std::string> warnings_;
  std::string states_checksum_;

  // The viewed datasets (the table's `viewed` ones the file has), mapped or owned.
  BundleArrays arrays_;
  bool has_transfer_ = false;
  double perturbation_theta_ = 0;
  bool has_perturbation_ = false;
};

}  // namespace lazyboe
