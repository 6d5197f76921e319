// The k-d trees over the edge states (neighbour_index.h) and their index file beside the bundle
// (edge_index_file.h): the same neighbours as a scan of every edge, built or mapped; an index
// that does not belong to the bundle, is damaged, or is not a file is never used, and never
// an error.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <tuple>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"
#include "lazyboe/common/huge_pages.h"
#include "lazyboe/planning/edge_index_file.h"
#include "lazyboe/planning/planners/neighbour_memo.h"
#include "test_util.h"

namespace lazyboe {
namespace {

namespace fs = std::filesystem;
using Neighbours = std::vector<std::pair<uint32_t, double>>;

// A bundle whose edge states have what trips k-d trees: duplicates, a tight cluster, coordinates
// shared by many points, and points far from the rest.
Bundle awkward_bundle(size_t n, uint64_t seed) {
  Bundle b = test::viewable_bundle(n, 7, seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  for (size_t e = 0; e < n; ++e) {
    double* q0 = b.q0.data() + 7 * e;
    if (e % 7 == 1) std::memcpy(q0, b.q0.data() + 7 * (e - 1), 7 * sizeof(double));  // duplicate
    if (e % 5 == 2)
      for (int k = 0; k < 7; ++k) q0[k] = 0.5 + u(rng);  // cluster
    if (e % 3 == 0) q0[2] = 1.0;                         // a shared coordinate
    if (e % 101 == 50) q0[0] = 900;                      // far away
  }
  return b;
}

// Every edge whose state is within the radius, by the index's own definition (squared distance
// summed in joint order, strictly below the squared radius), in id order.
Neighbours scan(const BundleView& v, EdgePoint point, const double* q, double radius) {
  Neighbours out;
  for (size_t e = 0; e < v.size(); ++e) {
    const double* p = point == EdgePoint::Start ? v.q0(e) : v.qf(e);
    double d = 0;
    for (int k = 0; k < v.dof(); ++k) d += (q[k] - p[k]) * (q[k] - p[k]);
    if (d < radius * radius) out.emplace_back(static_cast<uint32_t>(e), d);
  }
  return out;
}

// The `count` nearest of a scan's results: nearest first, equal distances by id.
Neighbours nearest_of(Neighbours all, size_t count) {
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return a.second < b.second || (a.second == b.second && a.first < b.first);
  });
  all.resize(std::min(count, all.size()));
  return all;
}

// Queries at edge states (where the radius is a neighbour's exact distance, the boundary
// case), at random points and outside the points' box, for several radii: within, any_within
// and nearest answer as the scan.
void expect_scan_results(const BundleView& v, const EdgeIndex& index) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-4, 4);
  Neighbours found;
  for (int i = 0; i < 300; ++i) {
    std::vector<double> q(7);
    const size_t e = rng() % v.size();
    const double* at = index.point() == EdgePoint::Start ? v.q0(e) : v.qf(e);
    for (int k = 0; k < 7; ++k) q[k] = i % 3 == 0 ? at[k] : u(rng) + (i % 3 == 1 ? 0 : 9);
    std::vector<double> radii = {1e-9, 0.05, 0.7, 2.5, 6};
    const Neighbours near = scan(v, index.point(), q.data(), 3);
    if (!near.empty()) radii.push_back(std::sqrt(near[near.size() / 2].second));
    for (const double r : radii) {
      index.within(q.data(), r, found);
      const Neighbours expected = scan(v, index.point(), q.data(), r);
      ASSERT_EQ(found, expected) << "query " << i << " radius " << r;
      ASSERT_EQ(index.any_within(q.data(), r), !expected.empty()) << "query " << i;
      for (const size_t count : {1, 8, 128}) {
        index.nearest(q.data(), count, r, found);
        ASSERT_EQ(found, nearest_of(expected, count)) << "query " << i << " count " << count;
      }
    }
  }
}

