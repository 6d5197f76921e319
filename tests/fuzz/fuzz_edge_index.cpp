// The k-d tree index file beside a bundle (edge_index_file.h, schemas/bundle.md, "k-d tree
// index"): whatever bytes lie at <bundle>.kd-index, a session either refuses them (and builds
// the trees, saying why) or maps them and searches them; a search of an accepted index must
// stay in bounds and end. The first byte chooses mapped or read (bit 0) and whether the body's
// checksum is recomputed before the file is written (bit 1), so that mutated trees get past it
// to the structure check and the search; the rest is the file.
#include <cstring>
#include <vector>

#include "fuzz_util.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/common/hash.h"
#include "lazyboe/planning/edge_index_file.h"
#include "states_bundle.h"

using namespace lazyboe;

namespace {
// 300 edges of 7 joints on a coarse grid (duplicates and shared coordinates, as real bundles
// have), from a fixed generator: the committed seeds (tests/fuzz/corpus/edge_index) are its
// index files.
const BundleView& bundle_view() {
  static const BundleView view = [] {
    uint64_t state = 12345;
    const auto grid = [&] {  // a small LCG: -1, -0.75, ..., 1
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<double>((state >> 33) % 9) / 4.0 - 1.0;
    };
    return BundleView::from_memory(test::states_bundle(300, 7, -1, 1, grid),
                                   fuzz::scratch_dir() + "/bundle.h5");
  }();
  return view;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const BundleView& view = bundle_view();
  std::vector<uint8_t> file(data + 1, data + size);
  constexpr size_t kHeader = 128, kChecksumAt = 120;  // schemas/bundle.md, "k-d tree index"
  if ((data[0] & 2) && file.size() >= kHeader) {
    Fnv1a64 hash;
    hash.update(file.data() + kHeader, file.size() - kHeader);
    const uint64_t value = hash.value();
    std::memcpy(file.data() + kChecksumAt, &value, sizeof value);
  }
  fuzz::write_scratch("bundle.h5.kd-index", file.data(), file.size());
  const BundleIndexes indexes = load_bundle_indexes(view, (data[0] & 1) == 0);
  std::vector<std::pair<uint32_t, double>> found;
  size_t total = 0;
  for (size_t e = 0; e < view.size(); e += 150) {  // a few searches: the checks are the target
    for (const double radius : {0.3, 1.5}) {
      indexes.starts.within(view.q0(e), radius, found);
      total += found.size();
      indexes.ends.within(view.qf(e), radius, found);
      total += found.size();
    }
  }
  volatile size_t keep = total;  // the searches must happen
  (void)keep;
  (void)bundle_index_status(view);
  return 0;
}
