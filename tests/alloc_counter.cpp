#include "alloc_counter.h"

#include <cstdlib>
#include <new>

namespace lazyboe::test {
std::atomic<long> allocations{0};
}  // namespace lazyboe::test

#if LAZYBOE_TEST_COUNTS_ALLOCATIONS
void* operator new(std::size_t size) {
  ++lazyboe::test::allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#endif
