#include "lazyboe/bundle/bundle_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <type_traits>
#include <utility>
#include <variant>

#include "lazyboe/bundle/bundle_check.h"
#include "lazyboe/bundle/bundle_format.h"
#include "lazyboe/bundle/hdf5_handle.h"
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"

namespace lazyboe {
namespace {

namespace ds = bundle_dataset;

std::string str(uint64_t v) { return std::to_string(v); }

// ---- consistency checks shared by the writer (on memory) and the reader (on the file) ----

// `name` is "bundle.knot_offset" for memory, "/edges/knot_offset" for the file.
void check_offsets(const std::string& where, const std::string& name,
                   const std::vector<uint64_t>& offsets, uint64_t rows,
                   const std::string& rows_name) {
  if (offsets.empty()) return;  // sizes are checked by the caller
  if (offsets[0] != 0) fail(where, name + ": first value " + str(offsets[0]) + ", expected 0");
  for (size_t k = 0; k + 1 < offsets.size(); ++k)
    if (offsets[k + 1] < offsets[k])
      fail(where, name + ": decreases at edge " + str(k) + " (" + str(offsets[k]) + " -> " +
                      str(offsets[k + 1]) + ")");
  if (offsets.back() != rows)
    fail(where, name + ": last value " + str(offsets.back()) + " does not match the " + str(rows) +
                    " rows of " + rows_name);
}

void check_header(const std::string& where, const std::string& prefix, const BundleHeader& h) {
  if (h.dof < 1) fail(where, prefix + "dof: " + std::to_string(h.dof) + ", expected at least 1");
  const size_t dof = static_cast<size_t>(h.dof);
  if (h.region_lower.size() != dof)
    fail(where, prefix + "region_lower: " + str(h.region_lower.size()) +
                    " values, expected dof = " + str(dof));
  if (h.region_upper.size() != dof)
    fail(where, prefix + "region_upper: " + str(h.region_upper.size()) +
                    " values, expected dof = " + str(dof));
}

void check_size(const std::string& where, const std::string& field, size_t found, size_t expected,
                const std::string& expected_text) {
  if (found != expected)
    fail(where, "bundle." + field + ": " + str(found) + " values, expected " + expected_text +
                    " = " + str(expected));
}

// What an in-memory array's size should be, in words, for check_bundle's errors.
std::string memory_size_text(const BundleDatasetSpec& spec, uint64_t edges, uint64_t dof) {
  switch (spec.rows) {
    case RowRule::Edges:
      return spec.per_joint ? "edges x dof = " + str(edges) + " x " + str(dof)
                            : "edges (duration.size())";
    case RowRule::EdgesPlusOne:
      return "edges + 1";
    case RowRule::KnotRows:
      return "rows of knots x dof";
    case RowRule::SampleRows:
      return "sample_q.size()";
  }
  return "";
}

// Real attributes: finite and non-negative (an empty bundle written from default settings has
// zeros; the tools that use a setting check it against what they need).
void check_header_values(const std::string& where, const BundleHeader& h) {
  const std::pair<const char*, double> values[] = {{"min_duration", h.min_duration},
                                                   {"max_duration", h.max_duration},
                                                   {"knot_interval", h.knot_interval},
                                                   {"velocity_scale", h.velocity_scale},
                                                   {"limit_scale", h.limit_scale},
                                                   {"control_rate", h.control_rate},
                                                   {"sample_interval", h.sample_interval},
                                                   {"design_theta", h.design_theta},
                                                   {"simulated_seconds", h.simulated_seconds},
                                                   {"wall_seconds", h.wall_seconds}};
  for (const auto& [name, v] : values)
    if (!(std::isfinite(v) && v >= 0))
      fail(where, std::string("attribute ") + name + ": " + std::to_string(v) +
                      ", expected a finite number >= 0");
  for (const auto* bounds : {&h.region_lower, &h.region_upper})
    for (double v : *bounds)
      if (!(std::abs(v) <= 1e3))
        fail(where, std::string("attribute ") +
                        (bounds == &h.region_lower ? "region_lower" : "region_upper") + ": " +
                        std::to_string(v) + " is outside [-1000, 1000]");
}

// ---- header <-> root attributes ----

void write_header(const std::string& where, hid_t file, const BundleHeader& h, uint64_t edges) {
  using namespace h5;
  write_attr_i64(where, file, "schema_version", kBundleSchemaVersion);
  write_attr_string(where, file, "tool_version", h.tool_version);
  write_attr_bool(where, file, "complete", h.complete);
  write_attr_string(where, file, "robot_name", h.robot_name);
  write_attr_string(where, file, "robot_config", h.robot_config);
  write_attr_string(where, file, "robot_hash", h.robot_hash);
  write_attr_string(where, file, "env_name", h.env_name);
  write_attr_string(where, file, "env_file", h.env_file);
  write_attr_string(where, file, "env_hash", h.env_hash);
  write_attr_i64(where, file, "dof", h.dof);
  write_attr_u64(where, file, "seed", h.seed);
  write_attr_u64(where, file, "target_edges", h.target_edges);
  write_attr_f64s(where, file, "region_lower", h.region_lower);
  write_attr_f64s(where, file, "region_upper", h.region_upper);
  write_attr_f64(where, file, "min_duration", h.min_duration);
  write_attr_f64(where, file, "max_duration", h.max_duration);
  write_attr_f64(where, file, "knot_interval", h.knot_interval);
  write_attr_f64(where, file, "velocity_scale", h.velocity_scale);
  write_attr_f64(where, file, "limit_scale", h.limit_scale);
  write_attr_f64(where, file, "control_rate", h.control_rate);
  write_attr_f64(where, file, "sample_interval", h.sample_interval);
  write_attr_f64(where, file, "design_theta", h.design_theta);
  write_attr_u64(where, file, "attempts", h.attempts);
  write_attr_u64(where, file, "valid", h.valid);
  std::vector<std::string> reasons;
  std::vector<uint64_t> counts;
  for (const auto& [reason, count] : h.rejected) {
    reasons.push_back(reason);
    counts.push_back(count);
  }
  write_attr_strings(where, file, "rejected_reasons", reasons);
  write_attr_u64s(where, file, "rejected_counts", counts);
  write_attr_u64(where, file, "start_resamples", h.start_resamples);
  write_attr_string(where, file, "integrator", h.integrator);
  write_attr_i64(where, file, "substeps", h.substeps);
  write_attr_f64(where, file, "simulated_seconds", h.simulated_seconds);
  write_attr_f64(where, file, "wall_seconds", h.wall_seconds);
  write_attr_u64(where, file, "edges", edges);
}

BundleHeader read_header(const std::string& where, hid_t file, uint64_t* edges) {
  using namespace h5;
  BundleHeader h;
  if (!has_attribute(file, "schema_version"))
    fail(where, "attribute schema_version missing: not a lazyboe bundle");
  const int64_t version = read_attr_i64(where, file, "schema_version");
  if (version != kBundleSchemaVersion)
    fail(where, "schema_version " + std::to_string(version) + ": written by " +
                    (version > kBundleSchemaVersion ? "a newer" : "an older") +
                    " lazyboe (this one reads schema version " +
                    std::to_string(kBundleSchemaVersion) + ")");
  h.schema_version = static_cast<int>(version);
  h.tool_version = read_attr_string(where, file, "tool_version");
  h.complete = read_attr_bool(where, file, "complete");
  h.robot_name = read_attr_string(where, file, "robot_name");
  h.robot_config = read_attr_string(where, file, "robot_config");
  h.robot_hash = read_attr_string(where, file, "robot_hash");
  h.env_name = read_attr_string(where, file, "env_name");
  h.env_file = read_attr_string(where, file, "env_file");
  h.env_hash = read_attr_string(where, file, "env_hash");
  const int64_t dof = read_attr_i64(where, file, "dof");
  if (dof < 1 || dof > 1000000)
    fail(where, "attribute dof: " + std::to_string(dof) + ", expected a positive joint count");
  h.dof = static_cast<int>(dof);
  h.seed = read_attr_u64(where, file, "seed");
  h.target_edges = read_attr_u64(where, file, "target_edges");
  h.region_lower = read_attr_f64s(where, file, "region_lower");
  h.region_upper = read_attr_f64s(where, file, "region_upper");
  h.min_duration = read_attr_f64(where, file, "min_duration");
  h.max_duration = read_attr_f64(where, file, "max_duration");
  h.knot_interval = read_attr_f64(where, file, "knot_interval");
  h.velocity_scale = read_attr_f64(where, file, "velocity_scale");
  h.limit_scale = read_attr_f64(where, file, "limit_scale");
  h.control_rate = read_attr_f64(where, file, "control_rate");
  h.sample_interval = read_attr_f64(where, file, "sample_interval");
  h.design_theta = read_attr_f64(where, file, "design_theta");
  h.attempts = read_attr_u64(where, file, "attempts");
  h.valid = read_attr_u64(where, file, "valid");
  const std::vector<std::string> reasons = read_attr_strings(where, file, "rejected_reasons");
  const std::vector<uint64_t> counts = read_attr_u64s(where, file, "rejected_counts");
  if (reasons.size() != counts.size())
    fail(where, "attribute rejected_counts: " + str(counts.size()) +
                    " values, but rejected_reasons has " + str(reasons.size()));
  for (size_t i = 0; i < reasons.size(); ++i)
    if (!h.rejected.emplace(reasons[i], counts[i]).second)
      fail(where, "attribute rejected_reasons: reason '" + reasons[i] + "' appears twice");
  h.start_resamples = read_attr_u64(where, file, "start_resamples");
  h.integrator = read_attr_string(where, file, "integrator");
  h.substeps = static_cast<int>(read_attr_i64(where, file, "substeps"));
  h.simulated_seconds = read_attr_f64(where, file, "simulated_seconds");
  h.wall_seconds = read_attr_f64(where, file, "wall_seconds");
  const uint64_t n = read_attr_u64(where, file, "edges");
  if (edges) *edges = n;
  check_header(where, "attribute ", h);
  check_header_values(where, h);
  return h;
}

// Shape of a dataset, which must be `expected`; `meaning` says what the dimensions are.
void expect_shape(const std::string& where, hid_t file, const char* name,
                  const std::vector<uint64_t>& expected, const std::string& meaning) {
  const std::vector<uint64_t> found = h5::dataset_shape(where, file, name);
  if (found != expected)
    fail(where, std::string(name) + ": shape " + h5::shape_string(found) + ", expected " +
                    h5::shape_string(expected) + " (" + meaning + ")");
}

// A dataset with its checksum: "fnv1a64:<16 hex digits>" of its raw (little-endian) bytes, as
// the attribute `checksum` (the layout stays contiguous and mappable).
template <class T>
void write_checked(const std::string& where, hid_t file, const char* name,
                   const std::vector<T>& data, const std::vector<uint64_t>& dims) {
  h5::write_dataset(where, file, name, data, dims);
  Fnv1a64 hash;
  hash.update(data.data(), data.size() * sizeof(T));
  h5::Dataset dset = h5::open_dataset(where, file, name);
  h5::write_attr_string(where, dset, kChecksumAttribute, std::string(kChecksumPrefix) + hash.hex());
}

// The /perturbation group and its attributes (its datasets are written with the others).
void write_perturbation_group(const std::string& tmp, hid_t file, const Perturbation& p) {
  h5::Group g = h5::create_group(tmp, file, ds::perturbation);
  h5::write_attr_bool(tmp, g, "complete", p.complete);
  h5::write_attr_f64(tmp, g, "theta", p.theta);
  h5::write_attr_u64(tmp, g, "perturbations", p.perturbations);
  h5::write_attr_u64(tmp, g, "seed", p.seed);
  h5::write_attr_f64(tmp, g, "wall_seconds", p.wall_seconds);
  h5::write_attr_f64(tmp, g, "simulated_seconds", p.simulated_seconds);
  h5::write_attr_string(
      tmp, g, "distribution",
      "start + d, d = r u: u uniform on the unit sphere, r uniform in (0, theta]");
}

// Every dataset the bundle holds, in the table's order.
void write_datasets(const std::string& tmp, hid_t file, const Bundle& b) {
  h5::create_group(tmp, file, "/edges");
  h5::create_group(tmp, file, "/controls");
  h5::create_group(tmp, file, "/trajectory");
  bool group_written = false;  // /perturbation, before its first dataset (the file's order)
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (!bundle_has(b, spec)) continue;
    if (spec.presence != Presence::Always && !std::exchange(group_written, true))
      write_perturbation_group(tmp, file, b.perturbation);
    const std::vector<uint64_t> dims =
        dataset_shape(spec, bundle_rows(b), static_cast<uint64_t>(b.dof()));
    std::visit([&](const auto* data) { write_checked(tmp, file, spec.path, *data, dims); },
               bundle_array(b, spec.id));
  }
}

// The dataset bytes of the file, to size its memory image at once.
uint64_t payload_bytes(const Bundle& b) {
  uint64_t bytes = 0;
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (!bundle_has(b, spec)) continue;
    std::visit([&](const auto* data) { bytes += data->size() * sizeof((*data)[0]); },
               bundle_array(b, spec.id));
  }
  return bytes;
}

}  // namespace

