#include "lazyboe/bench/report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>

#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/histogram.h"
#include "lazyboe/common/numbers.h"
#include "lazyboe/common/statistics.h"

namespace lazyboe {
namespace {

std::string quoted(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '\n' || c == '\r') c = ' ';
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// Splits one CSV line with RFC 4180 quoting; false for an unterminated quote.
bool split_csv(const std::string& line, std::vector<std::string>& fields) {
  fields.assign(1, "");
  bool in_quotes = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        in_quotes = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      in_quotes = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return !in_quotes;
}

std::string number(double value, const char* format = "%.6g") {
  if (!std::isfinite(value)) return "";
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

double parse_number(const std::string& text, const std::string& where, const std::string& column) {
  if (text.empty()) return std::numeric_limits<double>::quiet_NaN();
  // Plain decimal, finite, >= 0 (times, costs, budgets): "0x10", "inf" and "nan" are refused.
  double value = 0;
  if (!parse_decimal(text, value) || value < 0)
    fail(where, column + ": expected a finite number >= 0, got '" + text + "'");
  return value;
}

uint64_t parse_count(const std::string& text, const std::string& where, const std::string& column) {
  uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size()) {
    fail(where, column + ": expected a whole number >= 0, got '" + text + "'");
  }
  return value;
}

// The int fields of RunRecord (repeat, n_solutions, stops, ...): a larger count would wrap.
int parse_int_count(const std::string& text, const std::string& where, const std::string& column) {
  const uint64_t value = parse_count(text, where, column);
  if (value > static_cast<uint64_t>(std::numeric_limits<int>::max())) {
    fail(where, column + ": " + text + " is outside the accepted range [0, " +
                    std::to_string(std::numeric_limits<int>::max()) + "]");
  }
  return static_cast<int>(value);
}

}  // namespace

const std::vector<std::string>& runs_csv_header() {
  static const std::vector<std::string> header = {
      "planner", "problem", "repeat", "seed", "success", "time_to_first_solution", "best_cost",
      "n_solutions", "nodes", "simulations", "lazy_edges", "collision_checks", "budget", "failure",
      // The returned trajectory's execution and the raw chain's (lazyboe-bench --raw: the same).
      "duration", "stops", "arc_length", "raw_duration", "raw_stops", "post_seconds", "junctions",
      "blends_kept", "shortcuts", "found_by"};
  return header;
}

std::string runs_csv_row(const RunRecord& r, const std::string& problem_id) {
  std::ostringstream row;
  row << quoted(r.planner) << ',' << quoted(problem_id) << ',' << r.repeat << ',' << r.seed << ','
      << (r.success ? 1 : 0) << ',' << number(r.time_to_first_solution, "%.6f") << ','
      << number(r.best_cost, "%.6f") << ',' << r.n_solutions << ',' << r.counters.nodes << ','
      << r.counters.simulations << ',' << r.counters.lazy_edges << ','
      << r.counters.collision_checks << ',' << number(r.budget) << ',' << quoted(r.failure);
  auto count = [](int v) { return v < 0 ? std::string() : std::to_string(v); };
  row << ',' << number(r.duration, "%.3f") << ',' << count(r.stops) << ','
      << number(r.arc_length, "%.6f") << ',' << number(r.raw_duration, "%.3f") << ','
      << count(r.raw_stops) << ',' << number(r.post_seconds, "%.6f") << ',' << count(r.junctions)
      << ',' << count(r.blends_kept) << ',' << count(r.shortcuts) << ',' << quoted(r.found_by);
  return row.str();
}

PartialRunsFile::PartialRunsFile(const std::string& path) : path_(path) {
  std::string bytes;
  {
    std::ifstream existing(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(existing), std::istreambuf_iterator<char>());
  }
  const bool fresh = bytes.empty();
  if (!fresh && bytes.back() != '\n') {
    // A row an interruption cut short (read_runs_csv ignored it): drop it, so the next row
    // starts on a line of its own.
    std::filesystem::resize_file(path, bytes.rfind('\n') + 1);
  }
  file_ = std::fopen(path.c_str(), "a");
  if (!file_) fail(path, "cannot write");
  if (fresh) {
    std::string header;
    for (const std::string& c : runs_csv_header()) header += (header.empty() ? "" : ",") + c;
    std::fprintf(file_, "%s\n", header.c_str());
    std::fflush(file_);
  }
}

PartialRunsFile::~PartialRunsFile() {
  if (file_) std::fclose(file_);
}

void PartialRunsFile::append(const RunRecord& r, const std::string& problem_id) {
  const std::string row = runs_csv_row(r, problem_id) + "\n";
  if (std::fputs(row.c_str(), file_) < 0 || std::fflush(file_) != 0) fail(path_, "cannot write");
}

std::vector<RunRecord> read_runs_csv(const std::string& path,
                                     const std::vector<std::string>& problem_ids) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::vector<std::string> lines;
  for (std::string text; std::getline(in, text);) lines.push_back(text);
  const bool complete_last_line = [&] {
    std::ifstream raw(path, std::ios::binary | std::ios::ate);
    if (raw.tellg() <= 0) return true;
    raw.seekg(-1, std::ios::end);
    return raw.get() == '\n';
  }();
  std::vector<std::string> fields;
  const std::vector<std::string>& header = runs_csv_header();
  if (lines.empty() || !split_csv(lines[0], fields) || fields != header) {
    fail(path + ": line 1", "expected the runs.csv header");
  }
  std::map<std::string, int> index_of;
  for (size_t k = 0; k < problem_ids.size(); ++k) index_of[problem_ids[k]] = static_cast<int>(k);
  std::vector<RunRecord> runs;
  for (size_t k = 1; k < lines.size(); ++k) {
    const std::string where = path + ": line " + std::to_string(k + 1);
    const bool torn = k + 1 == lines.size() && !complete_last_line;
    if (!split_csv(lines[k], fields) || fields.size() != header.size()) {
      if (torn) break;  // the write an interruption cut short
      fail(where, "expected " + std::to_string(header.size()) + " fields");
    }
    if (torn) break;
    RunRecord r;
    r.planner = fields[0];
    const auto problem = index_of.find(fields[1]);
    if (problem == index_of.end()) fail(where, "problem: '" + fields[1] + "' is not in the study");
    r.problem = problem->second;
    r.repeat = parse_int_count(fields[2], where, "repeat");
    r.seed = parse_count(fields[3], where, "seed");
    if (fields[4] != "0" && fields[4] != "1") fail(where, "success: expected 0 or 1");
    r.success = fields[4] == "1";
    r.time_to_first_solution = parse_number(fields[5], where, "time_to_first_solution");
    r.best_cost = parse_number(fields[6], where, "best_cost");
    r.n_solutions = parse_int_count(fields[7], where, "n_solutions");
    r.counters.nodes = parse_count(fields[8], where, "nodes");
    r.counters.simulations = parse_count(fields[9], where, "simulations");
    r.counters.lazy_edges = parse_count(fields[10], where, "lazy_edges");
    r.counters.collision_checks = parse_count(fields[11], where, "collision_checks");
    r.budget = parse_number(fields[12], where, "budget");
    r.failure = fields[13];
    auto count = [&](int k, const char* column) {
      return fields[k].empty() ? -1 : parse_int_count(fields[k], where, column);
    };
    r.duration = parse_number(fields[14], where, "duration");
    r.stops = count(15, "stops");
    r.arc_length = parse_number(fields[16], where, "arc_length");
    r.raw_duration = parse_number(fields[17], where, "raw_duration");
    r.raw_stops = count(18, "raw_stops");
    r.post_seconds = parse_number(fields[19], where, "post_seconds");
    r.junctions = count(20, "junctions");
    r.blends_kept = count(21, "blends_kept");
    r.shortcuts = count(22, "shortcuts");
    r.found_by = fields[23];
    runs.push_back(std::move(r));
  }
  return runs;
}

