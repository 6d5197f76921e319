#include "lazyboe/planning/workspace_index.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>

#include "lazyboe/bundle/scene.h"
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/index_file.h"
#include "lazyboe/planning/workspace_sweep.h"
#include "lazyboe/robot/kinematics.h"

namespace lazyboe {
namespace {

constexpr char kMagic[8] = {'L', 'B', 'W', 'S', 'I', 'D', 'X', '\n'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 192;
constexpr size_t kMaxKeys = size_t{1} << 31;  // (cell, link) lists: a grid of 2 10^9 is a mistake
constexpr size_t kChunk = 2048;               // edges swept between two appends to the lists

// The fixed header (little-endian, as the bundle's datasets); the body follows at byte 192:
// the indexed links' names (each NUL-terminated, padded to 8 bytes), the list offsets
// (cells x links + 1 uint64) and the lists (padded to 8 bytes).
struct IndexHeader {
  char magic[8];
  uint32_t version, links;
  uint64_t edges;
  double cell, origin[3];
  int32_t dims[3];
  uint32_t reserved;
  char states_checksum[64];  // bundle_states_fingerprint(), NUL-padded
  uint64_t names_bytes, list_bytes;
  uint64_t body_checksum;  // word_checksum of the body
  uint64_t reserved2[4];
};
static_assert(sizeof(IndexHeader) == kHeaderBytes, "IndexHeader is a file format");

size_t padded8(size_t bytes) { return (bytes + 7) / 8 * 8; }

// FNV-1a 64 over the body's 64-bit words (8x faster than byte-wise; the body is padded to 8).
uint64_t word_checksum(const char* data, size_t bytes) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i + 8 <= bytes; i += 8) {
    uint64_t w;
    std::memcpy(&w, data + i, 8);
    h = (h ^ w) * 0x100000001b3ull;
  }
  return h;
}

std::string names_block(const RobotModel& robot, const std::vector<int>& links) {
  std::string out;
  for (const int l : links) out += robot.links[l].name + '\0';
  out.resize(padded8(out.size()), '\0');
  return out;
}

void append_varint(std::vector<uint8_t>& out, uint64_t v) {
  for (; v >= 0x80; v >>= 7) out.push_back(static_cast<uint8_t>(v | 0x80));
  out.push_back(static_cast<uint8_t>(v));
}

// The grid around every cell any edge's links can reach.
WorkspaceGrid make_grid(const BundleView& bundle, const RobotModel& robot,
                        const std::vector<SweptShape>& shapes, double cell, int threads) {
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d upper = -lower;
#pragma omp parallel num_threads(threads)
  {
    RobotData data(robot);
    std::vector<Segment> segments;
    Eigen::Vector3d lo = lower, hi = upper;
#pragma omp for schedule(dynamic, 64)
    for (size_t e = 0; e < bundle.size(); ++e) {
      sweep_segments(bundle, robot, shapes, e, data, segments);
      for (const Segment& s : segments) {
        lo = lo.cwiseMin(s.a.cwiseMin(s.b) - Eigen::Vector3d::Constant(s.radius));
        hi = hi.cwiseMax(s.a.cwiseMax(s.b) + Eigen::Vector3d::Constant(s.radius));
      }
    }
#pragma omp critical
    {
      lower = lower.cwiseMin(lo);  // min and max: the same in any order
      upper = upper.cwiseMax(hi);
    }
  }
  WorkspaceGrid g;
  g.cell = cell;
  const double pad = cell;  // a cell's half diagonal and more
  for (int k = 0; k < 3; ++k) {
    g.origin[k] = std::floor((lower[k] - pad) / cell) * cell;
    g.dims[k] = static_cast<int>(std::ceil((upper[k] + pad - g.origin[k]) / cell));
  }
  return g;
}

// Per (cell, link) key, the edges that sweep it, delta-coded in edge order (so the lists do not
// depend on the threads that swept them).
std::vector<std::vector<uint8_t>> sweep_lists(const BundleView& bundle, const RobotModel& robot,
                                              const std::vector<SweptShape>& shapes, size_t links,
                                              const WorkspaceGrid& grid,
                                              const WorkspaceIndexOptions& options, int threads,
                                              uint64_t& entries) {
  const size_t keys = grid.cells() * links;
  std::vector<std::vector<uint8_t>> lists(keys);
  std::vector<uint64_t> last(keys, 0);  // 1 + the last edge of each list (0: none yet)
  std::vector<std::vector<uint32_t>> swept(kChunk);
  for (size_t begin = 0; begin < bundle.size(); begin += kChunk) {
    const size_t end = std::min(bundle.size(), begin + kChunk);
#pragma omp parallel num_threads(threads)
    {
      RobotData data(robot);
      std::vector<Segment> segments;
      std::vector<uint32_t> stamp(keys, 0);
#pragma omp for schedule(dynamic, 16)
      for (size_t e = begin; e < end; ++e) {
        sweep_segments(bundle, robot, shapes, e, data, segments);
        swept_keys(grid, shapes, segments, links, static_cast<uint32_t>(e - begin + 1), stamp,
                   swept[e - begin]);
      }
    }
    for (size_t e = begin; e < end; ++e) {
      for (const uint32_t k : swept[e - begin]) {
        append_varint(lists[k], e + 1 - last[k]);
        last[k] = e + 1;
      }
      entries += swept[e - begin].size();
    }
    if (options.progress) options.progress(end);
  }
  return lists;
}

// Why the header does not describe an index of `bundle` and `robot` in a file of `size` bytes;
// "" if it does.
std::string mismatch(const IndexHeader& h, const BundleView& bundle, const std::string& names,
                     size_t links, size_t size) {
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) return "not a workspace index";
  if (h.version != kVersion) return "workspace index format version " + std::to_string(h.version);
  const std::string stored(h.states_checksum, strnlen(h.states_checksum, sizeof h.states_checksum));
  if (h.edges != bundle.size() || stored != bundle_states_fingerprint(bundle))
    return "made for other edge states than the bundle's (rewrite it with lazyboe-build "
           "--workspace-index)";
  if (!(h.cell > 0) || !std::isfinite(h.cell) || !std::isfinite(h.origin[0]) ||
      !std::isfinite(h.origin[1]) || !std::isfinite(h.origin[2]) || h.dims[0] <= 0 ||
      h.dims[1] <= 0 || h.dims[2] <= 0 || h.links == 0 || h.links > kMaxLinks)
    return "truncated or malformed";
  const uint64_t keys = static_cast<uint64_t>(h.dims[0]) * static_cast<uint64_t>(h.dims[1]) *
                        static_cast<uint64_t>(h.dims[2]) * h.links;
  if (keys > kMaxKeys || h.names_bytes % 8 != 0 || h.list_bytes % 8 != 0 || h.names_bytes > size ||
      h.list_bytes > size || size != kHeaderBytes + h.names_bytes + 8 * (keys + 1) + h.list_bytes)
    return "truncated or malformed";
  if (h.names_bytes != names.size() || h.links != links) return "made for another robot's links";
  return "";
}

}  // namespace