void check_bundle(const Bundle& b, const std::string& where) {
  const BundleHeader& h = b.header;
  if (h.schema_version != kBundleSchemaVersion)
    fail(where, "bundle.header.schema_version: " + std::to_string(h.schema_version) +
                    ", this lazyboe writes schema version " + std::to_string(kBundleSchemaVersion));
  check_header(where, "bundle.header.", h);
  const size_t dof = static_cast<size_t>(h.dof);
  if (b.knots.size() % dof != 0)
    fail(where,
         "bundle.knots: " + str(b.knots.size()) + " values, not a multiple of dof = " + str(dof));
  if (b.sample_q.size() % dof != 0)
    fail(where, "bundle.sample_q: " + str(b.sample_q.size()) +
                    " values, not a multiple of dof = " + str(dof));
  const BundleRows rows = bundle_rows(b);
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (!bundle_has(b, spec)) continue;
    const size_t found =
        std::visit([](const auto* data) { return data->size(); }, bundle_array(b, spec.id));
    const size_t expected = dataset_rows(spec, rows) * (spec.per_joint ? dof : 1);
    check_size(where, spec.field, found, expected, memory_size_text(spec, rows.edges, dof));
  }
  check_offsets(where, "bundle.knot_offset", b.knot_offset, b.knots.size() / dof, "bundle.knots");
  check_offsets(where, "bundle.sample_offset", b.sample_offset, b.sample_q.size() / dof,
                "bundle.sample_q");
}

