#include "lazyboe/bundle/hdf5_handle.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <type_traits>

#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"

namespace lazyboe::h5 {
namespace {

// The innermost message on HDF5's error stack (the most specific one), for appending to ours.
herr_t innermost(unsigned n, const H5E_error2_t* err, void* data) {
  if (n == 0 && err->desc) *static_cast<std::string*>(data) = err->desc;
  return 0;
}

std::string hdf5_reason() {
  std::string desc;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, &desc);
  // Read, so cleared: HDF5 does not free the entries' strings left on the stack at exit (LSan).
  H5Eclear2(H5E_DEFAULT);
  for (char& c : desc)
    if (c == '\n' || c == '\r') c = ' ';
  return desc.empty() ? "" : " (HDF5: " + desc + ")";
}

[[noreturn]] void fail_hdf5(const std::string& where, const std::string& what) {
  fail(where, what + hdf5_reason());
}

std::string attr_where(const std::string& name) { return "attribute " + name; }

PropList create_plist(hid_t cls) {
  PropList p(H5Pcreate(cls));
  if (!p.valid()) fail_hdf5("", "cannot create an HDF5 property list");
  return p;
}

Datatype vlen_string_type() {
  Datatype t(H5Tcopy(H5T_C_S1));
  if (!t.valid() || H5Tset_size(t, H5T_VARIABLE) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0)
    fail_hdf5("", "cannot create the HDF5 string type");
  return t;
}

// Fixed-length strings of `size` bytes, padded with NULs: stored in the object header itself.
// Variable-length strings live in a global heap, which HDF5 1.10 reads without bounds checks.
Datatype fixed_string_type(size_t size) {
  Datatype t(H5Tcopy(H5T_C_S1));
  if (!t.valid() || H5Tset_size(t, std::max<size_t>(size, 1)) < 0 ||
      H5Tset_strpad(t, H5T_STR_NULLPAD) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0)
    fail_hdf5("", "cannot create the HDF5 string type");
  return t;
}

uint64_t little_endian(const unsigned char* p, int bytes) {
  uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// One global heap collection (HDF5 file format, "Global Heap"): "GCOL", version 1, 3 reserved
// bytes, its size (8 bytes), then objects: index (2), reference count (2), reserved (4), size
// (8), data padded to 8 bytes; index 0 is the free space, which counts its own header. False
// when an object runs past the collection (HDF5 1.10 would copy past it) or the free space is
// shorter than its header (HDF5 1.10 would loop forever).
bool global_heap_fits(const unsigned char* file, uint64_t file_size, uint64_t at) {
  const uint64_t size = little_endian(file + at + 8, 8);
  if (size > file_size - at) return true;  // HDF5 cannot read it: a clean error, not ours
  if (size < 16) return false;
  const uint64_t end = at + size;
  for (uint64_t p = at + 16; p + 16 <= end;) {
    const uint64_t index = little_endian(file + p, 2), bytes = little_endian(file + p + 8, 8);
    if (bytes > size) return false;
    const uint64_t need = index == 0 ? bytes : 16 + ((bytes + 7) & ~uint64_t{7});
    if (need < 16 || need > end - p) return false;
    p += need;
  }
  return true;
}

// Variable-length strings (bundles written before fixed-length ones) are read from global heap
// collections, which HDF5 1.10 trusts: a damaged object size is a wild memcpy. So before the
// first such read from a file, every collection in it is checked (once per file version).
void check_global_heaps(const std::string& where, hid_t obj) {
  const ssize_t n = H5Fget_name(obj, nullptr, 0);
  if (n <= 0) return;  // a file in memory (the writer's image), not read from anywhere
  std::string path(static_cast<size_t>(n), '\0');
  H5Fget_name(obj, path.data(), path.size() + 1);
  const int fd = ::open(path.c_str(), O_RDONLY);
  struct stat st;
  if (fd < 0 || ::fstat(fd, &st) != 0) {
    if (fd >= 0) ::close(fd);
    fail(where, "cannot reopen the file to check its string storage: " +
                    std::string(std::strerror(errno)));
  }
  static thread_local std::string checked;  // path, inode, size and time of the last file checked
  const std::string key = path + ":" + std::to_string(st.st_ino) + ":" +
                          std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) +
                          "." + std::to_string(st.st_mtim.tv_nsec);
  if (key == checked || st.st_size < 16) {
    ::close(fd);
    return;
  }
  const uint64_t size = static_cast<uint64_t>(st.st_size);
  void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) fail(where, "cannot map the file to check its string storage");
  const auto* bytes = static_cast<const unsigned char*>(map);
  bool fits = true;
  for (uint64_t at = 0; fits && at + 16 <= size; ++at) {
    const void* hit = std::memchr(bytes + at, 'G', size - 16 - at + 1);
    if (!hit) break;
    at = static_cast<const unsigned char*>(hit) - bytes;
    if (std::memcmp(bytes + at, "GCOL\1", 5) == 0) fits = global_heap_fits(bytes, size, at);
  }
  ::munmap(map, size);
  if (!fits) fail(where, "damaged: a global heap (its variable-length strings) runs past its end");
  checked = key;
}

