// Incremental, crash-safe checkpoints of lazyboe-build and lazyboe-perturb (schemas/bundle.md,
// "Checkpoints"). The bundle file at the output path is the *base*: a complete, valid bundle
// file written whole (an earlier state of the run, or the file the run started from). The
// journal beside it ("<path>.build-journal", "<path>.perturb-journal"; lib/common/journal.h)
// holds what was done since, one checksummed record per checkpoint, so a checkpoint costs time
// proportional to the work since the previous one. The run's last save (complete, or stopped
// by a signal) writes the whole bundle file as before and then deletes the journal, so the
// finished file is the same bytes as a run without checkpoints.
//
// The journal's first record names its base (edge count, attempts and a hash of the edges
// and settings); a journal whose base is not the file beside it (left behind by a run killed
// after its final rename, or by another build) is ignored and removed, saying so.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/common/journal.h"

namespace lazyboe {

struct PerturbSettings;

std::string build_journal_path(const std::string& bundle_path);
std::string perturb_journal_path(const std::string& bundle_path);

// What a resume found beside the bundle file.
struct JournalReplay {
  bool found = false;          // a journal file was there
  bool applied = false;        // it belonged to this bundle and its records were applied
  uint64_t records = 0;        // checkpoint records applied
  uint64_t ignored_bytes = 0;  // a torn last record (a kill during a checkpoint), dropped
  std::string note;            // why a journal was ignored; "" otherwise
};

class BuildCheckpoints {
 public:
  explicit BuildCheckpoints(std::string path) : path_(std::move(path)) {}
  // Resume: reads the bundle file and applies a journal made for it. `replay` says what was
  // found. The file read is this run's base until save() writes a new one.
  Bundle load(JournalReplay* replay);
  // A checkpoint. The first of a fresh build writes the whole bundle so far as the base and
  // starts the journal; every later one appends the edges since the previous one.
  void save(const Bundle& b);
  // The last save: the whole bundle file (write_bundle), then the journal is deleted.
  void finish(const Bundle& b);

 private:
  std::string path_;
  JournalWriter journal_;
  std::string base_record_;  // the journal's first record, once there is a base
  uint64_t saved_edges_ = 0;
};

class PerturbCheckpoints {
 public:
  explicit PerturbCheckpoints(std::string path) : path_(std::move(path)) {}
  // After prepare_perturbation: applies a journal made for this bundle, prepared for these
  // settings (its per-edge counts, probabilities and totals), and recomputes `complete`.
  JournalReplay resume(Bundle& b, const PerturbSettings& s);
  // A checkpoint: appends the results of `edges` (finished since the previous save).
  void save(const Bundle& b, const std::vector<size_t>& edges);
  // The last save: the whole bundle file, then the journal is deleted.
  void finish(const Bundle& b);

 private:
  std::string path_;
  JournalWriter journal_;
  std::string base_record_;
};

}  // namespace lazyboe
