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

// Asks the kernel to read [data, data + bytes) of the mapping at `map` (of `map_bytes`) ahead,
// without waiting; nothing when the range is not in the mapping (a dataset read into memory).
void read_ahead(const void* map, size_t map_bytes, const void* data, size_t bytes) {
  const auto begin = reinterpret_cast<uintptr_t>(map), at = reinterpret_cast<uintptr_t>(data);
  if (bytes == 0 || at < begin || at + bytes > begin + map_bytes) return;
  const uintptr_t page = static_cast<uintptr_t>(::sysconf(_SC_PAGESIZE));
  const uintptr_t from = at / page * page;
  ::madvise(reinterpret_cast<void*>(from), at + bytes - from, MADV_WILLNEED);
}

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
  const uint64_t* offset = arrays_.of<uint64_t>(Id::KnotOffset);
  return CommandProfile{f64(Id::Knots) + offset[e] * n, static_cast<int>(offset[e + 1] - offset[e]),
                        n, f64(Id::CommandDuration)[e]};
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

bool BundleView::holds(const BundleDatasetSpec& spec) const {
  return present_with(spec, has_perturbation_, has_transfer_);
}

void BundleView::attach_datasets(long file, const BundleRows& rows, bool allow_mmap) {
  arrays_.edges = rows.edges;
  arrays_.dof = static_cast<uint64_t>(dof());
  arrays_.knot_rows = rows.knots;
  arrays_.sample_rows = rows.samples;
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (!spec.viewed || !holds(spec)) continue;
    const std::vector<uint64_t> dims = dataset_shape(spec, rows, arrays_.dof);
    const void* data = nullptr;
    switch (spec.type) {
      case ElementType::F64:
        data = attach<double>(file, spec.path, dims, allow_mmap);
        break;
      case ElementType::U64:
        data = attach<uint64_t>(file, spec.path, dims, allow_mmap);
        break;
      case ElementType::F32:
        data = attach<float>(file, spec.path, dims, allow_mmap);
        break;
    }
    arrays_.set(spec.id, data);
  }
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
  v.states_checksum_ = stored_checksums(path, file, {ds::q0, ds::qf});
  BundleRows rows{n, 0, 0};
  rows.knots = rows_by_dof(path, file, ds::knots, dof);
  // The sample offsets are checked like every reader checks them (the samples' values steer
  // lazysp's look before a simulation and make the workspace index, never decide validity:
  // read_bundle and --verify check them).
  rows.samples = rows_by_dof(path, file, ds::sample_q, dof);
  if (h5::exists(file, ds::perturbation)) {
    h5::Group g(H5Gopen2(file, ds::perturbation, H5P_DEFAULT));
    if (!g.valid()) fail(path, std::string(ds::perturbation) + ": cannot open group");
    if (v.use_perturbation(h5::read_attr_bool(path, g, "complete"))) {
      v.perturbation_theta_ = h5::read_attr_f64(path, g, "theta");
      // Optional: absent from analyses written before the transfer statistics.
      v.has_transfer_ = has_transfer_datasets(path, file);
    }
  }
  v.attach_datasets(file, rows, allow_mmap);
  v.check_knot_ranges();
  v.check_values();
  return v;
}

void BundleView::read_samples_ahead() const {
  if (!map_ || edges_ == 0 || !samples_ahead_) return;
  std::call_once(*samples_ahead_, [this] {
    const uint64_t rows = arrays_.of<uint64_t>(Id::SampleOffset)[edges_];
    read_ahead(map_.get(), map_.get_deleter().bytes, samples(0),
               static_cast<size_t>(rows) * static_cast<size_t>(dof()) * sizeof(float));
  });
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
  const Perturbation& p = b.perturbation;
  if (p.present && v.use_perturbation(p.complete)) {
    v.perturbation_theta_ = p.theta;
    v.has_transfer_ = p.has_transfer;
  }
  const BundleArrays all = arrays_of(b);
  v.arrays_ = all;
  v.arrays_.data = {};
  for (const BundleDatasetSpec& spec : bundle_datasets())
    if (spec.viewed && v.holds(spec))
      v.arrays_.set(spec.id, all.data[static_cast<size_t>(spec.id)]);
  v.check_knot_ranges();
  v.check_values();
  return v;
}

// The offsets index the knots: check them once so that no query can read out of bounds.
void BundleView::check_knot_ranges() const {
  const uint64_t* offset = arrays_.of<uint64_t>(Id::KnotOffset);
  for (uint64_t e = 0; e < edges_; ++e) {
    if (offset[e + 1] < offset[e] + 2 || offset[e + 1] > arrays_.knot_rows) {
      fail(path_,
           std::string(ds::knot_offset) + ": edge " + std::to_string(e) + " has a bad knot range");
    }
  }
}

// The checks every reader runs (bundle_check.h) on what the view reads, in one pass; not the
// samples' values, which never decide validity (lazysp's look only steers with them; a
// non-finite sample fails its state check), so opening does not read them all.
void BundleView::check_values() const {
  BundleArrays a = arrays_;
  a.set(Id::SampleQ, nullptr);
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