std::string type_string(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  const size_t bits = H5Tget_size(type) * 8;
  switch (cls) {
    case H5T_FLOAT:
      return "float" + std::to_string(bits);
    case H5T_INTEGER:
      return (H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
    case H5T_STRING:
      return "string";
    case H5T_COMPOUND:
      return "compound";
    case H5T_ARRAY:
      return "array";
    case H5T_VLEN:
      return "variable-length sequence";
    case H5T_ENUM:
      return "enum";
    default:
      return "unsupported type";
  }
}

template <class T>
bool type_matches(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  if (H5Tget_size(type) != sizeof(T)) return false;
  if constexpr (std::is_floating_point_v<T>) {
    return cls == H5T_FLOAT;
  } else {
    return cls == H5T_INTEGER && H5Tget_sign(type) == H5T_SGN_NONE;
  }
}

void check_no_nul(const std::string& where, const std::string& name, const std::string& s) {
  if (s.find('\0') != std::string::npos)
    fail(where, attr_where(name) + ": strings may not contain a NUL character");
}

// ---- attribute writing ----

void write_attr_raw(const std::string& where, hid_t obj, const std::string& name, hid_t file_type,
                    hid_t mem_type, const std::vector<hsize_t>& dims, const void* data) {
  if (has_attribute(obj, name) && H5Adelete(obj, name.c_str()) < 0)
    fail_hdf5(where, attr_where(name) + ": cannot replace");
  Dataspace space(dims.empty()
                      ? H5Screate(H5S_SCALAR)
                      : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  if (!space.valid()) fail_hdf5(where, attr_where(name) + ": cannot create its dataspace");
  Attribute attr(H5Acreate2(obj, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT));
  if (!attr.valid()) fail_hdf5(where, attr_where(name) + ": cannot create");
  const bool empty = !dims.empty() && dims[0] == 0;
  if (!empty && H5Awrite(attr, mem_type, data) < 0)
    fail_hdf5(where, attr_where(name) + ": cannot write");
  if (attr.close() < 0) fail_hdf5(where, attr_where(name) + ": cannot close");
}

// ---- attribute reading ----

struct OpenAttr {
  Attribute attr;
  Datatype type;
  size_t count = 0;  // number of elements
  bool scalar = false;
};

// Opens an attribute, checking it exists and has a scalar (one element) or 1-D shape.
OpenAttr open_attr(const std::string& where, hid_t obj, const std::string& name, bool want_vector) {
  if (!has_attribute(obj, name)) fail(where, attr_where(name) + " missing");
  OpenAttr a;
  a.attr = Attribute(H5Aopen(obj, name.c_str(), H5P_DEFAULT));
  if (!a.attr.valid()) fail_hdf5(where, attr_where(name) + ": cannot open");
  a.type = Datatype(H5Aget_type(a.attr));
  Dataspace space(H5Aget_space(a.attr));
  if (!a.type.valid() || !space.valid()) fail_hdf5(where, attr_where(name) + ": cannot read");
  const H5S_class_t cls = H5Sget_simple_extent_type(space);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (cls == H5S_NULL) {
    a.count = 0;
  } else if (cls == H5S_SCALAR) {
    a.count = 1;
    a.scalar = true;
  } else if (cls == H5S_SIMPLE && rank == 1) {
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space, &n, nullptr);
    a.count = n;
  } else {
    fail(where, attr_where(name) + ": expected " +
                    (want_vector ? "a 1-D array" : "a single value") + ", found rank " +
                    std::to_string(rank));
  }
  if (want_vector && a.scalar)
    fail(where, attr_where(name) + ": expected a 1-D array, found a single value");
  if (!want_vector && a.count != 1)
    fail(where, attr_where(name) + ": expected a single value, found " + std::to_string(a.count) +
                    " values");
  return a;
}

void require_class(const std::string& where, const std::string& name, const OpenAttr& a,
                   H5T_class_t cls, const char* kind) {
  if (H5Tget_class(a.type) != cls)
    fail(where, attr_where(name) + ": expected " + kind + ", found " + type_string(a.type));
}

void read_attr_raw(const std::string& where, const std::string& name, const OpenAttr& a,
                   hid_t mem_type, void* data) {
  if (a.count > 0 && H5Aread(a.attr, mem_type, data) < 0)
    fail_hdf5(where, attr_where(name) + ": cannot read");
}

// Integers of any size and sign, returned through int64 or uint64 depending on the sign.
struct IntValues {
  bool is_signed = false;
  std::vector<int64_t> s;
  std::vector<uint64_t> u;
};

IntValues read_ints(const std::string& where, hid_t obj, const std::string& name,
                    bool want_vector) {
  OpenAttr a = open_attr(where, obj, name, want_vector);
  require_class(where, name, a, H5T_INTEGER, "an integer");
  IntValues v;
  v.is_signed = H5Tget_sign(a.type) != H5T_SGN_NONE;
  if (v.is_signed) {
    v.s.resize(a.count);
    read_attr_raw(where, name, a, H5T_NATIVE_INT64, v.s.data());
  } else {
    v.u.resize(a.count);
    read_attr_raw(where, name, a, H5T_NATIVE_UINT64, v.u.data());
  }
  return v;
}

std::vector<std::string> read_strings(const std::string& where, hid_t obj, const std::string& name,
                                      bool want_vector) {
  OpenAttr a = open_attr(where, obj, name, want_vector);
  require_class(where, name, a, H5T_STRING, "a string");
  std::vector<std::string> out(a.count);
  if (a.count == 0) return out;
  const htri_t variable = H5Tis_variable_str(a.type);
  if (variable < 0) fail_hdf5(where, attr_where(name) + ": cannot read its string type");
  if (variable) {
    check_global_heaps(where, obj);
    Datatype mem = vlen_string_type();
    std::vector<char*> ptrs(a.count, nullptr);
    read_attr_raw(where, name, a, mem, ptrs.data());
    for (size_t i = 0; i < a.count; ++i) {
      if (ptrs[i]) out[i] = ptrs[i];
      H5free_memory(ptrs[i]);
    }
  } else {
    const size_t size = H5Tget_size(a.type);
    Datatype mem(H5Tcopy(H5T_C_S1));
    // The file's character set: HDF5 converts neither way between ASCII and UTF-8.
    const H5T_cset_t cset = H5Tget_cset(a.type);
    if (!mem.valid() || cset < 0 || H5Tset_size(mem, size) < 0 ||
        H5Tset_strpad(mem, H5T_STR_NULLPAD) < 0 || H5Tset_cset(mem, cset) < 0)
      fail_hdf5(where, attr_where(name) + ": cannot read its string type");
    std::vector<char> buf(size * a.count);
    read_attr_raw(where, name, a, mem, buf.data());
    const bool space_padded = H5Tget_strpad(a.type) == H5T_STR_SPACEPAD;
    for (size_t i = 0; i < a.count; ++i) {
      std::string s(buf.data() + i * size, size);
      s = s.substr(0, s.find('\0'));
      if (space_padded) s = s.substr(0, s.find_last_not_of(' ') + 1);
      out[i] = s;
    }
  }
  return out;
}

}  // namespace

