#include "lazyboe/bundle/bundle_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "lazyboe/bundle/bundle_check.h"
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

// Rows of a (rows x dof) dataset whose row count is free.
uint64_t rows_of(const std::string& where, hid_t file, const char* name, uint64_t dof) {
  const std::vector<uint64_t> found = h5::dataset_shape(where, file, name);
  if (found.size() != 2 || found[1] != dof)
    fail(where, std::string(name) + ": shape " + h5::shape_string(found) + ", expected rows x " +
                    str(dof) + " (rows x dof)");
  return found[0];
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

void write_edges(const std::string& tmp, hid_t file, const Bundle& b) {
  const uint64_t n = b.size(), dof = static_cast<uint64_t>(b.dof());
  const uint64_t k = b.knots.size() / dof, s = b.sample_q.size() / dof;
  h5::create_group(tmp, file, "/edges");
  h5::create_group(tmp, file, "/controls");
  h5::create_group(tmp, file, "/trajectory");
  write_checked(tmp, file, ds::q0, b.q0, {n, dof});
  write_checked(tmp, file, ds::qf, b.qf, {n, dof});
  write_checked(tmp, file, ds::duration, b.duration, {n});
  write_checked(tmp, file, ds::command_duration, b.command_duration, {n});
  write_checked(tmp, file, ds::attempt, b.attempt, {n});
  write_checked(tmp, file, ds::knot_offset, b.knot_offset, {n + 1});
  write_checked(tmp, file, ds::sample_offset, b.sample_offset, {n + 1});
  write_checked(tmp, file, ds::knots, b.knots, {k, dof});
  write_checked(tmp, file, ds::sample_q, b.sample_q, {s, dof});
  write_checked(tmp, file, ds::sample_dq, b.sample_dq, {s, dof});
}

void write_perturbation(const std::string& tmp, hid_t file, const Perturbation& p, uint64_t n) {
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
  write_checked(tmp, file, ds::pert_done, p.done, {n});
  write_checked(tmp, file, ds::pert_valid, p.valid, {n});
  write_checked(tmp, file, ds::pert_lazy, p.lazy, {n});
  write_checked(tmp, file, ds::pert_collision, p.collision, {n});
  write_checked(tmp, file, ds::pert_max_error, p.max_error, {n});
  write_checked(tmp, file, ds::p_lazy_prop, p.p_lazy_prop, {n});
  write_checked(tmp, file, ds::p_collision, p.p_collision, {n});
  if (p.has_transfer) {
    write_checked(tmp, file, ds::transfer_lazy, p.transfer_lazy, {n});
    write_checked(tmp, file, ds::transfer_max_error, p.transfer_max_error, {n});
    write_checked(tmp, file, ds::p_lazy_prop_transfer, p.p_lazy_prop_transfer, {n});
  }
}

// The dataset bytes of the file, to size its memory image at once.
uint64_t payload_bytes(const Bundle& b) {
  const Perturbation& p = b.perturbation;
  return 8 * (b.q0.size() + b.qf.size() + b.duration.size() + b.command_duration.size() +
              b.attempt.size() + b.knot_offset.size() + b.sample_offset.size() + b.knots.size()) +
         4 * (b.sample_q.size() + b.sample_dq.size()) +
         (p.present ? 8 * b.size() * (p.has_transfer ? 10 : 7) : 0);
}

BundleArrays arrays_of(const Bundle& b, uint64_t knot_rows, uint64_t sample_rows) {
  BundleArrays a;
  a.edges = b.size();
  a.dof = static_cast<uint64_t>(b.dof());
  a.knot_rows = knot_rows;
  a.sample_rows = sample_rows;
  a.q0 = b.q0.data();
  a.qf = b.qf.data();
  a.duration = b.duration.data();
  a.command_duration = b.command_duration.data();
  a.knot_offset = b.knot_offset.data();
  a.sample_offset = b.sample_offset.data();
  a.knots = b.knots.data();
  a.sample_q = b.sample_q.data();
  a.sample_dq = b.sample_dq.data();
  const Perturbation& p = b.perturbation;
  if (!p.present) return a;
  a.perturbations = p.perturbations;
  a.done = p.done.data();
  a.valid = p.valid.data();
  a.lazy = p.lazy.data();
  a.collision = p.collision.data();
  a.max_error = p.max_error.data();
  a.p_lazy_prop = p.p_lazy_prop.data();
  a.p_collision = p.p_collision.data();
  if (p.has_transfer) {
    a.transfer_lazy = p.transfer_lazy.data();
    a.transfer_max_error = p.transfer_max_error.data();
    a.p_lazy_prop_transfer = p.p_lazy_prop_transfer.data();
  }
  return a;
}

}  // namespace

