// Thin layer over the HDF5 C API: RAII handles that close their hid_t, and helpers that write
// and read contiguous datasets and attributes with one-line lazyboe::Error messages.
//
// Every helper takes `where` (the file path, put first in the message) and the object or
// attribute name, so a failure reads "bundle.h5: /edges/q0: shape 50 x 6, expected 50 x 7".
// HDF5's own error-stack printing is switched off (quiet()) by these helpers: failures are
// reported by our exceptions, not by HDF5 stack dumps.
//
// Types in the file are fixed little-endian (IEEE F64LE, F32LE, STD U64LE/I64LE/U8LE), so the
// raw bytes of a contiguous dataset can be memory-mapped on the (little-endian) machines we run
// on; in memory the native types are used.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lazyboe::h5 {

// Turns off HDF5's automatic error printing for the calling thread's default error stack
// (idempotent, cheap; every helper below calls it).
void quiet();

// A move-only owner of one hid_t, closed with Close on destruction.
template <herr_t (*Close)(hid_t)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : id_(id) {}
  ~Handle() { close(); }
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      close();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }  // NOLINT: pass straight to the C API
  bool valid() const { return id_ >= 0; }
  // Closes now; returns the close status (negative on failure, e.g. a failed final flush).
  herr_t close() {
    const herr_t status = valid() ? Close(id_) : 0;
    id_ = H5I_INVALID_HID;
    return status;
  }
  hid_t release() { return std::exchange(id_, H5I_INVALID_HID); }

 private:
  hid_t id_ = H5I_INVALID_HID;
};

using File = Handle<H5Fclose>;
using Group = Handle<H5Gclose>;
using Dataset = Handle<H5Dclose>;
using Dataspace = Handle<H5Sclose>;
using Datatype = Handle<H5Tclose>;
using Attribute = Handle<H5Aclose>;
using PropList = Handle<H5Pclose>;

// ---- files and groups -------------------------------------------------------------------

// Creates (truncating) a file with the default (1.8-compatible) format. Objects created
// through these helpers do not record modification times, so equal content gives equal bytes.
File create_file(const std::string& path);
// The same file held in memory only (HDF5's core driver, no backing store): nothing touches the
// disk, so a full disk cannot fail inside HDF5 (where a failed write leaves the library in a
// state that crashes at exit). `expected_bytes` sizes the first allocation. `name` only labels
// the file.
File create_memory_file(const std::string& name, uint64_t expected_bytes);
// The bytes of a memory file made by create_memory_file, as a complete HDF5 file (as if it
// were closed: HDF5 clears the open-for-writing flag in the copy).
std::vector<unsigned char> memory_file_image(const std::string& where, File& file);
// Opens read-only; "no such file", "not an HDF5 file" and the like name the path.
File open_file(const std::string& path);
// Opens read-write (tests and repair tools; the bundle writer never modifies in place).
File open_file_rw(const std::string& path);
// Closes a file, throwing if the final flush fails.
void close_file(const std::string& where, File& file);

Group create_group(const std::string& where, hid_t loc, const std::string& name);
// True when every component of the path (absolute or relative to loc) exists.
bool exists(hid_t loc, const std::string& path);

// ---- datasets ---------------------------------------------------------------------------

// Element types the helpers handle: double, float, uint64_t.
template <class T>
struct TypeOf;
template <>
struct TypeOf<double> {
  static hid_t memory() { return H5T_NATIVE_DOUBLE; }
  static hid_t file() { return H5T_IEEE_F64LE; }
  static constexpr const char* name = "float64";
};
template <>
struct TypeOf<float> {
  static hid_t memory() { return H5T_NATIVE_FLOAT; }
  static hid_t file() { return H5T_IEEE_F32LE; }
  static constexpr const char* name = "float32";
};
template <>
struct TypeOf<uint64_t> {
  static hid_t memory() { return H5T_NATIVE_UINT64; }
  static hid_t file() { return H5T_STD_U64LE; }
  static constexpr const char* name = "uint64";
};