void write_runs_csv(const std::string& path, const std::vector<RunRecord>& runs,
                    const std::vector<std::string>& problem_ids) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  std::string header;
  for (const std::string& c : runs_csv_header()) header += (header.empty() ? "" : ",") + c;
  out << header << "\n";
  for (const RunRecord& r : runs) out << runs_csv_row(r, problem_ids.at(r.problem)) << "\n";
  file.commit();
}

namespace {

struct PlannerStats {
  size_t runs = 0, successes = 0;
  std::vector<double> ttfs, cost, solutions, simulations;
  // Successful runs: the returned trajectory's execution and the raw chain's.
  std::vector<double> duration, raw_duration, stops, raw_stops, arc_length, post_seconds,
      ttfs_with_post;
  long junctions = 0, blends_kept = 0, shortcuts = 0;
  size_t direct = 0;    // solved by the straight command tried before the search
  size_t waypoint = 0;  // by lazysp's straight commands through one or two waypoints, tried next
};

std::string fixed(double value, int digits) {
  if (!std::isfinite(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

double median_of(const std::vector<double>& v) {
  return v.empty() ? std::numeric_limits<double>::quiet_NaN() : quantiles(v).median;
}
double mean_of(const std::vector<double>& v) {
  return v.empty() ? std::numeric_limits<double>::quiet_NaN() : quantiles(v).mean;
}

std::string test_cell(const std::vector<double>& lazy, const std::vector<double>& other) {
  if (lazy.empty() || other.empty()) return "n/a";
  const MannWhitney t = mann_whitney_u(lazy, other);
  return "U = " + fixed(t.u1, 1) + ", p = " + format_p_value(t.p) + " " + significance_mark(t.p);
}

double success_rate(const PlannerStats& s) {
  return s.runs ? static_cast<double>(s.successes) / s.runs
                : std::numeric_limits<double>::quiet_NaN();
}

// The paper's targets for LazyBoE, each met or not (stats has a "lazyboe" entry with runs).
void write_targets(std::ostream& md, std::map<std::string, PlannerStats>& stats,
                   const std::vector<PlannerSpec>& specs) {
  const PlannerStats& lazy = stats["lazyboe"];
  md << "\n## Targets\n\n";
  auto verdict = [](bool ok) { return ok ? "**met**" : "**not met**"; };
  const double lazy_median = median_of(lazy.ttfs);
  if (stats.count("ompl-sst") && stats["ompl-sst"].runs > 0) {
    const double sst_median = median_of(stats["ompl-sst"].ttfs);
    const double ratio = sst_median / lazy_median;
    md << "- LazyBoE's median time to first solution at least 10x lower than OMPL's SST: ";
    if (std::isfinite(ratio)) {
      md << fixed(lazy_median, 3) << " s against " << fixed(sst_median, 3) << " s, "
         << fixed(ratio, 1) << "x: " << verdict(ratio >= 10) << "\n";
    } else {
      md << "not measurable (no successful run of one of them)\n";
    }
  } else {
    md << "- LazyBoE against OMPL's SST: not measured (ompl-sst not in this study)\n";
  }
  bool best = true;
  std::string worse;
  for (const PlannerSpec& spec : specs) {
    if (spec.name == "lazyboe" || !spec.available || !stats[spec.name].runs) continue;
    if (success_rate(stats[spec.name]) > success_rate(lazy)) {
      best = false;
      worse += (worse.empty() ? "" : ", ") + spec.name;
    }
  }
  md << "- Success rate at least every baseline's and at least 92%: "
     << fixed(100 * success_rate(lazy), 0) << "%" << (best ? "" : " (" + worse + " higher)") << ": "
     << verdict(best && success_rate(lazy) >= 0.92) << "\n";
  if (stats.count("boe") && stats["boe"].runs > 0) {
    const double boe_cost = median_of(stats["boe"].cost), lazy_cost = median_of(lazy.cost);
    md << "- Final cost no worse than BoE's (median): ";
    if (std::isfinite(lazy_cost) && std::isfinite(boe_cost)) {
      md << fixed(lazy_cost, 2) << " rad against " << fixed(boe_cost, 2)
         << " rad: " << verdict(lazy_cost <= boe_cost) << "\n";
    } else {
      md << "not measurable (no successful run of one of them)\n";
    }
  } else {
    md << "- Final cost against BoE: not measured (boe not in this study)\n";
  }
}

// The returned trajectories' execution against the raw chains (issue 14's figures).
void write_execution(std::ostream& md, std::map<std::string, PlannerStats>& stats,
                     const std::vector<PlannerSpec>& specs) {
  md << "\n## Execution\n\n";
  md << "Over the successful runs: the returned trajectory (post-processed: shortcuts and "
        "junction blending, docs/execution.md; the raw chain itself with --raw) against the "
        "raw edge chain. Stops exclude the start and the end. Post-processing runs after the "
        "planner's clock has stopped, outside the budget; our planners hand over their own "
        "simulation of each step, OMPL's do not (their chain is simulated again). Time to an "
        "executable trajectory: time to first solution plus post-processing. Direct: runs a "
        "bundle planner answered with the straight command it tries before searching (none "
        "with --no-direct); waypoint: runs lazysp answered with the straight commands through "
        "one or two sampled waypoints it tries next (none with --no-direct).\n\n";
  md << "| planner | median duration (s) | median raw duration (s) | shorter | median stops | "
        "median raw stops | median arc length (rad) | median raw arc length (rad) | blends kept "
        "| shortcuts | direct | waypoint | median post-processing (s) | median time to an "
        "executable trajectory (s) |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const PlannerSpec& spec : specs) {
    if (!spec.available) continue;
    const PlannerStats& s = stats[spec.name];
    const double d = median_of(s.duration), raw = median_of(s.raw_duration);
    md << "| " << spec.name << " | " << fixed(d, 2) << " | " << fixed(raw, 2) << " | "
       << fixed(100 * (1 - d / raw), 0) << "% | " << fixed(median_of(s.stops), 1) << " | "
       << fixed(median_of(s.raw_stops), 1) << " | " << fixed(median_of(s.arc_length), 2) << " | "
       << fixed(median_of(s.cost), 2) << " | " << s.blends_kept << " / " << s.junctions << " | "
       << s.shortcuts << " | " << s.direct << " | " << s.waypoint << " | "
       << fixed(median_of(s.post_seconds), 4) << " | " << fixed(median_of(s.ttfs_with_post), 4)
       << " |\n";
  }
}

// Each planner's runs gathered for the summary.
std::map<std::string, PlannerStats> planner_stats(const std::vector<RunRecord>& runs) {
  std::map<std::string, PlannerStats> stats;
  for (const RunRecord& r : runs) {
    PlannerStats& s = stats[r.planner];
    ++s.runs;
    s.solutions.push_back(r.n_solutions);
    s.simulations.push_back(static_cast<double>(r.counters.simulations));
    if (!r.success) continue;
    ++s.successes;
    s.ttfs.push_back(r.time_to_first_solution);
    s.cost.push_back(r.best_cost);
    s.duration.push_back(r.duration);
    s.raw_duration.push_back(r.raw_duration);
    s.stops.push_back(r.stops);
    s.raw_stops.push_back(r.raw_stops);
    s.arc_length.push_back(r.arc_length);
    s.post_seconds.push_back(r.post_seconds);
    s.ttfs_with_post.push_back(r.time_to_first_solution + r.post_seconds);
    s.junctions += std::max(0, r.junctions);
    s.blends_kept += std::max(0, r.blends_kept);
    s.shortcuts += std::max(0, r.shortcuts);
    s.direct += r.found_by == "direct";
    s.waypoint += r.found_by == "waypoint" || r.found_by == "two_waypoints";
  }
  return stats;
}

}  // namespace

std::string summary_markdown(const StudyInfo& info, const std::vector<PlannerSpec>& specs,
                             const std::vector<RunRecord>& runs) {
  std::map<std::string, PlannerStats> stats = planner_stats(runs);
  std::ostringstream md;
  md << "# lazyboe-bench summary\n\n";
  md << "- Bundle: `" << info.bundle << "` (" << info.edges << " edges), robot `" << info.robot
     << "`, environment `" << info.environment << "`\n";
  md << "- Problems: " << info.problems << " (" << info.problems_source << "), repeats "
     << info.repeats << ", budget " << fixed(info.budget, 1) << " s per run, study seed "
     << info.seed << ", " << info.jobs << " run(s) in parallel\n";
  if (!info.task.empty()) md << "- Task of every run: " << info.task << "\n";
  if (info.direct >= 0)
    md << "- A single straight command (start to goal, rest to rest, within the bundle's command "
          "limits, every check) solves "
       << info.direct << " of " << info.problems
       << " problems: those need no planning; the bundle planners answer them with that command "
          "before searching (unless --no-direct), and the post-processing's first shortcut "
          "finds them whatever the planner\n";
  md << "- Machine: " << info.machine << "\n";
  md << "- Command: `" << info.command_line << "`\n\n";
  md << "Time to first solution and final cost are over the successful runs; the number of "
        "solutions is over all runs (0 for a failure). A run succeeds when it returns a path "
        "that passes the re-simulation from the exact start with every check.\n\n";

  md << "## Results\n\n";
  md << "| planner | runs | success | median TTFS (s) | mean TTFS (s) | median cost (rad) | "
        "mean cost (rad) | mean solutions | median simulations |\n";
  md << "|---|---|---|---|---|---|---|---|---|\n";
  for (const PlannerSpec& spec : specs) {
    if (!spec.available) {
      md << "| " << spec.name << " | skipped: " << spec.unavailable_reason << " | | | | | | | |\n";
      continue;
    }
    const PlannerStats& s = stats[spec.name];
    md << "| " << spec.name << " | " << s.runs << " | " << fixed(100 * success_rate(s), 0) << "% | "
       << fixed(median_of(s.ttfs), 3) << " | " << fixed(mean_of(s.ttfs), 3) << " | "
       << fixed(median_of(s.cost), 2) << " | " << fixed(mean_of(s.cost), 2) << " | "
       << fixed(mean_of(s.solutions), 2) << " | " << fixed(median_of(s.simulations), 0) << " |\n";
  }

  write_execution(md, stats, specs);

  const bool have_lazy = stats.count("lazyboe") && stats["lazyboe"].runs > 0;
  if (have_lazy) {
    const PlannerStats& lazy = stats["lazyboe"];
    md << "\n## LazyBoE against each baseline\n\n";
    md << "Mann-Whitney U test, two-sided (U of LazyBoE's sample); marks: ns p > 0.05, "
          "* p <= 0.05, ** p <= 0.01, *** p <= 0.001, **** p <= 0.0001.\n\n";
    md << "| baseline | time to first solution | final cost | number of solutions |\n";
    md << "|---|---|---|---|\n";
    for (const PlannerSpec& spec : specs) {
      if (spec.name == "lazyboe" || !spec.available) continue;
      const PlannerStats& s = stats[spec.name];
      md << "| " << spec.name << " | " << test_cell(lazy.ttfs, s.ttfs) << " | "
         << test_cell(lazy.cost, s.cost) << " | " << test_cell(lazy.solutions, s.solutions)
         << " |\n";
    }

    write_targets(md, stats, specs);
  }

  bool any_skipped = false;
  for (const PlannerSpec& spec : specs) any_skipped |= !spec.available;
  if (any_skipped) {
    md << "\n## Skipped planners\n\n";
    for (const PlannerSpec& spec : specs) {
      if (!spec.available) md << "- " << spec.name << ": " << spec.unavailable_reason << "\n";
    }
  }
  return md.str();
}

}  // namespace lazyboe
