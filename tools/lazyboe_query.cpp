// lazyboe-query: open a bundle once (memory-mapped) and answer a batch of planning queries
// (JSON Lines) with LazyBoE and its baselines; every returned trajectory is re-simulated and
// re-validated end to end.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>

#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/histogram.h"
#include "lazyboe/common/process_memory.h"
#include "lazyboe/io/query_io.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/registry.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;

struct Options {
  std::string bundle_path, queries_path, out_path = "-", trajectories = "none", trajectory_dir;
  std::string robot_path, env_path;
  int jobs = 1, sim_threads = 0;
  double sample_interval = 0.01;
  bool control_rate = false, raw = false;
  int shortcut_attempts = ExecutionOptions{}.shortcut_attempts;
  bool no_mmap = false, quiet = false;
};

struct Outcome {
  std::string planner;
  bool success = false;
  double ttfs = 0, cost = 0;
  std::string failure;  // why there is no solution
  bool error = false;
};

// What every query of a run shares.
struct Job {
  const PlanningSession& session;
  QueryDefaults defaults;  // with what to return: the flags, unless a query says otherwise
  TrajectoryOutput mode = TrajectoryOutput::None;
  std::string trajectory_dir;
};

void add_options(CLI::App& app, Options& o) {
  // The flag's callback runs before CLI11 checks the required options: it needs neither.
  app.add_flag_callback(
      "--list-planners",
      [] {
        std::fputs(planner_list_text().c_str(), stdout);
        throw CLI::Success();
      },
      "List the planners, what they need and their parameters, and exit");
  app.add_option("--bundle", o.bundle_path,
                 "Bundle file (HDF5), with its perturbation analysis for lazyboe")
      ->required();
  app.add_option("--queries", o.queries_path,
                 "Queries, one JSON object per line; - for standard input")
      ->required();
  app.add_option("--out", o.out_path, "Results, one JSON object per line; - for standard output")
      ->capture_default_str();
  app.add_option("--jobs", o.jobs, "Queries planned in parallel")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--sim-threads", o.sim_threads,
                 "Threads simulating one BoE/LazyBoE query's edges in parallel (the answers do "
                 "not depend on it); 0: the cores left per job")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--trajectories", o.trajectories,
                 "none, inline (in each result) or csv (files in --trajectory-dir)")
      ->capture_default_str();
  app.add_option("--trajectory-dir", o.trajectory_dir, "Directory for --trajectories csv");
  app.add_option("--sample-interval", o.sample_interval,
                 "Trajectory sample spacing, s (a query's \"sample_interval\" overrides it)")
      ->capture_default_str()
      ->check(real_in({0, 1e3, true}, " s"));
  app.add_flag("--control-rate", o.control_rate,
               "Sample every control tick (1 kHz for the Panda): --sample-interval 0.001");
  app.add_flag("--raw", o.raw,
               "Return the planner's edge chain as it is (a stop at rest after every step), "
               "without shortcutting and junction blending (a query's \"raw\" overrides it)");
  app.add_option("--shortcut-attempts", o.shortcut_attempts,
                 "Post-processing budget: direct commands tried per path (0: no shortcutting)")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--robot", o.robot_path, "Robot config (default: the bundle's)");
  app.add_option("--env", o.env_path,
                 "Environment the queries are planned in (default: the bundle's own; any "
                 "scene for the bundle's robot; a query's \"scene\" overrides it)");
  app.add_flag("--no-mmap", o.no_mmap, "Read the bundle into memory instead of mapping it");
  app.add_flag("--quiet", o.quiet, "No summary on stderr");
}

TrajectoryOutput trajectory_mode(const Options& o) {
  if (o.trajectories == "inline") return TrajectoryOutput::Inline;
  if (o.trajectories == "csv") {
    if (o.trajectory_dir.empty()) fail("--trajectory-dir", "required with --trajectories csv");
    std::filesystem::create_directories(o.trajectory_dir);
    return TrajectoryOutput::Csv;
  }
  if (o.trajectories != "none") fail("--trajectories", "expected none, inline or csv");
  return TrajectoryOutput::None;
}