bool WorkspaceGrid::cell_range(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper,
                               std::array<int, 3>& first, std::array<int, 3>& last) const {
  for (int k = 0; k < 3; ++k) {
    const double lo = std::floor((lower[k] - origin[k]) / cell);
    const double hi = std::floor((upper[k] - origin[k]) / cell);
    if (!(hi >= 0) || !(lo < dims[k])) return false;  // outside, or NaN
    first[k] = static_cast<int>(std::max(lo, 0.0));
    last[k] = static_cast<int>(std::min(hi, static_cast<double>(dims[k] - 1)));
  }
  return true;
}

std::string workspace_index_path(const std::string& bundle_path) {
  return bundle_path + ".ws-index";
}

WorkspaceIndexSummary write_workspace_index(const BundleView& bundle, const RobotModel& robot,
                                            const WorkspaceIndexOptions& options) {
  const std::string path = workspace_index_path(bundle.path());
  if (bundle.header().sample_interval <= 0)
    fail(bundle.path(),
         "has no stored trajectory samples (built with --sample-interval 0): the "
         "workspace index sweeps them");
  if (!(options.cell > 0) || !std::isfinite(options.cell)) fail(path, "cell size must be positive");
  std::vector<int> links;
  const std::vector<SweptShape> shapes = swept_shapes(robot, links);
  const int threads = options.threads > 0 ? options.threads : omp_get_num_procs();
  WorkspaceIndexSummary out;
  out.grid = make_grid(bundle, robot, shapes, options.cell, threads);
  out.links = links.size();
  if (out.grid.cells() * links.size() > kMaxKeys)
    fail(path, "a cell of " + std::to_string(options.cell) + " m makes too many cells");
  const std::vector<std::vector<uint8_t>> lists =
      sweep_lists(bundle, robot, shapes, links.size(), out.grid, options, threads, out.entries);

  IndexHeader h{};
  const std::string states = bundle_states_fingerprint(bundle);
  if (states.size() >= sizeof h.states_checksum) fail(path, "unexpected checksum " + states);
  const std::string names = names_block(robot, links);
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kVersion;
  h.links = static_cast<uint32_t>(links.size());
  h.edges = bundle.size();
  h.cell = out.grid.cell;
  for (int k = 0; k < 3; ++k) {
    h.origin[k] = out.grid.origin[k];
    h.dims[k] = out.grid.dims[k];
  }
  std::memcpy(h.states_checksum, states.data(), states.size());
  std::vector<uint64_t> offsets(lists.size() + 1, 0);
  for (size_t k = 0; k < lists.size(); ++k) offsets[k + 1] = offsets[k] + lists[k].size();
  h.names_bytes = names.size();
  h.list_bytes = padded8(offsets.back());
  std::string image(kHeaderBytes, '\0');
  image += names;
  image.append(reinterpret_cast<const char*>(offsets.data()), offsets.size() * sizeof(uint64_t));
  for (const std::vector<uint8_t>& l : lists)
    image.append(reinterpret_cast<const char*>(l.data()), l.size());
  image.resize(kHeaderBytes + names.size() + offsets.size() * 8 + h.list_bytes, '\0');
  h.body_checksum = word_checksum(image.data() + kHeaderBytes, image.size() - kHeaderBytes);
  std::memcpy(image.data(), &h, sizeof h);
  AtomicFile file(path, AtomicFile::Writer::External);
  file.write_all(image.data(), image.size());
  file.commit();
  out.bytes = image.size();
  return out;
}