void quiet() {
  // Thread-local: in a thread-safe HDF5 build (Debian's is) each thread has its own error stack
  // and its own automatic-printing setting.
  thread_local bool done = false;
  if (!done) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    done = true;
  }
}

// ---- files and groups -------------------------------------------------------------------

namespace {
// The HDF5 1.8 file format (superblock 2, object header 2): every piece of metadata carries a
// checksum that HDF5 verifies before decoding it. HDF5 1.10 decodes the older format's
// metadata without bounds checks, so a damaged byte there could crash it (found by fuzzing).
// Every object at an 8-byte boundary, so that datasets stay mappable as arrays of doubles (the
// older format's headers happened to keep them there; version 2 headers are not padded).
herr_t set_checksummed_format(hid_t fapl) {
  if (H5Pset_alignment(fapl, 1, 8) < 0) return -1;
  return H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18);
}
}  // namespace

File create_file(const std::string& path) {
  quiet();
  PropList fcpl = create_plist(H5P_FILE_CREATE);
  PropList fapl = create_plist(H5P_FILE_ACCESS);
  // No modification times in the root group's header: equal content gives equal files.
  // Strong close: closing the file really closes (and flushes) everything in it.
  if (H5Pset_obj_track_times(fcpl, 0) < 0 || H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0 ||
      set_checksummed_format(fapl) < 0)
    fail_hdf5(path, "cannot set up the HDF5 file properties");
  File file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl, fapl));
  if (!file.valid()) fail_hdf5(path, "cannot create the file");
  return file;
}