void report_load(const Options& o, const PlanningSession& session) {
  if (o.quiet) return;
  const BundleView& bundle = session.bundle;
  for (const std::string& w : bundle.warnings())
    std::fprintf(stderr, "lazyboe-query: warning: %s\n", w.c_str());
  std::fprintf(
      stderr, "lazyboe-query: %s: %zu edges loaded in %.3f s (%s), resident memory %.0f MiB\n",
      o.bundle_path.c_str(), bundle.size(), session.load_seconds,
      bundle.memory_mapped() ? "memory-mapped" : "read into memory", resident_memory_mib());
  std::fprintf(stderr, "lazyboe-query: k-d trees %s\n", session.indexes.source.c_str());
  std::fprintf(stderr, "lazyboe-query: workspace index %s\n", session.workspace.source.c_str());
  if (const EdgeMarks* marks = session.world().edge_marks.get())
    std::fprintf(
        stderr, "lazyboe-query: scene %s: %zu of %zu edges may collide (marked in %.1f ms)\n",
        session.world().env.name.c_str(), marks->marked, bundle.size(), 1e3 * marks->seconds);
}

// A query id names its trajectory file: it must stay inside --trajectory-dir.
bool usable_file_name(const std::string& id) {
  return !id.empty() && id != "." && id != ".." && id.find('/') == std::string::npos &&
         id.find('\0') == std::string::npos;
}

// One query line: its result line, and what the summary needs. Nothing escapes it (it runs
// inside an OpenMP job).
std::pair<std::string, Outcome> answer(const Job& job, const std::string& text, int line,
                                       SimulatorWorkspace& ws, RolloutPool& pool) {
  std::string id;
  Outcome o;
  nlohmann::json j;
  try {
    const PlanningSession& session = job.session;
    const Query q = parse_query(text, line, session.sim(), ws, job.defaults, id, &session.scenes);
    o.planner = q.request.planner;
    if (job.mode == TrajectoryOutput::Csv && !usable_file_name(q.id)) {
      fail("line " + std::to_string(line) + ": id",
           "'" + q.id + "' cannot name a file in --trajectory-dir (no '/', not . or ..)");
    }
    const PlanningWorld& world = q.world ? *q.world : session.world();
    const PlanAnswer a = answer_request(session.context(world), q.request, ws, &pool);
    const PlanResult& r = a.result;
    std::string csv;
    if (r.success && job.mode == TrajectoryOutput::Csv) {
      csv = (std::filesystem::path(job.trajectory_dir) / (q.id + ".csv")).string();
      write_trajectory_csv(csv, a.trajectory);
    }
    j = result_json(q, a, world, job.mode, csv);
    o.success = r.success;
    o.ttfs = r.time_to_first_solution;
    o.cost = r.success ? a.trajectory.cost : 0;
    o.failure = r.failure;
  } catch (const std::exception& e) {  // Error, or anything else: never out of a job
    j = error_json(id, line, o.planner, e.what());
    o.error = true;
  }
  return std::make_pair(j.dump(), o);
}

// Streaming: one result per query as soon as it is ready.
std::vector<Outcome> answer_stream(const Job& job, std::ostream& out, int sim_threads) {
  std::vector<Outcome> outcomes;
  SimulatorWorkspace ws(job.session.sim());
  RolloutPool pool(job.session.sim(), sim_threads);
  std::string text;
  int line = 0;
  while (std::getline(std::cin, text)) {
    ++line;
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    auto [json, o] = answer(job, text, line, ws, pool);
    out << json << "\n" << std::flush;
    outcomes.push_back(o);
  }
  return outcomes;
}

