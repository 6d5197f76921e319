// The k-d tree index file beside a bundle (edge_index_file.h, schemas/bundle.md, "k-d tree
// index"): whatever bytes lie at <bundle>.kd-index, a session either refuses them (and builds
// the trees, saying why) or maps them and searches them; a search of an accepted index must
// stay in bounds and end. The first byte chooses mapped or read; the rest is the file.
#include <vector>

#include "edge_index_bundle.h"
#include "fuzz_util.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/edge_index_file.h"

using namespace lazyboe;

namespace {
const BundleView& bundle_view() {
  static const BundleView view =
      BundleView::from_memory(fuzz::edge_index_bundle(), fuzz::scratch_dir() + "/bundle.h5");
  return view;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const BundleView& view = bundle_view();
  fuzz::write_scratch("bundle.h5.kd-index", data + 1, size - 1);
  const BundleIndexes indexes = load_bundle_indexes(view, data[0] % 2 == 0);
  std::vector<std::pair<uint32_t, double>> found;
  size_t total = 0;
  for (size_t e = 0; e < view.size(); e += 37) {
    for (const double radius : {0.3, 1.2, 5.0}) {
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