File create_memory_file(const std::string& name, uint64_t expected_bytes) {
  quiet();
  PropList fcpl = create_plist(H5P_FILE_CREATE);
  PropList fapl = create_plist(H5P_FILE_ACCESS);
  const size_t increment = static_cast<size_t>(std::max<uint64_t>(expected_bytes, 1 << 20));
  if (H5Pset_obj_track_times(fcpl, 0) < 0 || H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0 ||
      set_checksummed_format(fapl) < 0 || H5Pset_fapl_core(fapl, increment, 0) < 0)
    fail_hdf5(name, "cannot set up the HDF5 file properties");
  File file(H5Fcreate(name.c_str(), H5F_ACC_TRUNC, fcpl, fapl));
  if (!file.valid()) fail_hdf5(name, "cannot create the file in memory");
  return file;
}

namespace {
// HDF5 1.10's H5Fget_file_image clears the superblock's "open for writing" flag in the copy but
// leaves the checksum computed with it set, so the image of a version 2 or 3 superblock would
// not open. The superblock: signature (8), version, offset size s, length size, flags, four
// addresses of s bytes, then the lookup3 checksum of all that.
void repair_superblock_checksum(std::vector<unsigned char>& image) {
  static const unsigned char signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
  if (image.size() < 12 || std::memcmp(image.data(), signature, 8) != 0) return;
  if (image[8] != 2 && image[8] != 3) return;
  const size_t covered = 12 + 4 * size_t{image[9]};
  if (image.size() < covered + 4) return;
  const uint32_t sum = lookup3(image.data(), covered, 0);
  for (int i = 0; i < 4; ++i) image[covered + i] = static_cast<unsigned char>(sum >> (8 * i));
}
}  // namespace

std::vector<unsigned char> memory_file_image(const std::string& where, File& file) {
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) fail_hdf5(where, "cannot complete the file in memory");
  const ssize_t size = H5Fget_file_image(file, nullptr, 0);
  if (size < 0) fail_hdf5(where, "cannot read the file size");
  std::vector<unsigned char> image(static_cast<size_t>(size));
  if (H5Fget_file_image(file, image.data(), image.size()) != size)
    fail_hdf5(where, "cannot copy the file image out of memory");
  repair_superblock_checksum(image);
  return image;
}