std::string written_bundle(const std::string& name, const Bundle& b) {
  const std::string dir = test::temp_dir() + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_bundle(dir + "/bundle.h5", b);
  return dir + "/bundle.h5";
}

TEST(EdgeIndex, FindsWhatAScanFindsForStartsAndEnds) {
  const BundleView v =
      BundleView::from_memory(std::make_shared<const Bundle>(awkward_bundle(3000, 1)), "mem");
  for (const EdgePoint point : {EdgePoint::Start, EdgePoint::End}) {
    const EdgeIndex index(v, point);
    EXPECT_EQ(index.point(), point);
    expect_scan_results(v, index);
  }
}

// lazysp's memo of its radius queries answers as the index, for states asked before (from the
// memo, bit for bit the same state) and new ones, also after it filled up and started again.
TEST(EdgeIndex, TheMemoOfRadiusQueriesAnswersAsTheIndex) {
  const BundleView v =
      BundleView::from_memory(std::make_shared<const Bundle>(awkward_bundle(3000, 4)), "mem");
  const EdgeIndex index(v);
  for (const size_t capacity : {size_t{1} << 20, size_t{2000}}) {  // bytes
    NeighbourMemo memo(index, 0.7, 7, capacity);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<std::vector<double>> states;
    for (int i = 0; i < 200; ++i) {
      if (i % 2 == 1) {  // a state asked before, as the lazy search's next round asks it
        states.push_back(states[rng() % states.size()]);
      } else {
        states.emplace_back(7);
        for (int k = 0; k < 7; ++k) states.back()[k] = v.q0(i)[k] + 0.1 * u(rng);
      }
      const NeighbourMemo::Span got = memo.within(states.back().data());
      std::vector<uint32_t> ids(got.edges, got.edges + got.count), expected;
      for (const auto& [e, d2] : scan(v, EdgePoint::Start, states.back().data(), 0.7))
        expected.push_back(e);
      ASSERT_EQ(ids, expected) << "state " << i << ", memo of " << capacity << " bytes";
    }
    if (capacity > 2000) {
      EXPECT_EQ(memo.hits(), 100u);  // every state asked again
    } else {
      EXPECT_LT(memo.hits(), 100u);  // it started again when full
    }
  }
}

TEST(EdgeIndex, TinyAndEmptyBundles) {
  for (const size_t n : {0, 1, 2, 17}) {
    const BundleView v = BundleView::from_memory(
        std::make_shared<const Bundle>(test::viewable_bundle(n, 7, 2)), "m");
    const EdgeIndex index(v);
    const std::vector<double> q(7, 0.0);
    Neighbours found = {{1, 1.0}};
    index.within(q.data(), 100, found);
    EXPECT_EQ(found, scan(v, EdgePoint::Start, q.data(), 100)) << n << " edges";
    EXPECT_EQ(found.size(), n);
    EXPECT_EQ(index.any_within(q.data(), 100), n > 0);
    index.nearest(q.data(), 4, 100, found);
    EXPECT_EQ(found, nearest_of(scan(v, EdgePoint::Start, q.data(), 100), 4)) << n << " edges";
    index.nearest(q.data(), 0, 100, found);
    EXPECT_TRUE(found.empty());
  }
}

