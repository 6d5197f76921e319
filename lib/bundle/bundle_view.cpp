#include "lazyboe/bundle/bundle_view.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <utility>

#include "lazyboe/bundle/bundle_check.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/hdf5_handle.h"
#include "lazyboe/common/error.h"

namespace lazyboe {

namespace ds = bundle_dataset;

void FileUnmap::operator()(void* address) const { ::munmap(address, bytes); }

namespace {

// The checksum attribute of the datasets, space-separated; empty when one has none.
std::string stored_checksums(const std::string& path, long file,
                             std::initializer_list<const char*> datasets) {
  std::string out;
  for (const char* name : datasets) {
    const h5::Dataset dset = h5::open_dataset(path, file, name);
    if (!h5::has_attribute(dset, kChecksumAttribute)) return "";
    out += (out.empty() ? "" : " ") + h5::read_attr_string(path, dset, kChecksumAttribute);
  }
  return out;
}

}  // namespace

CommandProfile BundleView::command(size_t e) const {
  const int n = dof();
  return CommandProfile{knots_ + knot_offset_[e] * n,
                        static_cast<int>(knot_offset_[e + 1] - knot_offset_[e]), n,
                        command_duration_[e]};
}

template <typename T>
const T* BundleView::attach(long file, const std::string& dataset,
                            const std::vector<uint64_t>& dims, bool allow_mmap) {
  const std::vector<uint64_t> shape = h5::dataset_shape(path_, file, dataset);
  if (shape != dims) {
    fail(path_,
         dataset + ": shape " + h5::shape_string(shape) + ", expected " + h5::shape_string(dims));
  }
  uint64_t count = 1;
  for (uint64_t d : dims) {
    if (d != 0 && count > std::numeric_limits<uint64_t>::max() / sizeof(T) / d)
      fail(path_, dataset + ": shape " + h5::shape_string(shape) + " is too large");
    count *= d;
  }
  if (count == 0) return nullptr;
  if (allow_mmap && map_) {
    const DatasetLocation loc = dataset_location(path_, file, dataset);
    const uint64_t mapped = map_.get_deleter().bytes;  // offsets from the file: no wrap-around
    if (loc.contiguous && loc.bytes == count * sizeof(T) && loc.file_offset % alignof(T) == 0 &&
        loc.bytes <= mapped && loc.file_offset <= mapped - loc.bytes) {
      return reinterpret_cast<const T*>(static_cast<const char*>(map_.get()) + loc.file_offset);
    }
    warnings_.push_back(
        dataset + " cannot be memory-mapped (chunked, compressed or unaligned): read into memory");
  }
  all_mapped_ = false;
  auto data = std::make_shared<std::vector<T>>(h5::read_dataset<T>(path_, file, dataset, dims));
  owned_.push_back(data);
  return data->data();
}

BundleView BundleView::open(const std::string& path, bool allow_mmap) {
  BundleView v;
  v.path_ = path;
  uint64_t n = 0;
  v.header_ = read_bundle_header(path, &n);
  require_complete(v.header_, path);
  v.edges_ = n;
  const uint64_t dof = static_cast<uint64_t>(v.header_.dof);

  if (allow_mmap) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) == 0 && st.st_size > 0) {
      void* map = ::mmap(nullptr, static_cast<size_t>(st.st_size), PROT_READ, MAP_SHARED, fd, 0);
      if (map != MAP_FAILED) {
        v.map_ = std::unique_ptr<void, FileUnmap>(map, FileUnmap{static_cast<size_t>(st.st_size)});
      }
    }
    ::close(fd);  // the mapping stays valid
    if (!v.map_) v.warnings_.push_back("cannot memory-map the file: datasets read into memory");
  }
  v.all_mapped_ = v.map_ != nullptr;

  h5::File file = h5::open_file(path);
  v.q0_ = v.attach<double>(file, ds::q0, {n, dof}, allow_mmap);
  v.qf_ = v.attach<double>(file, ds::qf, {n, dof}, allow_mmap);
  v.states_checksum_ = stored_checksums(path, file, {ds::q0, ds::qf});
  v.duration_ = v.attach<double>(file, ds::duration, {n}, allow_mmap);
  v.command_duration_ = v.attach<double>(file, ds::command_duration, {n}, allow_mmap);
  v.knot_offset_ = v.attach<uint64_t>(file, ds::knot_offset, {n + 1}, allow_mmap);
  const std::vector<uint64_t> knot_shape = h5::dataset_shape(path, file, ds::knots);
  if (knot_shape.size() != 2 || knot_shape[1] != dof)
    fail(path, std::string(ds::knots) + ": expected K x dof");
  v.knots_ = v.attach<double>(file, ds::knots, knot_shape, allow_mmap);
  // The sample offsets are checked like every reader checks them (the samples' values are
  // never used to plan: read_bundle and --verify check them; the workspace index reads them).
  const std::vector<uint64_t> sample_shape = h5::dataset_shape(path, file, ds::sample_q);
  if (sample_shape.size() != 2 || sample_shape[1] != dof)
    fail(path, std::string(ds::sample_q) + ": expected S x dof");
  const uint64_t sample_rows = sample_shape[0];
  v.sample_offset_ = v.attach<uint64_t>(file, ds::sample_offset, {n + 1}, allow_mmap);
  v.sample_q_ = v.attach<float>(file, ds::sample_q, sample_shape, allow_mmap);
  v.check_knot_ranges(knot_shape[0]);
  if (h5::exists(file, ds::perturbation)) {
    h5::Group g(H5Gopen2(file, ds::perturbation, H5P_DEFAULT));
    if (!g.valid()) fail(path, std::string(ds::perturbation) + ": cannot open group");
    if (v.use_perturbation(h5::read_attr_bool(path, g, "complete"))) {
      v.perturbation_theta_ = h5::read_attr_f64(path, g, "theta");
      v.p_lazy_prop_ = v.attach<double>(file, ds::p_lazy_prop, {n}, allow_mmap);
      v.p_collision_ = v.attach<double>(file, ds::p_collision, {n}, allow_mmap);
      // Optional: absent from analyses written before the transfer statistics.
      if (has_transfer_datasets(path, file)) {
        v.p_lazy_prop_transfer_ = v.attach<double>(file, ds::p_lazy_prop_transfer, {n}, allow_mmap);
        v.transfer_max_error_ = v.attach<double>(file, ds::transfer_max_error, {n}, allow_mmap);
        v.has_transfer_ = true;
      }
    }
  }
  v.check_values(knot_shape[0], sample_rows, v.sample_offset_);
  return v;
}