namespace {
File open_file_mode(const std::string& path, unsigned flags) {
  quiet();
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    fail(path, "cannot open: " + std::string(std::strerror(errno)));
  if (S_ISDIR(st.st_mode)) fail(path, "cannot open: is a directory");
  const int fd = ::open(path.c_str(), (flags & H5F_ACC_RDWR) ? O_RDWR : O_RDONLY);
  if (fd < 0) fail(path, "cannot open: " + std::string(std::strerror(errno)));
  ::close(fd);
  const htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  if (is_hdf5 == 0) fail(path, "not an HDF5 file");
  if (is_hdf5 < 0) fail_hdf5(path, "cannot open as an HDF5 file");
  File file(H5Fopen(path.c_str(), flags, H5P_DEFAULT));
  if (!file.valid()) fail_hdf5(path, "cannot open as an HDF5 file (truncated or damaged?)");
  return file;
}
}  // namespace

File open_file(const std::string& path) { return open_file_mode(path, H5F_ACC_RDONLY); }
File open_file_rw(const std::string& path) { return open_file_mode(path, H5F_ACC_RDWR); }

void close_file(const std::string& where, File& file) {
  if (!file.valid()) return;
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) {
    const std::string reason = hdf5_reason();
    file.close();
    fail(where, "cannot write the file" + reason);
  }
  if (file.close() < 0) fail_hdf5(where, "cannot finish writing the file");
}

Group create_group(const std::string& where, hid_t loc, const std::string& name) {
  quiet();
  PropList gcpl = create_plist(H5P_GROUP_CREATE);
  if (H5Pset_obj_track_times(gcpl, 0) < 0) fail_hdf5(where, name + ": cannot set up the group");
  Group group(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, gcpl, H5P_DEFAULT));
  if (!group.valid()) fail_hdf5(where, name + ": cannot create the group");
  return group;
}