void write_bundle(const std::string& path, const Bundle& b) {
  check_bundle(b, path);
  AtomicFile out(path, AtomicFile::Writer::External);
  // The file is composed in memory and written with plain writes, so that a full disk is one
  // clear error naming `path` (HDF5 itself, failing a write, leaves a state that crashes at exit).
  h5::File file = h5::create_memory_file(path, payload_bytes(b) + (1 << 20));
  write_header(path, file, b.header, b.size());
  write_datasets(path, file, b);
  const std::vector<unsigned char> image = h5::memory_file_image(path, file);
  file.close();
  out.write_all(image.data(), image.size());
  out.commit();
}

void require_complete(const BundleHeader& h, const std::string& path) {
  if (h.complete) return;
  fail(path, "incomplete bundle (" + str(h.valid) + " of " + str(h.target_edges) +
                 " edges): finish it with: lazyboe-build --resume --out " + path);
}

BundleHeader read_bundle_header(const std::string& path, uint64_t* edges) {
  h5::File file = h5::open_file(path);
  return read_header(path, file, edges);
}

namespace {

// The /perturbation group's attributes (present, with the datasets read from the table).
void read_perturbation_group(const std::string& path, hid_t file, Perturbation& p) {
  h5::Group g(H5Gopen2(file, ds::perturbation, H5P_DEFAULT));
  if (!g.valid()) fail(path, std::string(ds::perturbation) + ": cannot open group");
  p.present = true;
  p.complete = h5::read_attr_bool(path, g, "complete");
  p.theta = h5::read_attr_f64(path, g, "theta");
  p.perturbations = h5::read_attr_u64(path, g, "perturbations");
  p.seed = h5::read_attr_u64(path, g, "seed");
  p.wall_seconds = h5::read_attr_f64(path, g, "wall_seconds");
  p.simulated_seconds = h5::read_attr_f64(path, g, "simulated_seconds");
}

}  // namespace