BundleView BundleView::from_memory(std::shared_ptr<const Bundle> bundle, std::string name) {
  if (!bundle) fail(name, "no bundle");
  const Bundle& b = *bundle;
  check_bundle(b, name);  // the sizes and offsets a file's shapes guarantee
  require_complete(b.header, name);
  BundleView v;
  v.path_ = std::move(name);
  v.header_ = b.header;
  v.edges_ = b.size();
  v.owned_.push_back(bundle);
  v.q0_ = b.q0.data();
  v.qf_ = b.qf.data();
  v.duration_ = b.duration.data();
  v.command_duration_ = b.command_duration.data();
  v.knot_offset_ = b.knot_offset.data();
  v.knots_ = b.knots.data();
  v.sample_offset_ = b.sample_offset.data();
  v.sample_q_ = b.sample_q.data();
  v.check_knot_ranges(b.knots.size() / static_cast<size_t>(b.dof()));
  const Perturbation& p = b.perturbation;
  if (p.present && v.use_perturbation(p.complete)) {
    v.perturbation_theta_ = p.theta;
    v.p_lazy_prop_ = p.p_lazy_prop.data();
    v.p_collision_ = p.p_collision.data();
    if (p.has_transfer) {
      v.p_lazy_prop_transfer_ = p.p_lazy_prop_transfer.data();
      v.transfer_max_error_ = p.transfer_max_error.data();
      v.has_transfer_ = true;
    }
  }
  // After the perturbation is attached, so that its values are checked too (as open does).
  v.check_values(b.knots.size() / static_cast<size_t>(b.dof()),
                 b.sample_q.size() / static_cast<size_t>(b.dof()), b.sample_offset.data());
  return v;
}

// The offsets index the knots: check them once so that no query can read out of bounds.
void BundleView::check_knot_ranges(uint64_t knot_rows) const {
  for (uint64_t e = 0; e < edges_; ++e) {
    if (knot_offset_[e + 1] < knot_offset_[e] + 2 || knot_offset_[e + 1] > knot_rows) {
      fail(path_,
           std::string(ds::knot_offset) + ": edge " + std::to_string(e) + " has a bad knot range");
    }
  }
}

// The checks every reader runs (bundle_check.h) on what the view reads, in one pass.
void BundleView::check_values(uint64_t knot_rows, uint64_t sample_rows,
                              const uint64_t* sample_offset) const {
  BundleArrays a;
  a.edges = edges_;
  a.dof = static_cast<uint64_t>(dof());
  a.knot_rows = knot_rows;
  a.sample_rows = sample_rows;
  a.q0 = q0_;
  a.qf = qf_;
  a.duration = duration_;
  a.command_duration = command_duration_;
  a.knot_offset = knot_offset_;
  a.sample_offset = sample_offset;
  a.knots = knots_;
  a.p_lazy_prop = p_lazy_prop_;
  a.p_collision = p_collision_;
  a.p_lazy_prop_transfer = p_lazy_prop_transfer_;
  a.transfer_max_error = transfer_max_error_;
  check_bundle_arrays(a, path_);
  if (has_perturbation_ && !(perturbation_theta_ > 0 && perturbation_theta_ <= 1e3))
    fail(path_, std::string(ds::perturbation) + ": attribute theta: " +
                    std::to_string(perturbation_theta_) + ", expected a value in (0, 1000]");
}

// Only a finished analysis is used; an unfinished one is ignored with a warning.
bool BundleView::use_perturbation(bool complete) {
  if (!complete) {
    warnings_.push_back(
        "the perturbation analysis is incomplete (finish it with lazyboe-perturb): not used");
    return false;
  }
  has_perturbation_ = true;
  return true;
}

}  // namespace lazyboe