void check_bundle(const Bundle& b, const std::string& where) {
  const BundleHeader& h = b.header;
  if (h.schema_version != kBundleSchemaVersion)
    fail(where, "bundle.header.schema_version: " + std::to_string(h.schema_version) +
                    ", this lazyboe writes schema version " + std::to_string(kBundleSchemaVersion));
  check_header(where, "bundle.header.", h);
  const size_t n = b.duration.size();
  const size_t dof = static_cast<size_t>(h.dof);
  const std::string nd = "edges x dof = " + str(n) + " x " + str(dof);
  check_size(where, "q0", b.q0.size(), n * dof, nd);
  check_size(where, "qf", b.qf.size(), n * dof, nd);
  check_size(where, "command_duration", b.command_duration.size(), n, "edges (duration.size())");
  check_size(where, "attempt", b.attempt.size(), n, "edges (duration.size())");
  check_size(where, "knot_offset", b.knot_offset.size(), n + 1, "edges + 1");
  check_size(where, "sample_offset", b.sample_offset.size(), n + 1, "edges + 1");
  if (b.knots.size() % dof != 0)
    fail(where,
         "bundle.knots: " + str(b.knots.size()) + " values, not a multiple of dof = " + str(dof));
  if (b.sample_q.size() % dof != 0)
    fail(where, "bundle.sample_q: " + str(b.sample_q.size()) +
                    " values, not a multiple of dof = " + str(dof));
  check_size(where, "sample_dq", b.sample_dq.size(), b.sample_q.size(), "sample_q.size()");
  if (b.perturbation.present) {
    const Perturbation& p = b.perturbation;
    const std::string e = "edges (duration.size())";
    check_size(where, "perturbation.done", p.done.size(), n, e);
    check_size(where, "perturbation.valid", p.valid.size(), n, e);
    check_size(where, "perturbation.lazy", p.lazy.size(), n, e);
    check_size(where, "perturbation.collision", p.collision.size(), n, e);
    check_size(where, "perturbation.max_error", p.max_error.size(), n, e);
    check_size(where, "perturbation.p_lazy_prop", p.p_lazy_prop.size(), n, e);
    check_size(where, "perturbation.p_collision", p.p_collision.size(), n, e);
    if (p.has_transfer) {
      check_size(where, "perturbation.transfer_lazy", p.transfer_lazy.size(), n, e);
      check_size(where, "perturbation.transfer_max_error", p.transfer_max_error.size(), n, e);
      check_size(where, "perturbation.p_lazy_prop_transfer", p.p_lazy_prop_transfer.size(), n, e);
    }
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
  write_edges(path, file, b);
  if (b.perturbation.present) write_perturbation(path, file, b.perturbation, b.size());
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

Bundle read_bundle(const std::string& path) {
  h5::File file = h5::open_file(path);
  Bundle b;
  uint64_t n = 0;
  b.header = read_header(path, file, &n);
  const uint64_t dof = static_cast<uint64_t>(b.header.dof);

  // Every shape first (cheap), then the data.
  expect_shape(path, file, ds::q0, {n, dof}, "edges x dof");
  expect_shape(path, file, ds::qf, {n, dof}, "edges x dof");
  expect_shape(path, file, ds::duration, {n}, "edges");
  expect_shape(path, file, ds::command_duration, {n}, "edges");
  expect_shape(path, file, ds::attempt, {n}, "edges");
  expect_shape(path, file, ds::knot_offset, {n + 1}, "edges + 1");
  expect_shape(path, file, ds::sample_offset, {n + 1}, "edges + 1");
  const uint64_t k = rows_of(path, file, ds::knots, dof);
  const uint64_t s = rows_of(path, file, ds::sample_q, dof);
  expect_shape(path, file, ds::sample_dq, {s, dof}, "rows of /trajectory/q x dof");

  b.knot_offset = h5::read_dataset<uint64_t>(path, file, ds::knot_offset, {n + 1});
  check_offsets(path, ds::knot_offset, b.knot_offset, k, ds::knots);
  b.sample_offset = h5::read_dataset<uint64_t>(path, file, ds::sample_offset, {n + 1});
  check_offsets(path, ds::sample_offset, b.sample_offset, s, ds::sample_q);

  b.q0 = h5::read_dataset<double>(path, file, ds::q0, {n, dof});
  b.qf = h5::read_dataset<double>(path, file, ds::qf, {n, dof});
  b.duration = h5::read_dataset<double>(path, file, ds::duration, {n});
  b.command_duration = h5::read_dataset<double>(path, file, ds::command_duration, {n});
  b.attempt = h5::read_dataset<uint64_t>(path, file, ds::attempt, {n});
  b.knots = h5::read_dataset<double>(path, file, ds::knots, {k, dof});
  b.sample_q = h5::read_dataset<float>(path, file, ds::sample_q, {s, dof});
  b.sample_dq = h5::read_dataset<float>(path, file, ds::sample_dq, {s, dof});
  if (h5::exists(file, ds::perturbation)) {
    Perturbation& p = b.perturbation;
    h5::Group g(H5Gopen2(file, ds::perturbation, H5P_DEFAULT));
    if (!g.valid()) fail(path, std::string(ds::perturbation) + ": cannot open group");
    const std::string where = path;
    p.present = true;
    p.complete = h5::read_attr_bool(where, g, "complete");
    p.theta = h5::read_attr_f64(where, g, "theta");
    p.perturbations = h5::read_attr_u64(where, g, "perturbations");
    p.seed = h5::read_attr_u64(where, g, "seed");
    p.wall_seconds = h5::read_attr_f64(where, g, "wall_seconds");
    p.simulated_seconds = h5::read_attr_f64(where, g, "simulated_seconds");
    p.done = h5::read_dataset<uint64_t>(path, file, ds::pert_done, {n});
    p.valid = h5::read_dataset<uint64_t>(path, file, ds::pert_valid, {n});
    p.lazy = h5::read_dataset<uint64_t>(path, file, ds::pert_lazy, {n});
    p.collision = h5::read_dataset<uint64_t>(path, file, ds::pert_collision, {n});
    p.max_error = h5::read_dataset<double>(path, file, ds::pert_max_error, {n});
    p.p_lazy_prop = h5::read_dataset<double>(path, file, ds::p_lazy_prop, {n});
    p.p_collision = h5::read_dataset<double>(path, file, ds::p_collision, {n});
    // The transfer statistics: absent from analyses written before them.
    if (has_transfer_datasets(path, file)) {
      p.has_transfer = true;
      p.transfer_lazy = h5::read_dataset<uint64_t>(path, file, ds::transfer_lazy, {n});
      p.transfer_max_error = h5::read_dataset<double>(path, file, ds::transfer_max_error, {n});
      p.p_lazy_prop_transfer = h5::read_dataset<double>(path, file, ds::p_lazy_prop_transfer, {n});
    }
  }
  check_bundle_arrays(arrays_of(b, k, s), path);
  return b;
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
  for (const char* name : {ds::q0,
                           ds::qf,
                           ds::duration,
                           ds::command_duration,
                           ds::attempt,
                           ds::knot_offset,
                           ds::sample_offset,
                           ds::knots,
                           ds::sample_q,
                           ds::sample_dq,
                           ds::pert_done,
                           ds::pert_valid,
                           ds::pert_lazy,
                           ds::pert_collision,
                           ds::pert_max_error,
                           ds::p_lazy_prop,
                           ds::p_collision,
                           ds::transfer_lazy,
                           ds::transfer_max_error,
                           ds::p_lazy_prop_transfer}) {
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
