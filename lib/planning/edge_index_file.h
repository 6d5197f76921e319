// The k-d trees of a bundle, stored beside it in "<bundle>.kd-index" so that a session maps them
// instead of building them at load (1.2 s for a million edges). The index belongs to the bundle
// whose q0 and qf datasets have the checksums it records (stored with them, or computed from
// their bytes for a file written before checksums) and whose trees pass a full check against
// the edge states; any other file there (absent, of another bundle, damaged, not a file) is
// ignored with the reason, and the trees are built as before.
// Format: schemas/bundle.md, "k-d tree index".
#pragma once

#include <string>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/neighbour_index.h"

namespace lazyboe {

// Both trees of a bundle.
struct BundleIndexes {
  EdgeIndex starts, ends;
  std::string source;  // "mapped from PATH", "read from PATH", or "built at load (why)"
};

std::string edge_index_path(const std::string& bundle_path);

// The index file beside the bundle (memory-mapped, or read when memory_map is false) when it
// belongs to it; the trees built otherwise.
BundleIndexes load_bundle_indexes(const BundleView& bundle, bool memory_map);

// One line on the index beside the bundle: its path and whether planning uses it (checked as a
// session checks it), or why not.
std::string bundle_index_status(const BundleView& bundle);

// Builds both trees of the bundle and writes them to edge_index_path(bundle.path()), atomically
// (a temporary file renamed into place). Throws Error naming the index path when it cannot be
// written.
void write_bundle_index(const BundleView& bundle);

}  // namespace lazyboe
