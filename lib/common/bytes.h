// Little byte buffers for the checkpoint journals and the MPI messages: plain values and
// arrays appended to a string, and read back in the same order with bounds checks.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "lazyboe/common/error.h"

namespace lazyboe {

class ByteWriter {
 public:
  explicit ByteWriter(std::string& out) : out_(out) {}
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T>
  void put_array(const T* data, size_t count) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<uint64_t>(count);
    out_.append(reinterpret_cast<const char*>(data), count * sizeof(T));
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    put_array(v.data(), v.size());
  }
  void put_string(const std::string& s) { put_array(s.data(), s.size()); }

 private:
  std::string& out_;
};

// Reads what ByteWriter wrote; running past the end throws Error(where: "truncated record").
class ByteReader {
 public:
  ByteReader(const char* data, size_t size, std::string where)
      : p_(data), end_(data + size), where_(std::move(where)) {}
  template <class T>
  T get() {
    T v;
    take(&v, sizeof v);
    return v;
  }
  // Appends the array to `v` (which may hold values already).
  template <class T>
  void append_vector(std::vector<T>& v) {
    const uint64_t n = get<uint64_t>();
    if (n > static_cast<uint64_t>(end_ - p_) / sizeof(T)) fail(where_, "truncated record");
    const size_t old = v.size();
    v.resize(old + n);
    take(v.data() + old, n * sizeof(T));
  }
  template <class T>
  std::vector<T> get_vector() {
    std::vector<T> v;
    append_vector(v);
    return v;
  }
  std::string get_string() {
    const std::vector<char> c = get_vector<char>();
    return std::string(c.begin(), c.end());
  }
  bool at_end() const { return p_ == end_; }

 private:
  void take(void* dst, size_t n) {
    if (n > static_cast<size_t>(end_ - p_)) fail(where_, "truncated record");
    if (n) std::memcpy(dst, p_, n);
    p_ += n;
  }
  const char* p_;
  const char* end_;
  std::string where_;
};

}  // namespace lazyboe