// A file: `jobs` queries at a time, results in input order.
// A JSON array (pretty-printed or not), or an object pretty-printed over several lines, is not
// JSON Lines: one error for the file that says how to convert it, not one per line.
void refuse_non_json_lines(const std::string& path,
                           const std::vector<std::pair<int, std::string>>& lines) {
  if (lines.empty()) return;
  const std::string& first = lines.front().second;
  const std::string where = "line " + std::to_string(lines.front().first) + ": ";
  const char opening = first[first.find_first_not_of(" \t\r")];
  if (opening == '[') {
    fail(path, where +
                   "a JSON array; a query file is JSON Lines, one query object per line (jq -c "
                   "'.[]' FILE converts an array)");
  }
  if (opening != '{' || nlohmann::json::accept(first)) return;
  std::string object = first;
  for (size_t k = 1; k < lines.size() && k < 200; ++k) {  // the first object's end, if near
    object += "\n" + lines[k].second;
    if (!nlohmann::json::accept(object)) continue;
    fail(path, where + "a JSON object over lines " + std::to_string(lines.front().first) + "-" +
                   std::to_string(lines[k].first) +
                   "; a query file is JSON Lines, one query object per line (jq -c . FILE "
                   "converts pretty-printed objects)");
  }
}

std::vector<Outcome> answer_file(const Job& job, const std::string& path, std::ostream& out,
                                 int jobs, int sim_threads) {
  require_input_file(path, "--queries");
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::vector<std::pair<int, std::string>> lines;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.find_first_not_of(" \t\r") != std::string::npos) lines.emplace_back(line, text);
  }
  refuse_non_json_lines(path, lines);
  std::vector<Outcome> outcomes(lines.size());
  std::vector<SimulatorWorkspace> workspaces;
  std::vector<std::unique_ptr<RolloutPool>> pools;  // not movable: they own threads
  for (int t = 0; t < jobs; ++t) {
    workspaces.emplace_back(job.session.sim());
    pools.push_back(std::make_unique<RolloutPool>(job.session.sim(), sim_threads));
  }
#pragma omp parallel for num_threads(jobs) schedule(dynamic, 1) ordered
  for (long k = 0; k < static_cast<long>(lines.size()); ++k) {
    const int t = omp_get_thread_num();
    // Not a structured binding: clang cannot use one inside the ordered region.
    const auto answered = answer(job, lines[k].second, lines[k].first, workspaces[t], *pools[t]);
    outcomes[k] = answered.second;
#pragma omp ordered
    { out << answered.first << "\n" << std::flush; }
  }
  return outcomes;
}

void print_summary(const std::vector<Outcome>& outcomes) {
  std::map<std::string, std::vector<const Outcome*>> by_planner;
  size_t errors = 0;
  for (const Outcome& o : outcomes) {
    if (o.error)
      ++errors;
    else
      by_planner[o.planner].push_back(&o);
  }
  std::fprintf(stderr, "%-11s %7s %7s %8s %14s %14s %10s\n", "planner", "queries", "solved",
               "success", "median TTFS s", "mean TTFS s", "mean cost");
  for (const auto& [name, list] : by_planner) {
    std::vector<double> ttfs, cost;
    std::map<std::string, size_t> failures;
    for (const Outcome* o : list) {
      if (!o->success) {  // by kind: the text before a query's own figures in parentheses
        ++failures[o->failure.substr(0, o->failure.find(" ("))];
        continue;
      }
      ttfs.push_back(o->ttfs);
      cost.push_back(o->cost);
    }
    // One decimal, rounded down: 2999 of 3000 is 99.9%, never 100%.
    const double percent = std::floor(1000.0 * ttfs.size() / list.size()) / 10;
    std::fprintf(stderr, "%-11s %7zu %7zu %7.1f%%", name.c_str(), list.size(), ttfs.size(),
                 percent);
    if (ttfs.empty()) {  // no figures to show: dashes, not zeros that read like results
      std::fprintf(stderr, " %14s %14s %10s\n", "-", "-", "-");
    } else {
      const Quantiles qt = quantiles(ttfs), qc = quantiles(cost);
      std::fprintf(stderr, " %14.4f %14.4f %10.3f\n", qt.median, qt.mean, qc.mean);
    }
    if (!failures.empty()) {  // the leading reason, so a failure reads as one
      const auto leading =
          std::max_element(failures.begin(), failures.end(),
                           [](const auto& a, const auto& b) { return a.second < b.second; });
      std::fprintf(stderr, "%-11s %zu failed, most often: %s\n", "", list.size() - ttfs.size(),
                   leading->first.c_str());
    }
  }
  if (errors) std::fprintf(stderr, "%zu queries had errors (see their \"error\" field)\n", errors);
  std::fprintf(stderr, "resident memory %.0f MiB\n", resident_memory_mib());
}

