// Counts every operator new in a test binary (alloc_counter.cpp replaces the global one), to
// prove that hot paths allocate nothing.
#pragma once

#include <atomic>

// ThreadSanitizer's (static) runtime defines operator new itself, so a TSan build cannot
// replace it: there the count stays 0 and the tests that read it skip.
#if defined(__SANITIZE_THREAD__)
#define LAZYBOE_TEST_COUNTS_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define LAZYBOE_TEST_COUNTS_ALLOCATIONS 0
#endif
#endif
#ifndef LAZYBOE_TEST_COUNTS_ALLOCATIONS
#define LAZYBOE_TEST_COUNTS_ALLOCATIONS 1
#endif

namespace lazyboe::test {
extern std::atomic<long> allocations;
inline constexpr bool counts_allocations = LAZYBOE_TEST_COUNTS_ALLOCATIONS;
}  // namespace lazyboe::test

// The first statement of a test that reads `allocations`.
#define LAZYBOE_SKIP_UNLESS_COUNTING_ALLOCATIONS()                                          \
  if (!lazyboe::test::counts_allocations)                                                   \
  GTEST_SKIP() << "allocations are not counted under ThreadSanitizer (its runtime defines " \
                  "operator new)"