Bundle read_bundle(const std::string& path) {
  h5::File file = h5::open_file(path);
  Bundle b;
  uint64_t n = 0;
  b.header = read_header(path, file, &n);
  const uint64_t dof = static_cast<uint64_t>(b.header.dof);

  const uint64_t k = rows_by_dof(path, file, ds::knots, dof);
  const uint64_t s = rows_by_dof(path, file, ds::sample_q, dof);
  if (h5::exists(file, ds::perturbation)) read_perturbation_group(path, file, b.perturbation);
  b.perturbation.has_transfer = b.perturbation.present && has_transfer_datasets(path, file);
  const BundleRows rows{n, k, s};
  // Every shape first (cheap), then the data.
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (bundle_has(b, spec))
      expect_shape(path, file, spec.path, dataset_shape(spec, rows, dof), shape_rule_text(spec));
  }
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (!bundle_has(b, spec)) continue;
    std::visit(
        [&](auto* data) {
          using T = typename std::decay_t<decltype(*data)>::value_type;
          *data = h5::read_dataset<T>(path, file, spec.path, dataset_shape(spec, rows, dof));
        },
        bundle_array(b, spec.id));
    if (spec.id == BundleDatasetId::KnotOffset)
      check_offsets(path, ds::knot_offset, b.knot_offset, k, ds::knots);
    if (spec.id == BundleDatasetId::SampleOffset)
      check_offsets(path, ds::sample_offset, b.sample_offset, s, ds::sample_q);
  }
  check_bundle_arrays(arrays_of(b), path);
  return b;
}

