#include "lazyboe/planning/edge_index_file.h"

#include <cstring>
#include <filesystem>
#include <vector>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"
#include "lazyboe/planning/index_file.h"

namespace lazyboe {

namespace {

constexpr char kMagic[8] = {'L', 'B', 'K', 'D', 'I', 'D', 'X', '\n'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 128;

// The fixed header (little-endian, as the bundle's datasets); the body follows at byte 128.
struct IndexHeader {
  char magic[8];
  uint32_t version, dof;
  uint64_t edges;
  uint32_t leaf_size, reserved;
  char states_checksum[64];  // BundleView::states_checksum(), NUL-padded
  uint64_t reserved2;
  uint64_t node_count[2];  // the start tree's, the end tree's
  uint64_t body_checksum;  // FNV-1a 64 of the body
};
static_assert(sizeof(IndexHeader) == kHeaderBytes, "IndexHeader is a file format");

size_t padded8(size_t bytes) { return (bytes + 7) / 8 * 8; }

// One tree's part of the body: the box (2 x dof doubles), the order (edges ids, padded to 8
// bytes), the nodes.
size_t tree_bytes(uint64_t edges, int dof, uint64_t nodes) {
  return 2 * sizeof(double) * static_cast<size_t>(dof) + padded8(edges * sizeof(uint32_t)) +
         nodes * sizeof(KdNode);
}

void append(std::string& out, const void* data, size_t bytes) {
  out.append(static_cast<const char*>(data), bytes);
}

void append_tree(std::string& body, const KdTreeArrays& t, uint64_t edges, int dof) {
  append(body, t.lower, sizeof(double) * static_cast<size_t>(dof));
  append(body, t.upper, sizeof(double) * static_cast<size_t>(dof));
  append(body, t.order, edges * sizeof(uint32_t));
  body.resize(padded8(body.size()), '\0');
  append(body, t.nodes, t.node_count * sizeof(KdNode));
}

// The arrays of one tree at `p` in the body (sizes checked by the caller).
KdTreeArrays tree_at(const char* p, uint64_t edges, int dof, uint64_t nodes) {
  KdTreeArrays t;
  t.lower = reinterpret_cast<const double*>(p);
  t.upper = t.lower + dof;
  t.order = reinterpret_cast<const uint32_t*>(p + 2 * sizeof(double) * static_cast<size_t>(dof));
  t.nodes = reinterpret_cast<const KdNode*>(p + 2 * sizeof(double) * static_cast<size_t>(dof) +
                                            padded8(edges * sizeof(uint32_t)));
  t.node_count = nodes;
  return t;
}

// Why the header does not describe an index of `bundle` in a file of `size` bytes; "" if it does.
std::string mismatch(const IndexHeader& h, const BundleView& bundle, size_t size) {
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) return "not a k-d tree index";
  if (h.version != kVersion) return "index format version " + std::to_string(h.version);
  const std::string stored(h.states_checksum, strnlen(h.states_checksum, sizeof h.states_checksum));
  if (h.dof != static_cast<uint32_t>(bundle.dof()) || h.edges != bundle.size() ||
      stored != bundle_states_fingerprint(bundle))
    return "made for other edge states than the bundle's (rewrite it with lazyboe-build --index)";
  const uint64_t limit = 2 * h.edges + 1;  // what the tree check accepts
  if (h.node_count[0] > limit || h.node_count[1] > limit ||
      size != kHeaderBytes + tree_bytes(h.edges, bundle.dof(), h.node_count[0]) +
                  tree_bytes(h.edges, bundle.dof(), h.node_count[1]))
    return "truncated or malformed";
  return "";
}

// The index at `path` for `bundle`; throws Error saying why it cannot be used.
BundleIndexes open_index(const BundleView& bundle, const std::string& path, bool memory_map) {
  const IndexFileBytes f = read_index_file(path, memory_map, kHeaderBytes);
  IndexHeader h;
  std::memcpy(&h, f.data, sizeof h);
  const std::string why = mismatch(h, bundle, f.size);
  if (!why.empty()) fail(path, why);
  Fnv1a64 hash;
  hash.update(f.data + kHeaderBytes, f.size - kHeaderBytes);
  if (hash.value() != h.body_checksum) fail(path, "checksum mismatch: the file is damaged");
  const char* body = f.data + kHeaderBytes;
  const KdTreeArrays starts = tree_at(body, h.edges, bundle.dof(), h.node_count[0]);
  const KdTreeArrays ends = tree_at(body + tree_bytes(h.edges, bundle.dof(), h.node_count[0]),
                                    h.edges, bundle.dof(), h.node_count[1]);
  return BundleIndexes{EdgeIndex(bundle, EdgePoint::Start, starts, f.storage, path),
                       EdgeIndex(bundle, EdgePoint::End, ends, f.storage, path),
                       (memory_map ? "mapped from " : "read from ") + path};
}

}  // namespace

std::string edge_index_path(const std::string& bundle_path) { return bundle_path + ".kd-index"; }

BundleIndexes load_bundle_indexes(const BundleView& bundle, bool memory_map) {
  const std::string path = edge_index_path(bundle.path());
  std::string why = "no index file";
  std::error_code error;
  if (std::filesystem::exists(path, error) || error) {
    try {
      return open_index(bundle, path, memory_map);
    } catch (const std::exception& e) {  // any reason to ignore the file: the trees are built
      why = e.what();
    }
  }
  return BundleIndexes{EdgeIndex(bundle, EdgePoint::Start), EdgeIndex(bundle, EdgePoint::End),
                       "built at load (" + why + ")"};
}

std::string bundle_index_status(const BundleView& bundle) {
  const std::string path = edge_index_path(bundle.path());
  std::error_code error;
  if (!std::filesystem::exists(path, error) && !error)
    return "none (planning builds the k-d trees at load; lazyboe-build --index " + bundle.path() +
           " writes it)";
  try {
    open_index(bundle, path, true);
    return path + " (used by planning)";
  } catch (const std::exception& e) {
    return std::string(e.what()) + " (not used: planning builds the k-d trees at load)";
  }
}

void write_bundle_index(const BundleView& bundle) {
  const std::string path = edge_index_path(bundle.path());
  const std::string states = bundle_states_fingerprint(bundle);
  IndexHeader h{};
  if (states.size() >= sizeof h.states_checksum) fail(path, "unexpected checksum " + states);
  const EdgeIndex starts(bundle, EdgePoint::Start), ends(bundle, EdgePoint::End);
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kVersion;
  h.dof = static_cast<uint32_t>(bundle.dof());
  h.edges = bundle.size();
  h.leaf_size = EdgeIndex::kLeafSize;
  std::memcpy(h.states_checksum, states.data(), states.size());
  h.node_count[0] = starts.arrays().node_count;
  h.node_count[1] = ends.arrays().node_count;
  std::string image(kHeaderBytes, '\0');
  append_tree(image, starts.arrays(), h.edges, bundle.dof());
  append_tree(image, ends.arrays(), h.edges, bundle.dof());
  Fnv1a64 hash;
  hash.update(image.data() + kHeaderBytes, image.size() - kHeaderBytes);
  h.body_checksum = hash.value();
  std::memcpy(image.data(), &h, sizeof h);
  AtomicFile out(path, AtomicFile::Writer::External);
  out.write_all(image.data(), image.size());
  out.commit();
}

}  // namespace lazyboe