// Leaves of more than 16 points (the start tree scans them by columns, 16 at a time): 60 edges
// that start at one state, which no split separates, and a tree as an index file may hold it,
// one leaf of every point.
TEST(EdgeIndex, LeavesOfManyPointsAnswerAsAScan) {
  Bundle b = test::viewable_bundle(500, 7, 4);
  for (size_t e = 1; e < 60; ++e) std::memcpy(b.q0.data() + 7 * e, b.q0.data(), 7 * sizeof(double));
  const BundleView v = BundleView::from_memory(std::make_shared<const Bundle>(b), "mem");
  expect_scan_results(v, EdgeIndex(v));

  auto one_leaf = std::make_shared<std::vector<KdNode>>(1);
  (*one_leaf)[0].first = 0;
  (*one_leaf)[0].second = static_cast<uint32_t>(v.size());
  auto order = std::make_shared<std::vector<uint32_t>>(v.size());
  std::iota(order->begin(), order->end(), 0u);
  auto box = std::make_shared<std::vector<double>>(14);
  for (int k = 0; k < 7; ++k) {
    (*box)[k] = (*box)[7 + k] = v.q0(0)[k];
    for (size_t e = 0; e < v.size(); ++e) {
      (*box)[k] = std::min((*box)[k], v.q0(e)[k]);
      (*box)[7 + k] = std::max((*box)[7 + k], v.q0(e)[k]);
    }
  }
  const KdTreeArrays arrays{one_leaf->data(), 1, order->data(), box->data(), box->data() + 7};
  const auto storage =
      std::make_shared<std::tuple<decltype(one_leaf), decltype(order), decltype(box)>>(one_leaf,
                                                                                       order, box);
  expect_scan_results(v, EdgeIndex(v, EdgePoint::Start, arrays, storage, "one leaf"));
}

// The index's private copy of its points (HugePageArray): whole huge pages, aligned to one,
// holding what was written; a move (construction or assignment) leaves the source empty.
TEST(EdgeIndex, HugePageArrayHoldsItsValuesOnAlignedPages) {
  HugePageArray<double> a(300000);
  ASSERT_EQ(a.size(), 300000u);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(a.data()) % HugePageArray<double>::kHugePage, 0u);
  for (size_t i = 0; i < a.size(); ++i) a.data()[i] = static_cast<double>(i) * 0.5;
  HugePageArray<double> b(std::move(a));
  EXPECT_TRUE(a.empty());
  EXPECT_EQ(a.data(), nullptr);
  ASSERT_EQ(b.size(), 300000u);
  EXPECT_EQ(b.data()[299999], 299999 * 0.5);
  HugePageArray<double> c(10);
  c = std::move(b);
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b.data(), nullptr);
  EXPECT_EQ(c.data()[12345], 12345 * 0.5);
  EXPECT_TRUE(HugePageArray<double>(0).empty());
}

TEST(EdgeIndexFile, WrittenIndexIsMappedAndAnswersAsTheBuiltTrees) {
  const std::string path = written_bundle("index-mapped", awkward_bundle(2000, 4));
  const BundleView v = BundleView::open(path);
  write_bundle_index(v);
  EXPECT_TRUE(fs::exists(path + ".kd-index"));
  for (const bool map : {true, false}) {
    const BundleIndexes loaded = load_bundle_indexes(v, map);
    EXPECT_EQ(loaded.source, (map ? "mapped from " : "read from ") + path + ".kd-index");
    expect_scan_results(v, loaded.starts);
    expect_scan_results(v, loaded.ends);
  }
  // The file is a function of the bundle: written again, byte for byte the same.
  const std::string first = test::read_file(path + ".kd-index");
  write_bundle_index(v);
  EXPECT_EQ(test::read_file(path + ".kd-index"), first);
}

