// The k-d trees over the edge states (lib/planning/neighbour_index.h): building one, and the
// radius query the planners make at every expansion, on 100 000 synthetic edge states spread
// uniformly over a box of 0.6 rad per joint (the density of the tests' small bundle, so a
// radius of 0.15 rad holds about 30 neighbours and 0.35 rad about 1000).
#include <benchmark/benchmark.h>

#include <memory>
#include <random>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/planning/neighbour_index.h"
#include "states_bundle.h"

namespace {

using namespace lazyboe;

constexpr int kDof = 7;
constexpr size_t kEdges = 100000;

const BundleView& view() {
  static const BundleView v = [] {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    return BundleView::from_memory(
        test::states_bundle(kEdges, kDof, -0.3, 0.3, [&] { return u(rng); }), "synthetic");
  }();
  return v;
}

void BM_EdgeIndexBuild(benchmark::State& state) {
  for (auto _ : state) {
    const EdgeIndex index(view());
    benchmark::DoNotOptimize(&index);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(kEdges));
}
BENCHMARK(BM_EdgeIndexBuild)->Unit(benchmark::kMillisecond);

// Queries at the edge end states, in a fixed order; the argument is the radius in mrad.
void BM_EdgeIndexWithin(benchmark::State& state) {
  static const EdgeIndex index(view());
  const double radius = static_cast<double>(state.range(0)) / 1000;
  std::vector<std::pair<uint32_t, double>> found;
  size_t e = 0, neighbours = 0;
  for (auto _ : state) {
    index.within(view().qf(e), radius, found);
    neighbours += found.size();
    e = (e + 7919) % kEdges;
  }
  state.counters["neighbours"] =
      benchmark::Counter(static_cast<double>(neighbours), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_EdgeIndexWithin)->Arg(150)->Arg(350)->Unit(benchmark::kMicrosecond);

}  // namespace