std::shared_ptr<const WorkspaceIndex> WorkspaceIndex::open(const BundleView& bundle,
                                                           const RobotModel& robot,
                                                           bool memory_map) {
  const std::string path = workspace_index_path(bundle.path());
  const IndexFileBytes f = read_index_file(path, memory_map, kHeaderBytes);
  IndexHeader h;
  std::memcpy(&h, f.data, sizeof h);
  std::vector<int> links;
  swept_shapes(robot, links);
  const std::string names = names_block(robot, links);
  const std::string why = mismatch(h, bundle, names, links.size(), f.size);
  if (!why.empty()) fail(path, why);
  if (std::memcmp(f.data + kHeaderBytes, names.data(), names.size()) != 0)
    fail(path, "made for another robot's links");
  if (word_checksum(f.data + kHeaderBytes, f.size - kHeaderBytes) != h.body_checksum)
    fail(path, "checksum mismatch: the file is damaged");
  std::shared_ptr<WorkspaceIndex> index(new WorkspaceIndex);
  index->path_ = path;
  index->grid_.cell = h.cell;
  for (int k = 0; k < 3; ++k) {
    index->grid_.origin[k] = h.origin[k];
    index->grid_.dims[k] = h.dims[k];
  }
  index->links_ = links;
  index->edges_ = h.edges;
  index->file_bytes_ = f.size;
  index->storage_ = f.storage;
  index->offsets_ = reinterpret_cast<const uint64_t*>(f.data + kHeaderBytes + h.names_bytes);
  index->data_ =
      reinterpret_cast<const uint8_t*>(index->offsets_ + index->grid_.cells() * h.links + 1);
  const size_t keys = index->grid_.cells() * h.links;
  for (size_t k = 0; k < keys; ++k) {  // so that no list is read out of bounds
    if (index->offsets_[k + 1] < index->offsets_[k]) fail(path, "truncated or malformed");
  }
  if (index->offsets_[0] != 0 || index->offsets_[keys] > h.list_bytes)
    fail(path, "truncated or malformed");
  return index;
}

WorkspaceIndexLoad load_workspace_index(const BundleView& bundle, const RobotModel& robot,
                                        bool memory_map) {
  const std::string path = workspace_index_path(bundle.path());
  std::error_code error;
  if (!std::filesystem::exists(path, error) && !error)
    return {nullptr,
            "none (planning in other scenes uses no collision prior; lazyboe-build "
            "--workspace-index " +
                bundle.path() + " writes it)"};
  try {
    return {WorkspaceIndex::open(bundle, robot, memory_map),
            (memory_map ? "mapped from " : "read from ") + path};
  } catch (const std::exception& e) {  // a damaged or foreign index is ignored, with the reason
    return {nullptr, std::string(e.what()) +
                         " (not used: rewrite it with lazyboe-build "
                         "--workspace-index)"};
  }
}

std::string workspace_index_status(const BundleView& bundle) {
  WorkspaceIndexLoad w;
  try {
    w = load_workspace_index(bundle, load_bundle_robot(bundle.header(), ""), true);
  } catch (const std::exception& e) {  // the bundle's robot is not where it was
    return std::string("not checked: ") + e.what();
  }
  if (!w.index) return w.source;
  char line[160];
  std::snprintf(line, sizeof line, " (%.1f MB, %.3f m cells; used for planning in other scenes)",
                w.index->file_bytes() / 1e6, w.index->grid().cell);
  return w.index->path() + line;
}

void WorkspaceIndex::mark(size_t cell, int link, uint64_t* bits) const {
  const size_t k = cell * links_.size() + static_cast<size_t>(link);
  const uint8_t* p = data_ + offsets_[k];
  const uint8_t* const end = data_ + offsets_[k + 1];
  uint64_t edge_plus_one = 0;
  while (p < end) {
    uint64_t delta = 0;
    for (int shift = 0; p < end && shift < 64; shift += 7) {
      const uint8_t byte = *p++;
      delta |= static_cast<uint64_t>(byte & 0x7f) << shift;
      if (!(byte & 0x80)) break;
    }
    edge_plus_one += delta;
    const uint64_t e = edge_plus_one - 1;
    if (e < edges_) bits[e >> 6] |= uint64_t{1} << (e & 63);
  }
}

}  // namespace lazyboe