uint64_t rows_by_dof(const std::string& where, hid_t file, const char* name, uint64_t dof) {
  const std::vector<uint64_t> found = h5::dataset_shape(where, file, name);
  if (found.size() != 2 || found[1] != dof)
    fail(where, std::string(name) + ": shape " + h5::shape_string(found) + ", expected rows x " +
                    str(dof) + " (rows x dof)");
  return found[0];
}

bool has_transfer_datasets(const std::string& where, hid_t file) {
  const bool lazy = h5::exists(file, ds::transfer_lazy);
  const bool max = h5::exists(file, ds::transfer_max_error);
  const bool prob = h5::exists(file, ds::p_lazy_prop_transfer);
  if (!(lazy || max || prob)) return false;
  for (const auto& [there, name] :
       {std::pair{lazy, ds::transfer_lazy}, std::pair{max, ds::transfer_max_error},
        std::pair{prob, ds::p_lazy_prop_transfer}}) {
    if (!there)
      fail(where,
           std::string(name) + ": dataset missing (the other transfer statistics are present)");
  }
  return true;
}

DatasetLocation dataset_location(const std::string& where, hid_t file, const std::string& dataset) {
  h5::Dataset dset = h5::open_dataset(where, file, dataset);
  h5::PropList dcpl(H5Dget_create_plist(dset));
  if (!dcpl.valid()) fail(where, dataset + ": cannot read its storage layout");
  const H5D_layout_t layout = H5Pget_layout(dcpl);
  if (layout < 0) fail(where, dataset + ": cannot read its storage layout");
  DatasetLocation loc;
  loc.contiguous = layout == H5D_CONTIGUOUS;
  loc.bytes = H5Dget_storage_size(dset);
  if (loc.contiguous) {
    const haddr_t offset = H5Dget_offset(dset);
    if (offset == HADDR_UNDEF) {
      loc.bytes = 0;  // no storage allocated (zero-sized, or never written)
    } else {
      loc.file_offset = offset;
    }
  }
  return loc;
}

DatasetLocation dataset_location(const std::string& path, const std::string& dataset) {
  h5::File file = h5::open_file(path);
  return dataset_location(path, file, dataset);
}

namespace {

// FNV-1a 64 of a dataset's bytes as they lie in the file.
std::string file_bytes_checksum(const std::string& path, const DatasetLocation& loc) {
  Fnv1a64 hash;
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(loc.file_offset));
  std::vector<char> buffer(static_cast<size_t>(std::min<uint64_t>(loc.bytes, 1 << 20)));
  for (uint64_t left = loc.bytes; left > 0;) {
    const size_t chunk = static_cast<size_t>(std::min<uint64_t>(left, buffer.size()));
    if (!in.read(buffer.data(), static_cast<std::streamsize>(chunk)))
      fail(path, "cannot read the file (truncated?)");
    hash.update(buffer.data(), chunk);
    left -= chunk;
  }
  return std::string(kChecksumPrefix) + hash.hex();
}

}  // namespace

std::vector<DatasetVerification> verify_bundle_checksums(const std::string& path) {
  h5::File file = h5::open_file(path);
  std::vector<DatasetVerification> out;
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    const char* name = spec.path;
    if (!h5::exists(file, name)) continue;  // optional ones; a missing required one: read_bundle
    DatasetVerification v;
    v.dataset = name;
    h5::Dataset dset = h5::open_dataset(path, file, name);
    if (!h5::has_attribute(dset, kChecksumAttribute)) {
      v.status = DatasetVerification::Status::NoChecksum;
    } else {
      v.stored = h5::read_attr_string(path, dset, kChecksumAttribute);
      const DatasetLocation loc = dataset_location(path, file, name);
      if (!loc.contiguous) fail(path, std::string(name) + ": not contiguous, cannot verify");
      v.computed = file_bytes_checksum(path, loc);
      v.status = v.stored == v.computed ? DatasetVerification::Status::Verified
                                        : DatasetVerification::Status::Mismatch;
    }
    out.push_back(v);
  }
  return out;
}

}  // namespace lazyboe
