#include "lazyboe/bundle/bundle_format.h"

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"

namespace lazyboe {

namespace ds = bundle_dataset;
using Id = BundleDatasetId;

const char* element_type_name(ElementType type) {
  switch (type) {
    case ElementType::F64:
      return "float64";
    case ElementType::U64:
      return "uint64";
    case ElementType::F32:
      return "float32";
  }
  return "?";
}

const std::array<BundleDatasetSpec, kBundleDatasetCount>& bundle_datasets() {
  using E = ElementType;
  using R = RowRule;
  using P = Presence;
  static const std::array<BundleDatasetSpec, kBundleDatasetCount> table = {{
      {Id::Q0, ds::q0, "q0", E::F64, R::Edges, true, P::Always, true},
      {Id::Qf, ds::qf, "qf", E::F64, R::Edges, true, P::Always, true},
      {Id::Duration, ds::duration, "duration", E::F64, R::Edges, false, P::Always, true},
      {Id::CommandDuration, ds::command_duration, "command_duration", E::F64, R::Edges, false,
       P::Always, true},
      {Id::Attempt, ds::attempt, "attempt", E::U64, R::Edges, false, P::Always, false},
      {Id::KnotOffset, ds::knot_offset, "knot_offset", E::U64, R::EdgesPlusOne, false, P::Always,
       true},
      {Id::SampleOffset, ds::sample_offset, "sample_offset", E::U64, R::EdgesPlusOne, false,
       P::Always, true},
      {Id::Knots, ds::knots, "knots", E::F64, R::KnotRows, true, P::Always, true},
      {Id::SampleQ, ds::sample_q, "sample_q", E::F32, R::SampleRows, true, P::Always, true},
      {Id::SampleDq, ds::sample_dq, "sample_dq", E::F32, R::SampleRows, true, P::Always, false},
      {Id::Done, ds::pert_done, "perturbation.done", E::U64, R::Edges, false, P::Perturbation,
       false},
      {Id::Valid, ds::pert_valid, "perturbation.valid", E::U64, R::Edges, false, P::Perturbation,
       false},
      {Id::Lazy, ds::pert_lazy, "perturbation.lazy", E::U64, R::Edges, false, P::Perturbation,
       false},
      {Id::Collision, ds::pert_collision, "perturbation.collision", E::U64, R::Edges, false,
       P::Perturbation, false},
      {Id::MaxError, ds::pert_max_error, "perturbation.max_error", E::F64, R::Edges, false,
       P::Perturbation, false},
      {Id::PLazyProp, ds::p_lazy_prop, "perturbation.p_lazy_prop", E::F64, R::Edges, false,
       P::Perturbation, true},
      {Id::PCollision, ds::p_collision, "perturbation.p_collision", E::F64, R::Edges, false,
       P::Perturbation, true},
      {Id::TransferLazy, ds::transfer_lazy, "perturbation.transfer_lazy", E::U64, R::Edges, false,
       P::Transfer, false},
      {Id::TransferMaxError, ds::transfer_max_error, "perturbation.transfer_max_error", E::F64,
       R::Edges, false, P::Transfer, true},
      {Id::PLazyPropTransfer, ds::p_lazy_prop_transfer, "perturbation.p_lazy_prop_transfer", E::F64,
       R::Edges, false, P::Transfer, true},
  }};
  return table;
}

const BundleDatasetSpec& bundle_dataset_spec(BundleDatasetId id) {
  return bundle_datasets()[static_cast<size_t>(id)];
}

BundleRows bundle_rows(const Bundle& b) {
  const uint64_t dof = b.dof() > 0 ? static_cast<uint64_t>(b.dof()) : 1;
  return {b.size(), b.knots.size() / dof, b.sample_q.size() / dof};
}

uint64_t dataset_rows(const BundleDatasetSpec& spec, const BundleRows& rows) {
  switch (spec.rows) {
    case RowRule::Edges:
      return rows.edges;
    case RowRule::EdgesPlusOne:
      return rows.edges + 1;
    case RowRule::KnotRows:
      return rows.knots;
    case RowRule::SampleRows:
      return rows.samples;
  }
  return 0;
}

std::vector<uint64_t> dataset_shape(const BundleDatasetSpec& spec, const BundleRows& rows,
                                    uint64_t dof) {
  if (spec.per_joint) return {dataset_rows(spec, rows), dof};
  return {dataset_rows(spec, rows)};
}

std::string shape_rule_text(const BundleDatasetSpec& spec) {
  static const char* const first[] = {"N", "N + 1", "K", "S"};
  return std::string(first[static_cast<int>(spec.rows)]) + (spec.per_joint ? " x dof" : "");
}

BundleArrayRef bundle_array(Bundle& b, BundleDatasetId id) {
  Perturbation& p = b.perturbation;
  switch (id) {
    case Id::Q0:
      return &b.q0;
    case Id::Qf:
      return &b.qf;
    case Id::Duration:
      return &b.duration;
    case Id::CommandDuration:
      return &b.command_duration;
    case Id::Attempt:
      return &b.attempt;
    case Id::KnotOffset:
      return &b.knot_offset;
    case Id::SampleOffset:
      return &b.sample_offset;
    case Id::Knots:
      return &b.knots;
    case Id::SampleQ:
      return &b.sample_q;
    case Id::SampleDq:
      return &b.sample_dq;
    case Id::Done:
      return &p.done;
    case Id::Valid:
      return &p.valid;
    case Id::Lazy:
      return &p.lazy;
    case Id::Collision:
      return &p.collision;
    case Id::MaxError:
      return &p.max_error;
    case Id::PLazyProp:
      return &p.p_lazy_prop;
    case Id::PCollision:
      return &p.p_collision;
    case Id::TransferLazy:
      return &p.transfer_lazy;
    case Id::TransferMaxError:
      return &p.transfer_max_error;
    case Id::PLazyPropTransfer:
      return &p.p_lazy_prop_transfer;
  }
  return &b.q0;  // unreachable: every id is listed
}

ConstBundleArrayRef bundle_array(const Bundle& b, BundleDatasetId id) {
  // One switch for both: the mutable overload only hands out the member's address.
  return std::visit([](auto* data) -> ConstBundleArrayRef { return data; },
                    bundle_array(const_cast<Bundle&>(b), id));
}

bool present_with(const BundleDatasetSpec& spec, bool perturbation, bool transfer) {
  switch (spec.presence) {
    case Presence::Always:
      return true;
    case Presence::Perturbation:
      return perturbation;
    case Presence::Transfer:
      return perturbation && transfer;
  }
  return false;
}

bool bundle_has(const Bundle& b, const BundleDatasetSpec& spec) {
  return present_with(spec, b.perturbation.present, b.perturbation.has_transfer);
}

}  // namespace lazyboe
