// Counts every operator new in a test binary (alloc_counter.cpp replaces the global one), to
// prove that hot paths allocate nothing.
#pragma once

#include <atomic>

namespace lazyboe::test {
extern std::atomic<long> allocations;
}  // namespace lazyboe::test
