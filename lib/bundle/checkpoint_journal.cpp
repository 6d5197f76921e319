#include "lazyboe/bundle/checkpoint_journal.h"

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/perturbation.h"
#include "lazyboe/common/bytes.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"

namespace lazyboe {
namespace {

constexpr uint32_t kJournalVersion = 1;
constexpr uint32_t kBuildKind = 1, kPerturbKind = 2;

template <class T>
void hash_vector(Fnv1a64& h, const std::vector<T>& v) {
  const uint64_t n = v.size();
  h.update(&n, sizeof n);
  h.update(v.data(), v.size() * sizeof(T));
}

template <class T>
void hash_value(Fnv1a64& h, const T& v) {
  h.update(&v, sizeof v);
}

void hash_string(Fnv1a64& h, const std::string& s) {
  hash_value<uint64_t>(h, s.size());
  h.update(s);
}

// The settings every edge depends on (what check_resume_compatible compares).
void hash_settings(Fnv1a64& h, const BundleHeader& b) {
  hash_string(h, b.robot_hash);
  hash_string(h, b.env_hash);
  hash_value(h, b.seed);
  hash_value(h, b.dof);
  hash_vector(h, b.region_lower);
  hash_vector(h, b.region_upper);
  for (double v : {b.min_duration, b.max_duration, b.knot_interval, b.velocity_scale, b.limit_scale,
                   b.control_rate, b.sample_interval, b.design_theta})
    hash_value(h, v);
  hash_string(h, b.integrator);
  hash_value(h, b.substeps);
}

// The first record: which journal this is and the state it continues.
std::string base_record(uint32_t kind, uint64_t edges, uint64_t attempts, uint64_t identity) {
  std::string r;
  ByteWriter w(r);
  w.put(kind);
  w.put(kJournalVersion);
  w.put(edges);
  w.put(attempts);
  w.put(identity);
  return r;
}

std::string build_base_record(const Bundle& b) {
  Fnv1a64 h;
  hash_settings(h, b.header);
  hash_vector(h, b.attempt);
  hash_vector(h, b.knot_offset);
  hash_vector(h, b.sample_offset);
  return base_record(kBuildKind, b.size(), b.header.attempts, h.value());
}

// Describes a base record for the note on an ignored journal.
std::string describe_base(const std::string& record) {
  ByteReader r(record.data(), record.size(), "journal");
  const uint32_t kind = r.get<uint32_t>();
  r.get<uint32_t>();
  const uint64_t edges = r.get<uint64_t>();
  return std::string(kind == kBuildKind ? "a build" : "a perturbation analysis") +
         " continuing a bundle of " + std::to_string(edges) + " edges";
}

// ---- the build's records ----

template <class T>
void put_tail(ByteWriter& w, const std::vector<T>& v, size_t from) {
  w.put_array(v.data() + from, v.size() - from);
}

std::string build_record(const Bundle& b, uint64_t first) {
  const size_t dof = static_cast<size_t>(b.dof());
  std::string r;
  r.reserve(64 + 8 * (b.q0.size() - first * dof) * 3);
  ByteWriter w(r);
  w.put<uint64_t>(first);
  put_tail(w, b.q0, first * dof);
  put_tail(w, b.qf, first * dof);
  put_tail(w, b.duration, first);
  put_tail(w, b.command_duration, first);
  put_tail(w, b.attempt, first);
  put_tail(w, b.knot_offset, first + 1);
  put_tail(w, b.knots, b.knot_offset[first] * dof);
  put_tail(w, b.sample_offset, first + 1);
  put_tail(w, b.sample_q, b.sample_offset[first] * dof);
  put_tail(w, b.sample_dq, b.sample_offset[first] * dof);
  const BundleHeader& h = b.header;
  w.put(h.target_edges);
  w.put(h.attempts);
  w.put(h.valid);
  w.put(h.start_resamples);
  w.put(h.simulated_seconds);
  w.put(h.wall_seconds);
  w.put<uint64_t>(h.rejected.size());
  for (const auto& [reason, count] : h.rejected) {
    w.put_string(reason);
    w.put(count);
  }
  return r;
}

void apply_build_record(Bundle& b, const std::string& record, const std::string& where) {
  ByteReader r(record.data(), record.size(), where);
  const uint64_t first = r.get<uint64_t>();
  if (first != b.size())
    fail(where, "checkpoint record starts at edge " + std::to_string(first) + ", expected " +
                    std::to_string(b.size()));
  r.append_vector(b.q0);
  r.append_vector(b.qf);
  r.append_vector(b.duration);
  r.append_vector(b.command_duration);
  r.append_vector(b.attempt);
  r.append_vector(b.knot_offset);
  r.append_vector(b.knots);
  r.append_vector(b.sample_offset);
  r.append_vector(b.sample_q);
  r.append_vector(b.sample_dq);
  BundleHeader& h = b.header;
  h.target_edges = r.get<uint64_t>();
  h.attempts = r.get<uint64_t>();
  h.valid = r.get<uint64_t>();
  h.start_resamples = r.get<uint64_t>();
  h.simulated_seconds = r.get<double>();
  h.wall_seconds = r.get<double>();
  const uint64_t reasons = r.get<uint64_t>();
  h.rejected.clear();
  for (uint64_t i = 0; i < reasons; ++i) {
    const std::string reason = r.get_string();
    h.rejected[reason] = r.get<uint64_t>();
  }
  if (!r.at_end()) fail(where, "checkpoint record: unexpected bytes at its end");
}

// A journal that does not belong to the file beside it is removed, saying why.
void drop_journal(const std::string& journal, const std::string& why, JournalReplay* replay) {
  ::unlink(journal.c_str());
  replay->note = journal + ": ignored and removed (" + why + ")";
}

}  // namespace

std::string build_journal_path(const std::string& p) { return p + ".build-journal"; }
std::string perturb_journal_path(const std::string& p) { return p + ".perturb-journal"; }

// ---- BuildCheckpoints ----

Bundle BuildCheckpoints::load(JournalReplay* replay) {
  JournalReplay local;
  if (!replay) replay = &local;
  Bundle b = read_bundle(path_);
  base_record_ = build_base_record(b);
  saved_edges_ = b.size();
  const std::string jpath = build_journal_path(path_);
  const JournalContents j = read_journal(jpath);
  replay->found = j.exists;
  if (!j.exists) return b;
  if (!j.valid_start || j.records.empty()) {
    drop_journal(jpath, "not a checkpoint journal, or torn before its first record", replay);
    return b;
  }
  if (j.records[0] != base_record_) {
    drop_journal(jpath, "it continues " + describe_base(j.records[0]) + ", not this file", replay);
    return b;
  }
  const std::string where = jpath;
  for (size_t i = 1; i < j.records.size(); ++i) apply_build_record(b, j.records[i], where);
  check_bundle(b, where);
  replay->applied = true;
  replay->records = j.records.size() - 1;
  replay->ignored_bytes = j.ignored_bytes;
  if (replay->records > 0) b.perturbation = Perturbation{};  // edges were added after the base
  b.header.complete = false;
  journal_ = JournalWriter::reopen(jpath, j.valid_bytes);
  saved_edges_ = b.size();
  return b;
}

void BuildCheckpoints::save(const Bundle& b) {
  if (base_record_.empty()) {
    // A fresh build: its first checkpoint is a whole (small) bundle file, the base.
    ::unlink(build_journal_path(path_).c_str());  // a stale one (--force)
    write_bundle(path_, b);
    crash_point("base-written");
    base_record_ = build_base_record(b);
    saved_edges_ = b.size();
  }
  if (!journal_.is_open())
    journal_ = JournalWriter::create(build_journal_path(path_), base_record_);
  journal_.append(build_record(b, saved_edges_));
  saved_edges_ = b.size();
}

void BuildCheckpoints::finish(const Bundle& b) {
  write_bundle(path_, b);
  crash_point("final-written");
  if (journal_.is_open()) {
    journal_.remove();
  } else {
    ::unlink(build_journal_path(path_).c_str());  // a stale one: it no longer matches
  }
}

// ---- PerturbCheckpoints ----

namespace {

std::string perturb_base_record(const Bundle& b, const PerturbSettings& s) {
  const Perturbation& p = b.perturbation;
  Fnv1a64 h;
  hash_settings(h, b.header);
  hash_vector(h, b.attempt);
  hash_vector(h, b.q0);
  hash_vector(h, b.qf);
  hash_vector(h, b.knot_offset);
  hash_value(h, s.theta);
  hash_value(h, s.perturbations);
  hash_value(h, s.seed);
  hash_value(h, p.has_transfer);
  hash_vector(h, p.done);
  hash_vector(h, p.valid);
  hash_vector(h, p.lazy);
  hash_vector(h, p.collision);
  hash_vector(h, p.max_error);
  hash_vector(h, p.transfer_lazy);
  hash_vector(h, p.transfer_max_error);
  hash_value(h, p.simulated_seconds);
  return base_record(kPerturbKind, b.size(), b.header.attempts, h.value());
}

std::string perturb_record(const Bundle& b, const std::vector<size_t>& edges) {
  const Perturbation& p = b.perturbation;
  std::string r;
  r.reserve(32 + edges.size() * 88);
  ByteWriter w(r);
  w.put(p.simulated_seconds);
  w.put(p.wall_seconds);
  w.put<uint64_t>(edges.size());
  for (size_t e : edges) {
    w.put<uint64_t>(e);
    w.put(p.done[e]);
    w.put(p.valid[e]);
    w.put(p.lazy[e]);
    w.put(p.collision[e]);
    w.put(p.max_error[e]);
    w.put(p.p_lazy_prop[e]);
    w.put(p.p_collision[e]);
    w.put(p.transfer_lazy[e]);
    w.put(p.transfer_max_error[e]);
    w.put(p.p_lazy_prop_transfer[e]);
  }
  return r;
}

void apply_perturb_record(Bundle& b, const std::string& record, const std::string& where) {
  Perturbation& p = b.perturbation;
  ByteReader r(record.data(), record.size(), where);
  p.simulated_seconds = r.get<double>();
  p.wall_seconds = r.get<double>();
  const uint64_t count = r.get<uint64_t>();
  for (uint64_t i = 0; i < count; ++i) {
    const uint64_t e = r.get<uint64_t>();
    if (e >= b.size()) fail(where, "checkpoint record names edge " + std::to_string(e));
    p.done[e] = r.get<uint64_t>();
    p.valid[e] = r.get<uint64_t>();
    p.lazy[e] = r.get<uint64_t>();
    p.collision[e] = r.get<uint64_t>();
    p.max_error[e] = r.get<double>();
    p.p_lazy_prop[e] = r.get<double>();
    p.p_collision[e] = r.get<double>();
    p.transfer_lazy[e] = r.get<uint64_t>();
    p.transfer_max_error[e] = r.get<double>();
    p.p_lazy_prop_transfer[e] = r.get<double>();
  }
  if (!r.at_end()) fail(where, "checkpoint record: unexpected bytes at its end");
}

}  // namespace

JournalReplay PerturbCheckpoints::resume(Bundle& b, const PerturbSettings& s) {
  JournalReplay replay;
  base_record_ = perturb_base_record(b, s);
  const std::string jpath = perturb_journal_path(path_);
  const JournalContents j = read_journal(jpath);
  replay.found = j.exists;
  if (!j.exists) return replay;
  if (!j.valid_start || j.records.empty()) {
    drop_journal(jpath, "not a checkpoint journal, or torn before its first record", &replay);
    return replay;
  }
  if (j.records[0] != base_record_) {
    drop_journal(jpath,
                 "it continues " + describe_base(j.records[0]) +
                     " with other settings or an earlier analysis, not this run",
                 &replay);
    return replay;
  }
  for (size_t i = 1; i < j.records.size(); ++i) apply_perturb_record(b, j.records[i], jpath);
  Perturbation& p = b.perturbation;
  p.complete =
      std::all_of(p.done.begin(), p.done.end(), [&](uint64_t d) { return d >= s.perturbations; });
  replay.applied = true;
  replay.records = j.records.size() - 1;
  replay.ignored_bytes = j.ignored_bytes;
  journal_ = JournalWriter::reopen(jpath, j.valid_bytes);
  return replay;
}

void PerturbCheckpoints::save(const Bundle& b, const std::vector<size_t>& edges) {
  if (base_record_.empty()) fail(path_, "PerturbCheckpoints::resume was not called");
  if (!journal_.is_open())
    journal_ = JournalWriter::create(perturb_journal_path(path_), base_record_);
  journal_.append(perturb_record(b, edges));
}

void PerturbCheckpoints::finish(const Bundle& b) {
  write_bundle(path_, b);
  crash_point("final-written");
  if (journal_.is_open()) {
    journal_.remove();
  } else {
    ::unlink(perturb_journal_path(path_).c_str());
  }
}

}  // namespace lazyboe
