// What the files beside a bundle (the k-d tree index, the workspace index) share: reading one
// whole, memory-mapped or read, and the fingerprint that ties one to the bundle's edge states.
// Internal to the library.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "lazyboe/bundle/bundle_view.h"

namespace lazyboe {

struct IndexFileBytes {
  std::shared_ptr<const void> storage;  // the mapping or the bytes read; keeps `data` valid
  const char* data = nullptr;
  size_t size = 0;
};

// The whole file, mapped read-only or read. Throws Error naming it when it cannot be, is not a
// regular file (opened without blocking: a FIFO there must not hang the session) or is shorter
// than `min_bytes` ("truncated or malformed").
IndexFileBytes read_index_file(const std::string& path, bool memory_map, size_t min_bytes);

// What ties an index to the bundle's edge states: the checksums stored with q0 and qf, or for a
// file written before checksums the same FNV-1a 64 computed from their bytes (one pass over them).
std::string bundle_states_fingerprint(const BundleView& bundle);

}  // namespace lazyboe