bool exists(hid_t loc, const std::string& path) {
  quiet();
  size_t pos = path.empty() || path[0] != '/' ? 0 : 1;
  while (pos <= path.size()) {
    size_t next = path.find('/', pos);
    if (next == std::string::npos) next = path.size();
    const std::string prefix = path.substr(0, next);
    if (next > pos && H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    pos = next + 1;
  }
  return true;
}

// ---- datasets ---------------------------------------------------------------------------

std::string shape_string(const std::vector<uint64_t>& dims) {
  if (dims.empty()) return "scalar";
  std::string s;
  for (size_t i = 0; i < dims.size(); ++i) s += (i ? " x " : "") + std::to_string(dims[i]);
  return s;
}

template <class T>
void write_dataset(const std::string& where, hid_t loc, const std::string& name,
                   const std::vector<T>& data, const std::vector<uint64_t>& dims) {
  quiet();
  if (dims.empty() || dims.size() > 2)
    fail(where, name + ": only 1-D and 2-D datasets are written");
  uint64_t count = 1;
  for (uint64_t d : dims) count *= d;
  if (count != data.size())
    fail(where, name + ": " + std::to_string(data.size()) + " values do not fill shape " +
                    shape_string(dims));
  const std::vector<hsize_t> hdims(dims.begin(), dims.end());
  Dataspace space(H5Screate_simple(static_cast<int>(hdims.size()), hdims.data(), nullptr));
  if (!space.valid()) fail_hdf5(where, name + ": cannot create its dataspace");
  PropList dcpl = create_plist(H5P_DATASET_CREATE);
  if (H5Pset_layout(dcpl, H5D_CONTIGUOUS) < 0 || H5Pset_obj_track_times(dcpl, 0) < 0 ||
      H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER) < 0)
    fail_hdf5(where, name + ": cannot set up the dataset");
  Dataset dset(
      H5Dcreate2(loc, name.c_str(), TypeOf<T>::file(), space, H5P_DEFAULT, dcpl, H5P_DEFAULT));
  if (!dset.valid()) fail_hdf5(where, name + ": cannot create the dataset");
  if (count > 0 &&
      H5Dwrite(dset, TypeOf<T>::memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
    fail_hdf5(where, name + ": cannot write");
  if (dset.close() < 0) fail_hdf5(where, name + ": cannot close");
}

Dataset open_dataset(const std::string& where, hid_t loc, const std::string& name) {
  if (!exists(loc, name)) fail(where, name + ": dataset missing");
  H5O_info_t info;
  if (H5Oget_info_by_name(loc, name.c_str(), &info, H5P_DEFAULT) < 0)
    fail_hdf5(where, name + ": cannot open");
  if (info.type != H5O_TYPE_DATASET) fail(where, name + ": expected a dataset, found a group");
  Dataset dset(H5Dopen2(loc, name.c_str(), H5P_DEFAULT));
  if (!dset.valid()) fail_hdf5(where, name + ": cannot open the dataset");
  return dset;
}

std::vector<uint64_t> dataset_shape(const std::string& where, hid_t loc, const std::string& name) {
  Dataset dset = open_dataset(where, loc, name);
  Dataspace space(H5Dget_space(dset));
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space) : -1;
  if (rank < 0) fail_hdf5(where, name + ": cannot read its shape");
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  return std::vector<uint64_t>(dims.begin(), dims.end());
}

template <class T>
std::vector<T> read_dataset(const std::string& where, hid_t loc, const std::string& name,
                            const std::vector<uint64_t>& dims) {
  const std::vector<uint64_t> found = dataset_shape(where, loc, name);
  if (found != dims)
    fail(where, name + ": shape " + shape_string(found) + ", expected " + shape_string(dims));
  Dataset dset = open_dataset(where, loc, name);
  Datatype type(H5Dget_type(dset));
  if (!type.valid()) fail_hdf5(where, name + ": cannot read its type");
  if (!type_matches<T>(type))
    fail(where, name + ": type " + type_string(type) + ", expected " + TypeOf<T>::name);
  uint64_t count = 1;
  for (uint64_t d : dims) count *= d;
  std::vector<T> data(count);
  if (count > 0 &&
      H5Dread(dset, TypeOf<T>::memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
    fail_hdf5(where, name + ": cannot read");
  return data;
}

template void write_dataset<double>(const std::string&, hid_t, const std::string&,
                                    const std::vector<double>&, const std::vector<uint64_t>&);
template void write_dataset<float>(const std::string&, hid_t, const std::string&,
                                   const std::vector<float>&, const std::vector<uint64_t>&);
template void write_dataset<uint64_t>(const std::string&, hid_t, const std::string&,
                                      const std::vector<uint64_t>&, const std::vector<uint64_t>&);
template std::vector<double> read_dataset<double>(const std::string&, hid_t, const std::string&,
                                                  const std::vector<uint64_t>&);
template std::vector<float> read_dataset<float>(const std::string&, hid_t, const std::string&,
                                                const std::vector<uint64_t>&);
template std::vector<uint64_t> read_dataset<uint64_t>(const std::string&, hid_t, const std::string&,
                                                      const std::vector<uint64_t>&);

// ---- attributes -------------------------------------------------------------------------

bool has_attribute(hid_t obj, const std::string& name) {
  quiet();
  return H5Aexists(obj, name.c_str()) > 0;
}

void write_attr_i64(const std::string& where, hid_t obj, const std::string& name, int64_t value) {
  write_attr_raw(where, obj, name, H5T_STD_I64LE, H5T_NATIVE_INT64, {}, &value);
}

void write_attr_u64(const std::string& where, hid_t obj, const std::string& name, uint64_t value) {
  write_attr_raw(where, obj, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, {}, &value);
}

void write_attr_f64(const std::string& where, hid_t obj, const std::string& name, double value) {
  write_attr_raw(where, obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &value);
}

void write_attr_bool(const std::string& where, hid_t obj, const std::string& name, bool value) {
  const uint8_t v = value ? 1 : 0;
  write_attr_raw(where, obj, name, H5T_STD_U8LE, H5T_NATIVE_UINT8, {}, &v);
}

void write_attr_string(const std::string& where, hid_t obj, const std::string& name,
                       const std::string& value) {
  check_no_nul(where, name, value);
  Datatype type = fixed_string_type(value.size());
  write_attr_raw(where, obj, name, type, type, {}, value.c_str());
}

void write_attr_f64s(const std::string& where, hid_t obj, const std::string& name,
                     const std::vector<double>& values) {
  write_attr_raw(where, obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size()},
                 values.data());
}

void write_attr_u64s(const std::string& where, hid_t obj, const std::string& name,
                     const std::vector<uint64_t>& values) {
  write_attr_raw(where, obj, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, {values.size()},
                 values.data());
}

void write_attr_strings(const std::string& where, hid_t obj, const std::string& name,
                        const std::vector<std::string>& values) {
  size_t longest = 1;
  for (const std::string& v : values) {
    check_no_nul(where, name, v);
    longest = std::max(longest, v.size());
  }
  std::vector<char> packed(longest * values.size(), '\0');
  for (size_t i = 0; i < values.size(); ++i)
    std::copy(values[i].begin(), values[i].end(), packed.begin() + i * longest);
  Datatype type = fixed_string_type(longest);
  write_attr_raw(where, obj, name, type, type, {values.size()}, packed.data());
}

int64_t read_attr_i64(const std::string& where, hid_t obj, const std::string& name) {
  const IntValues v = read_ints(where, obj, name, false);
  if (v.is_signed) return v.s[0];
  if (v.u[0] > static_cast<uint64_t>(std::numeric_limits<int64_t>::max()))
    fail(where, attr_where(name) + ": value " + std::to_string(v.u[0]) + " out of range");
  return static_cast<int64_t>(v.u[0]);
}

uint64_t read_attr_u64(const std::string& where, hid_t obj, const std::string& name) {
  const IntValues v = read_ints(where, obj, name, false);
  if (!v.is_signed) return v.u[0];
  if (v.s[0] < 0) fail(where, attr_where(name) + ": negative value " + std::to_string(v.s[0]));
  return static_cast<uint64_t>(v.s[0]);
}

double read_attr_f64(const std::string& where, hid_t obj, const std::string& name) {
  OpenAttr a = open_attr(where, obj, name, false);
  require_class(where, name, a, H5T_FLOAT, "a floating-point number");
  double value = 0;
  read_attr_raw(where, name, a, H5T_NATIVE_DOUBLE, &value);
  return value;
}

bool read_attr_bool(const std::string& where, hid_t obj, const std::string& name) {
  const int64_t v = read_attr_i64(where, obj, name);
  if (v != 0 && v != 1)
    fail(where, attr_where(name) + ": expected 0 or 1, found " + std::to_string(v));
  return v == 1;
}

std::string read_attr_string(const std::string& where, hid_t obj, const std::string& name) {
  return read_strings(where, obj, name, false)[0];
}

std::vector<double> read_attr_f64s(const std::string& where, hid_t obj, const std::string& name) {
  OpenAttr a = open_attr(where, obj, name, true);
  require_class(where, name, a, H5T_FLOAT, "floating-point numbers");
  std::vector<double> values(a.count);
  read_attr_raw(where, name, a, H5T_NATIVE_DOUBLE, values.data());
  return values;
}

std::vector<uint64_t> read_attr_u64s(const std::string& where, hid_t obj, const std::string& name) {
  IntValues v = read_ints(where, obj, name, true);
  if (!v.is_signed) return std::move(v.u);
  std::vector<uint64_t> out;
  for (int64_t s : v.s) {
    if (s < 0) fail(where, attr_where(name) + ": negative value " + std::to_string(s));
    out.push_back(static_cast<uint64_t>(s));
  }
  return out;
}

std::vector<std::string> read_attr_strings(const std::string& where, hid_t obj,
                                           const std::string& name) {
  return read_strings(where, obj, name, true);
}

}  // namespace lazyboe::h5
