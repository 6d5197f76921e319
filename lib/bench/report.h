// The study's files: runs.csv (one row per planner, problem and repeat), its append-only
// partial twin that survives an interrupted study, and summary.md (per-planner statistics,
// Mann-Whitney U tests of LazyBoE against each baseline, the performance targets).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "lazyboe/bench/study.h"

namespace lazyboe {

// Column names of runs.csv, in order.
const std::vector<std::string>& runs_csv_header();

// One runs.csv line (no newline); text fields are quoted when they need it.
std::string runs_csv_row(const RunRecord& r, const std::string& problem_id);

// Appends rows as runs finish (flushed line by line), so a crash loses at most the runs in
// progress. Opening an existing file keeps its rows (resume).
class PartialRunsFile {
 public:
  explicit PartialRunsFile(const std::string& path);
  ~PartialRunsFile();
  PartialRunsFile(const PartialRunsFile&) = delete;
  PartialRunsFile& operator=(const PartialRunsFile&) = delete;
  void append(const RunRecord& r, const std::string& problem_id);

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

// Rows of a runs.csv or partial file, with problem ids mapped back to indices by `problem_ids`.
// A torn last line (an interrupted write) is ignored; any other malformed line is an error
// naming the file and line.
std::vector<RunRecord> read_runs_csv(const std::string& path,
                                     const std::vector<std::string>& problem_ids);

// Writes runs.csv (temporary file and rename).
void write_runs_csv(const std::string& path, const std::vector<RunRecord>& runs,
                    const std::vector<std::string>& problem_ids);

struct StudyInfo {
  std::string bundle, robot, environment, command_line, machine, problems_source;
  std::string task;  // every run's task as given (payload, end-effector limits); "": none
  size_t edges = 0;
  int problems = 0, repeats = 0, jobs = 0;
  double budget = 0;
  uint64_t seed = 0;
  int direct = -1;  // problems one direct command solves (solved_by_direct_command); -1: unknown
};

// summary.md as text: the planners in `specs` order, unavailable ones listed as skipped.
std::string summary_markdown(const StudyInfo& info, const std::vector<PlannerSpec>& specs,
                             const std::vector<RunRecord>& runs);

}  // namespace lazyboe