// The exit status of an answered batch (results written either way): 0 when every line was
// planned (solved or not), 1 when every line of a non-empty batch had an error, and
// kSomeLinesFailed when some had.
constexpr int kSomeLinesFailed = 3;
int batch_status(const std::vector<Outcome>& outcomes) {
  const size_t errors = static_cast<size_t>(
      std::count_if(outcomes.begin(), outcomes.end(), [](const Outcome& o) { return o.error; }));
  if (errors == 0) return 0;
  if (errors < outcomes.size()) return kSomeLinesFailed;
  std::fprintf(stderr,
               "lazyboe-query: every query had an error (%zu of %zu; see their \"error\" "
               "field)\n",
               outcomes.size(), outcomes.size());
  return 1;
}

// The default --sim-threads: the cores left per job; a warning when jobs x threads exceed them.
int sim_threads_for(const Options& o) {
  const int cores = omp_get_num_procs();
  const int threads = o.sim_threads > 0 ? o.sim_threads : std::max(1, cores / o.jobs);
  if (!o.quiet && threads > 1 && static_cast<long>(o.jobs) * threads > cores) {
    std::fprintf(stderr,
                 "lazyboe-query: warning: --jobs %d x --sim-threads %d is more threads than the "
                 "%d cores; waiting threads spin and slow the others (use fewer)\n",
                 o.jobs, threads, cores);
  }
  return threads;
}

int run(const Options& o) {
  const TrajectoryOutput mode = trajectory_mode(o);
  if (o.sim_threads > 1024)
    fail("--sim-threads", "at most 1024, got " + std::to_string(o.sim_threads));
  const PlanningSession session(o.bundle_path, !o.no_mmap, o.robot_path, o.env_path);
  refuse_output_as_input({"--out", o.out_path}, {{"--bundle", o.bundle_path},
                                                 {"--queries", o.queries_path},
                                                 {"robot config", session.robot.files.config},
                                                 {"URDF", session.robot.files.urdf},
                                                 {"environment", session.world().env.path}});
  report_load(o, session);
  Job job{session, QueryDefaults{}, mode, o.trajectory_dir};
  job.defaults.output.raw = o.raw;
  job.defaults.output.sample_interval =
      o.control_rate ? 1.0 / session.robot.control_rate : o.sample_interval;
  job.defaults.output.shortcut_attempts = o.shortcut_attempts;

  // Output: a file written under a temporary name (renamed at the end), or standard output.
  const bool to_stdout = o.out_path == "-";
  std::unique_ptr<AtomicFile> file;
  if (!to_stdout) file = std::make_unique<AtomicFile>(o.out_path);
  std::ostream& out = to_stdout ? std::cout : file->stream();
  const int sim_threads = sim_threads_for(o);
  const std::vector<Outcome> outcomes =
      o.queries_path == "-" ? answer_stream(job, out, sim_threads)
                            : answer_file(job, o.queries_path, out, o.jobs, sim_threads);
  if (file) file->commit();
  if (!o.quiet) print_summary(outcomes);
  return batch_status(outcomes);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Answer a batch of planning queries (JSON Lines) on an edge bundle."};
  Options options;
  add_options(app, options);
  one_line_cli_errors(app, "lazyboe-query");
  CLI11_PARSE(app, argc, argv);
  return run_tool("lazyboe-query", [&] { return run(options); });
}
