// An array of plain values in memory the kernel may back with huge pages (Linux transparent
// huge pages, asked for with madvise): for the few megabytes that searches read at scattered
// places thousands of times a query (the k-d index's copy of its points), where the misses of
// the address translation with 4 KiB pages cost much of the time. Elsewhere, or when the
// kernel declines, it is ordinary memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace lazyboe {

template <typename T>
class HugePageArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                "plain values only: the memory is neither constructed nor destroyed");

 public:
  // x86-64's huge page (and aarch64's with 4 KiB pages); elsewhere only an alignment.
  static constexpr size_t kHugePage = size_t{2} << 20;

  HugePageArray() = default;
  // `count` values, uninitialised.
  explicit HugePageArray(size_t count) : size_(count) {
    if (count == 0) return;
    if (count > (SIZE_MAX - kHugePage) / sizeof(T)) throw std::bad_alloc();
    const size_t bytes = (count * sizeof(T) + kHugePage - 1) / kHugePage * kHugePage;
    data_ = static_cast<T*>(std::aligned_alloc(kHugePage, bytes));
    if (data_ == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(data_, bytes, MADV_HUGEPAGE);  // a request: declined, the pages stay small
#endif
  }
  ~HugePageArray() { std::free(data_); }
  HugePageArray(HugePageArray&& other) noexcept : data_(other.data_), size_(other.size_) {
    other.data_ = nullptr;
    other.size_ = 0;
  }
  HugePageArray& operator=(HugePageArray&& other) noexcept {
    if (this == &other) return *this;
    std::free(data_);
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    return *this;
  }
  HugePageArray(const HugePageArray&) = delete;
  HugePageArray& operator=(const HugePageArray&) = delete;

  T* data() { return data_; }
  const T* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

 private:
  T* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace lazyboe
