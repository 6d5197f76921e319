// The bundle file's per-edge datasets, described once (schemas/bundle.md has the same table for
// readers, and a test holds the two together). The writer, the reader, the memory-mapped view,
// the size and shape checks and the checksum verification all walk this table; the dataset
// paths are the constants of bundle_dataset (bundle_file.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace lazyboe {

struct Bundle;

// Every dataset, in the file's (and the schema's) order.
enum class BundleDatasetId {
  Q0,
  Qf,
  Duration,
  CommandDuration,
  Attempt,
  KnotOffset,
  SampleOffset,
  Knots,
  SampleQ,
  SampleDq,
  Done,
  Valid,
  Lazy,
  Collision,
  MaxError,
  PLazyProp,
  PCollision,
  TransferLazy,
  TransferMaxError,
  PLazyPropTransfer,
};
constexpr size_t kBundleDatasetCount = static_cast<size_t>(BundleDatasetId::PLazyPropTransfer) + 1;

enum class ElementType { F64, U64, F32 };
// The element type of T (double, uint64_t, float).
template <typename T>
constexpr ElementType element_type_of() {
  if constexpr (std::is_same_v<T, double>) return ElementType::F64;
  if constexpr (std::is_same_v<T, float>) return ElementType::F32;
  static_assert(
      std::is_same_v<T, double> || std::is_same_v<T, float> || std::is_same_v<T, uint64_t>,
      "bundle datasets hold double, float or uint64_t");
  return ElementType::U64;
}
const char* element_type_name(ElementType type);  // "float64", "uint64", "float32"

// The first dimension: the edges N, N + 1 (offsets), or the rows an offset dataset indexes (the
// knots K, the trajectory samples S).
enum class RowRule { Edges, EdgesPlusOne, KnotRows, SampleRows };

// When a dataset is in the file: always; with a perturbation analysis (the /perturbation
// group); with its transfer statistics (optional within the analysis: all three or none).
enum class Presence { Always, Perturbation, Transfer };

struct BundleDatasetSpec {
  BundleDatasetId id;
  const char* path;   // in the file: "/edges/q0"
  const char* field;  // in Bundle, as errors name it: "q0", "perturbation.p_lazy_prop"
  ElementType type;
  RowRule rows;
  bool per_joint;  // a second dimension of dof columns
  Presence presence;
  bool viewed;  // attached by BundleView (what planning reads)
};

// The table, indexed by BundleDatasetId. Every dataset carries a checksum attribute.
const std::array<BundleDatasetSpec, kBundleDatasetCount>& bundle_datasets();
const BundleDatasetSpec& bundle_dataset_spec(BundleDatasetId id);

// The row counts a dataset's first dimension follows.
struct BundleRows {
  uint64_t edges = 0, knots = 0, samples = 0;
};
// A bundle in memory's row counts (knots and samples from their sizes and dof).
BundleRows bundle_rows(const Bundle& bundle);
uint64_t dataset_rows(const BundleDatasetSpec& spec, const BundleRows& rows);
// Its shape in the file: {rows} or {rows, dof}.
std::vector<uint64_t> dataset_shape(const BundleDatasetSpec& spec, const BundleRows& rows,
                                    uint64_t dof);
// "N x dof", "N + 1", "K x dof": the schema's way of writing the shape.
std::string shape_rule_text(const BundleDatasetSpec& spec);

// The in-memory array of a dataset in a Bundle.
using BundleArrayRef =
    std::variant<std::vector<double>*, std::vector<uint64_t>*, std::vector<float>*>;
BundleArrayRef bundle_array(Bundle& bundle, BundleDatasetId id);
using ConstBundleArrayRef = std::variant<const std::vector<double>*, const std::vector<uint64_t>*,
                                         const std::vector<float>*>;
ConstBundleArrayRef bundle_array(const Bundle& bundle, BundleDatasetId id);
// Whether a dataset is there when the file has a perturbation analysis (or not) and its
// transfer statistics (or not).
bool present_with(const BundleDatasetSpec& spec, bool perturbation, bool transfer);
// Whether the bundle holds the dataset (its group is there).
bool bundle_has(const Bundle& bundle, const BundleDatasetSpec& spec);

}  // namespace lazyboe
