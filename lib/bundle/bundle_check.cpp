#include "lazyboe/bundle/bundle_check.h"

#include <cmath>
#include <variant>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/numbers.h"

namespace lazyboe {
namespace {

namespace ds = bundle_dataset;

constexpr double kMaxPosition = 1e3;  // rad or m
constexpr double kMaxVelocity = 1e4;  // rad/s or m/s
constexpr double kMaxDuration = 1e3;  // s

std::string str(uint64_t v) { return std::to_string(v); }

// Rows x dof values, each finite and within +-limit.
template <typename T>
void check_rows(const std::string& where, const char* name, const T* data, uint64_t rows,
                uint64_t dof, double limit, const char* row_word) {
  if (!data) return;
  for (uint64_t r = 0; r < rows; ++r) {
    for (uint64_t j = 0; j < dof; ++j) {
      const double v = data[r * dof + j];
      if (!(std::abs(v) <= limit))  // false for NaN too
        fail(where, std::string(name) + ": " + row_word + " " + str(r) + " joint " + str(j + 1) +
                        ": " + number_text(v) + " is outside [-" + number_text(limit) + ", " +
                        number_text(limit) + "]");
    }
  }
}

void check_values(const std::string& where, const char* name, const double* data, uint64_t n,
                  double low, double high, bool nan_allowed) {
  if (!data) return;
  for (uint64_t e = 0; e < n; ++e) {
    const double v = data[e];
    if (std::isnan(v) && nan_allowed) continue;
    if (!(v >= low && v <= high))
      fail(where, std::string(name) + ": edge " + str(e) + ": " + number_text(v) + " is outside [" +
                      number_text(low) + ", " + number_text(high) + "]");
  }
}

void check_offsets(const std::string& where, const char* name, const uint64_t* offsets,
                   uint64_t edges, uint64_t rows, const char* rows_name) {
  if (!offsets) return;
  if (offsets[0] != 0)
    fail(where, std::string(name) + ": first value " + str(offsets[0]) + ", expected 0");
  for (uint64_t k = 0; k < edges; ++k)
    if (offsets[k + 1] < offsets[k])
      fail(where, std::string(name) + ": decreases at edge " + str(k) + " (" + str(offsets[k]) +
                      " -> " + str(offsets[k + 1]) + ")");
  if (offsets[edges] != rows)
    fail(where, std::string(name) + ": last value " + str(offsets[edges]) + " does not match the " +
                    str(rows) + " rows of " + rows_name);
}

// count[e] <= bound[e] (or <= the constant when bound is null).
void check_at_most(const std::string& where, const char* name, const uint64_t* count,
                   const char* bound_name, const uint64_t* bound, uint64_t constant, uint64_t n) {
  if (!count) return;
  for (uint64_t e = 0; e < n; ++e) {
    const uint64_t b = bound ? bound[e] : constant;
    if (count[e] > b)
      fail(where, std::string(name) + ": edge " + str(e) + ": " + str(count[e]) + " is more than " +
                      bound_name + " (" + str(b) + ")");
  }
}

void check_perturbation(const BundleArrays& a, const std::string& where) {
  using Id = BundleDatasetId;
  const uint64_t n = a.edges;
  const uint64_t* done = a.of<uint64_t>(Id::Done);
  const uint64_t* valid = a.of<uint64_t>(Id::Valid);
  check_at_most(where, ds::pert_done, done, "perturbations", nullptr, a.perturbations, n);
  check_at_most(where, ds::pert_valid, valid, "done", done, 0, n);
  check_at_most(where, ds::pert_collision, a.of<uint64_t>(Id::Collision), "done", done, 0, n);
  check_at_most(where, ds::pert_lazy, a.of<uint64_t>(Id::Lazy), "valid", valid, 0, n);
  check_at_most(where, ds::transfer_lazy, a.of<uint64_t>(Id::TransferLazy), "valid", valid, 0, n);
  const double inf = HUGE_VAL;
  check_values(where, ds::pert_max_error, a.of<double>(Id::MaxError), n, 0, inf, true);
  check_values(where, ds::transfer_max_error, a.of<double>(Id::TransferMaxError), n, 0, inf, true);
  check_values(where, ds::p_lazy_prop, a.of<double>(Id::PLazyProp), n, 0, 1, false);
  check_values(where, ds::p_collision, a.of<double>(Id::PCollision), n, 0, 1, false);
  check_values(where, ds::p_lazy_prop_transfer, a.of<double>(Id::PLazyPropTransfer), n, 0, 1,
               false);
}

}  // namespace

BundleArrays arrays_of(const Bundle& b) {
  BundleArrays a;
  a.edges = b.size();
  a.dof = static_cast<uint64_t>(b.dof());
  const BundleRows rows = bundle_rows(b);
  a.knot_rows = rows.knots;
  a.sample_rows = rows.samples;
  a.perturbations = b.perturbation.present ? b.perturbation.perturbations : 0;
  for (const BundleDatasetSpec& spec : bundle_datasets()) {
    if (!bundle_has(b, spec)) continue;
    std::visit([&](const auto* data) { a.set(spec.id, data->data()); }, bundle_array(b, spec.id));
  }
  return a;
}

void check_bundle_arrays(const BundleArrays& a, const std::string& where) {
  using Id = BundleDatasetId;
  check_offsets(where, ds::knot_offset, a.of<uint64_t>(Id::KnotOffset), a.edges, a.knot_rows,
                ds::knots);
  check_offsets(where, ds::sample_offset, a.of<uint64_t>(Id::SampleOffset), a.edges, a.sample_rows,
                ds::sample_q);
  check_rows(where, ds::q0, a.of<double>(Id::Q0), a.edges, a.dof, kMaxPosition, "edge");
  check_rows(where, ds::qf, a.of<double>(Id::Qf), a.edges, a.dof, kMaxPosition, "edge");
  check_values(where, ds::duration, a.of<double>(Id::Duration), a.edges, 0, kMaxDuration, false);
  check_values(where, ds::command_duration, a.of<double>(Id::CommandDuration), a.edges, 0,
               kMaxDuration, false);
  check_rows(where, ds::knots, a.of<double>(Id::Knots), a.knot_rows, a.dof, kMaxVelocity, "row");
  check_rows(where, ds::sample_q, a.of<float>(Id::SampleQ), a.sample_rows, a.dof, kMaxPosition,
             "row");
  check_rows(where, ds::sample_dq, a.of<float>(Id::SampleDq), a.sample_rows, a.dof, kMaxVelocity,
             "row");
  check_perturbation(a, where);
}

}  // namespace lazyboe