// The trees are built (and still right) whenever the file beside the bundle cannot be used.
void expect_built(const BundleView& v, const std::string& reason) {
  const BundleIndexes loaded = load_bundle_indexes(v, true);
  EXPECT_NE(loaded.source.find("built at load ("), std::string::npos) << loaded.source;
  EXPECT_NE(loaded.source.find(reason), std::string::npos) << loaded.source;
  expect_scan_results(v, loaded.starts);
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(EdgeIndexFile, AnIndexOfOtherEdgesOrADamagedOneIsNotUsed) {
  const std::string path = written_bundle("index-bad", awkward_bundle(500, 5));
  const std::string index_path = path + ".kd-index";
  expect_built(BundleView::open(path), "no index file");
  write_bundle_index(BundleView::open(path));
  const std::string good = test::read_file(index_path);

  write_bundle(path, awkward_bundle(500, 6));  // same size, other edges
  expect_built(BundleView::open(path), "made for other edge states than the bundle's");
  write_bundle(path, awkward_bundle(500, 5));
  EXPECT_EQ(load_bundle_indexes(BundleView::open(path), true).source, "mapped from " + index_path);

  std::string damaged = good;
  damaged[damaged.size() / 2] ^= 1;
  write_bytes(index_path, damaged);
  expect_built(BundleView::open(path), "checksum mismatch");
  write_bytes(index_path, good.substr(0, good.size() - 8));
  expect_built(BundleView::open(path), "truncated or malformed");
  write_bytes(index_path, "not an index at all");
  expect_built(BundleView::open(path), "truncated or malformed");
  write_bytes(index_path, std::string(200, 'x'));
  expect_built(BundleView::open(path), "not a k-d tree index");
  write_bytes(index_path, "");
  expect_built(BundleView::open(path), "truncated or malformed");

  // Not a file to read: never an error, never a hang.
  fs::remove(index_path);
  fs::create_directory(index_path);
  expect_built(BundleView::open(path), "not a regular file");
  fs::remove(index_path);
  ASSERT_EQ(::mkfifo(index_path.c_str(), 0600), 0);
  expect_built(BundleView::open(path), "not a regular file");
  fs::remove(index_path);
  fs::create_symlink(index_path, index_path);  // a loop
  expect_built(BundleView::open(path), "cannot open");
  EXPECT_NE(bundle_index_status(BundleView::open(path)).find("not used"), std::string::npos);
  fs::remove(index_path);
}

// A file with a valid checksum but a tree that would loop or read out of bounds: refused by the
// structure check, never searched.
TEST(EdgeIndexFile, AMalformedTreeWithAValidChecksumIsNotUsed) {
  const std::string path = written_bundle("index-malformed", awkward_bundle(400, 7));
  const std::string index_path = path + ".kd-index";
  write_bundle_index(BundleView::open(path));
  const std::string good = test::read_file(index_path);
  const size_t header = 128, box = 2 * 7 * sizeof(double), order = 400 * sizeof(uint32_t);
  const size_t root = header + box + order;  // the start tree's first node (order is 8-aligned)
  const auto with_checksum = [&](std::string bytes) {
    Fnv1a64 hash;
    hash.update(bytes.data() + header, bytes.size() - header);
    const uint64_t value = hash.value();
    std::memcpy(&bytes[120], &value, sizeof value);
    return bytes;
  };
  const auto patched = [&](size_t offset, uint32_t value) {
    std::string bytes = good;
    std::memcpy(&bytes[offset], &value, sizeof value);
    return with_checksum(bytes);
  };
  const BundleView v = BundleView::open(path);
  write_bytes(index_path, patched(root + 16, 0));  // the root's left child: itself
  expect_built(v, "malformed k-d tree: child link");
  write_bytes(index_path, patched(root + 20, 1));  // the root's right child: its left one
  expect_built(v, "malformed k-d tree: a node with two parents");
  std::string moved = good;  // the root's left side ends below its points: they lie outside
  const double far_below = -1000;
  std::memcpy(&moved[root], &far_below, sizeof far_below);
  write_bytes(index_path, with_checksum(moved));
  expect_built(v, "malformed k-d tree: a point outside its cell");
  write_bytes(index_path, patched(root + 24, 9));  // split dimension 9 of 7
  expect_built(v, "malformed k-d tree: split");
  uint32_t second_id = 0;
  std::memcpy(&second_id, &good[header + box + 4], sizeof second_id);
  write_bytes(index_path, patched(header + box, second_id));  // an id twice in the order
  expect_built(v, "malformed k-d tree: point order is not a permutation");
  write_bytes(index_path, with_checksum(good));  // unchanged: used
  EXPECT_EQ(load_bundle_indexes(v, true).source, "mapped from " + index_path);
}

}  // namespace
}  // namespace lazyboe
