// The edge bundle's HDF5 file (layout: schemas/bundle.md, schema version 1).
//
// Writing always rewrites the whole file under a temporary name in the same directory and
// renames it into place, so the file at `path` is either the old complete file or the new
// complete one, whatever happens to the process. Reading validates the layout and reports any
// problem as one Error line naming the file and the dataset or attribute at fault.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"

namespace lazyboe {

constexpr int kBundleSchemaVersion = 1;  // the version this code writes and reads

// Dataset paths inside the file.
namespace bundle_dataset {
constexpr const char* q0 = "/edges/q0";                              // N x dof f64
constexpr const char* qf = "/edges/qf";                              // N x dof f64
constexpr const char* duration = "/edges/duration";                  // N f64
constexpr const char* command_duration = "/edges/command_duration";  // N f64
constexpr const char* attempt = "/edges/attempt";                    // N u64
constexpr const char* knot_offset = "/edges/knot_offset";            // N+1 u64
constexpr const char* sample_offset = "/edges/sample_offset";        // N+1 u64
constexpr const char* knots = "/controls/knots";                     // K x dof f64
constexpr const char* sample_q = "/trajectory/q";                    // S x dof f32
constexpr const char* sample_dq = "/trajectory/dq";                  // S x dof f32
constexpr const char* perturbation = "/perturbation";                // group, attributes
constexpr const char* pert_done = "/perturbation/done";              // N u64
constexpr const char* pert_valid = "/perturbation/valid";            // N u64
constexpr const char* pert_lazy = "/perturbation/lazy";              // N u64
constexpr const char* pert_collision = "/perturbation/collision";    // N u64
constexpr const char* pert_max_error = "/perturbation/max_error";    // N f64
constexpr const char* p_lazy_prop = "/perturbation/p_lazy_prop";     // N f64
constexpr const char* p_collision = "/perturbation/p_collision";     // N f64
// Optional within /perturbation (absent in analyses written before them): all three or none.
constexpr const char* transfer_lazy = "/perturbation/transfer_lazy";                // N u64
constexpr const char* transfer_max_error = "/perturbation/transfer_max_error";      // N f64
constexpr const char* p_lazy_prop_transfer = "/perturbation/p_lazy_prop_transfer";  // N f64
}  // namespace bundle_dataset

// Checks the in-memory bundle is self-consistent: schema_version 1, dof >= 1, region bounds of
// size dof, every array sized for N = duration.size() edges and dof columns, offsets of size
// N + 1 starting at 0, non-decreasing, ending at the rows of knots / samples. Throws
// Error("<where>: bundle.<field>: ...").
void check_bundle(const Bundle& bundle, const std::string& where);

// Writes the whole bundle (check_bundle first) to "<path>.tmp.<pid>.<n>", flushes and fsyncs it,
// then renames it over `path`. On failure the temporary file is removed, `path` is untouched,
// and Error is thrown. (A process killed mid-write may leave its temporary file behind.)
void write_bundle(const std::string& path, const Bundle& bundle);

// Reads and validates a whole bundle.
Bundle read_bundle(const std::string& path);

// Reads only the root attributes (cheap; no dataset is read). When `edges` is given it receives
// the number of edges N (the root attribute `edges`).
BundleHeader read_bundle_header(const std::string& path, uint64_t* edges = nullptr);

// Other tools than lazyboe-build accept only a finished bundle: this throws, saying how to
// finish it, for an incomplete one.
void require_complete(const BundleHeader& header, const std::string& path);

// Where a dataset's raw bytes are, for memory-mapping. When contiguous and bytes > 0, the
// little-endian elements lie row-major at [file_offset, file_offset + bytes) of the file.
// A zero-sized dataset has no storage: bytes = 0, file_offset = 0.
struct DatasetLocation {
  bool contiguous = false;
  uint64_t file_offset = 0;
  uint64_t bytes = 0;
};
DatasetLocation dataset_location(const std::string& path, const std::string& dataset);

// Every dataset carries the attribute `checksum` = "fnv1a64:" + 16 hex digits, the FNV-1a 64 of
// its raw bytes, computed when written. Verification rereads the bytes from the file.
constexpr const char* kChecksumAttribute = "checksum";
constexpr const char* kChecksumPrefix = "fnv1a64:";
struct DatasetVerification {
  enum class Status { Verified, Mismatch, NoChecksum };  // NoChecksum: written before checksums
  std::string dataset;
  Status status = Status::NoChecksum;
  std::string stored, computed;
};
// Every dataset of the bundle present in the file, in the order of schemas/bundle.md.
std::vector<DatasetVerification> verify_bundle_checksums(const std::string& path);
// (The same on an already open HDF5 file is in hdf5_handle.h, which is not installed.)

}  // namespace lazyboe