// Writes a contiguous, uncompressed dataset of rank dims.size() (1 or 2). The product of dims
// must equal data.size(); zero-sized dimensions are fine.
template <class T>
void write_dataset(const std::string& where, hid_t loc, const std::string& name,
                   const std::vector<T>& data, const std::vector<uint64_t>& dims);

Dataset open_dataset(const std::string& where, hid_t loc, const std::string& name);  // "missing"
std::vector<uint64_t> dataset_shape(const std::string& where, hid_t loc, const std::string& name);
std::string shape_string(const std::vector<uint64_t>& dims);  // "50 x 7"

// Reads a whole dataset of element type T (the file's type must be of the same kind and
// size: float64 for double, float32 for float, unsigned 64-bit integer for uint64_t) whose
// shape must be `dims`.
template <class T>
std::vector<T> read_dataset(const std::string& where, hid_t loc, const std::string& name,
                            const std::vector<uint64_t>& dims);

// ---- attributes (on any object: file, group, dataset) -----------------------------------

bool has_attribute(hid_t obj, const std::string& name);

void write_attr_i64(const std::string& where, hid_t obj, const std::string& name, int64_t value);
void write_attr_u64(const std::string& where, hid_t obj, const std::string& name, uint64_t value);
void write_attr_f64(const std::string& where, hid_t obj, const std::string& name, double value);
void write_attr_bool(const std::string& where, hid_t obj, const std::string& name,
                     bool value);  // uint8 0/1
// Fixed-length UTF-8 strings, NUL-padded (no embedded NUL): no global heap in the file.
void write_attr_string(const std::string& where, hid_t obj, const std::string& name,
                       const std::string& value);
// 1-D attributes; an empty vector gives a zero-length 1-D attribute.
void write_attr_f64s(const std::string& where, hid_t obj, const std::string& name,
                     const std::vector<double>& values);
void write_attr_u64s(const std::string& where, hid_t obj, const std::string& name,
                     const std::vector<uint64_t>& values);
void write_attr_strings(const std::string& where, hid_t obj, const std::string& name,
                        const std::vector<std::string>& values);

// Readers: the attribute must exist ("attribute X missing"), be scalar (or 1-D for the vector
// forms) and of the right kind (integer, float, string); integers are range-checked.
int64_t read_attr_i64(const std::string& where, hid_t obj, const std::string& name);
uint64_t read_attr_u64(const std::string& where, hid_t obj, const std::string& name);
double read_attr_f64(const std::string& where, hid_t obj, const std::string& name);
bool read_attr_bool(const std::string& where, hid_t obj, const std::string& name);  // 0 or 1
std::string read_attr_string(const std::string& where, hid_t obj, const std::string& name);
std::vector<double> read_attr_f64s(const std::string& where, hid_t obj, const std::string& name);
std::vector<uint64_t> read_attr_u64s(const std::string& where, hid_t obj, const std::string& name);
std::vector<std::string> read_attr_strings(const std::string& where, hid_t obj,
                                           const std::string& name);

}  // namespace lazyboe::h5

namespace lazyboe {

// bundle_file.h's dataset_location on an already open file; `where` names it in errors. Here,
// not there, so that the installed bundle_file.h does not include <hdf5.h>.
struct DatasetLocation;
DatasetLocation dataset_location(const std::string& where, hid_t file, const std::string& dataset);

// Whether an open bundle file holds the perturbation's transfer statistics: all three datasets
// (true) or none (false, an analysis written before them); one of them alone is an Error naming
// the missing one. read_bundle and BundleView::open both ask this.
bool has_transfer_datasets(const std::string& where, hid_t file);

// The row count of an open bundle file's (rows x dof) dataset, whose rows are free (the knots,
// the trajectory samples); any other shape is an Error naming the dataset and its shape.
uint64_t rows_by_dof(const std::string& where, hid_t file, const char* name, uint64_t dof);

}  // namespace lazyboe
