// lazyboe-query: open a bundle once (memory-mapped) and answer a batch of planning queries
// (JSON Lines) with LazyBoE and its baselines; every returned trajectory is re-simulated and
// re-validated end to end.
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>

#include "lazyboe/common/histogram.h"
#include "lazyboe/io/query_io.h"
#include "lazyboe/planning/planners.h"
#include "lazyboe/planning/planning_session.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;
struct Outcome {
  std::string planner;
  bool success = false;
  double ttfs = 0, cost = 0;
  bool error = false;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Answer a batch of planning queries (JSON Lines) on an edge bundle."};
  std::string bundle_path, queries_path, out_path = "-", trajectories = "none", trajectory_dir;
  std::string robot_path, env_path;
  int jobs = 1, sim_threads = 0;
  double sample_interval = 0.01;
  bool no_mmap = false, quiet = false;
  app.add_option("--bundle", bundle_path,
                 "Bundle file (HDF5), with its perturbation analysis for lazyboe")
      ->required();
  app.add_option("--queries", queries_path,
                 "Queries, one JSON object per line; - for standard input")
      ->required();
  app.add_option("--out", out_path, "Results, one JSON object per line; - for standard output")
      ->capture_default_str();
  app.add_option("--jobs", jobs, "Queries planned in parallel")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--sim-threads", sim_threads,
                 "Threads simulating one BoE/LazyBoE query's edges in parallel (the answers do "
                 "not depend on it); 0: the cores left per job")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--trajectories", trajectories,
                 "none, inline (in each result) or csv (files in --trajectory-dir)")
      ->capture_default_str();
  app.add_option("--trajectory-dir", trajectory_dir, "Directory for --trajectories csv");
  app.add_option("--sample-interval", sample_interval, "Trajectory sample spacing, s")
      ->capture_default_str();
  app.add_option("--robot", robot_path, "Robot config (default: the bundle's)");
  app.add_option("--env", env_path, "Environment (default: the bundle's)");
  app.add_flag("--no-mmap", no_mmap, "Read the bundle into memory instead of mapping it");
  app.add_flag("--quiet", quiet, "No summary on stderr");
  one_line_cli_errors(app, "lazyboe-query");
  CLI11_PARSE(app, argc, argv);

  return run_tool("lazyboe-query", [&]() -> int {
    TrajectoryOutput mode = TrajectoryOutput::None;
    if (trajectories == "inline") {
      mode = TrajectoryOutput::Inline;
    } else if (trajectories == "csv") {
      mode = TrajectoryOutput::Csv;
      if (trajectory_dir.empty()) fail("--trajectory-dir", "required with --trajectories csv");
      std::filesystem::create_directories(trajectory_dir);
    } else if (trajectories != "none") {
      fail("--trajectories", "expected none, inline or csv");
    }
    if (sim_threads > 1024)
      fail("--sim-threads", "at most 1024, got " + std::to_string(sim_threads));
    const PlanningSession session(bundle_path, !no_mmap, robot_path, env_path);
    const BundleView& bundle = session.bundle;
    const RobotModel& robot = session.scene.robot;
    const Simulator& sim = session.sim;
    if (!quiet) {
      for (const std::string& w : bundle.warnings())
        std::fprintf(stderr, "lazyboe-query: warning: %s\n", w.c_str());
      std::fprintf(
          stderr, "lazyboe-query: %s: %zu edges loaded in %.3f s (%s), resident memory %.0f MiB\n",
          bundle_path.c_str(), bundle.size(), session.load_seconds,
          bundle.memory_mapped() ? "memory-mapped" : "read into memory", resident_memory_mib());
    }

    QueryDefaults defaults;
    defaults.params = session.default_params();
    defaults.theta = defaults.params.theta;
    const PlanningContext context = session.context();
    const int sample_every =
        std::max(1, static_cast<int>(std::lround(sample_interval * robot.control_rate)));

    // Output: a file written under a temporary name (renamed at the end), or standard output.
    const bool to_stdout = out_path == "-";
    const std::string tmp_path = out_path + ".tmp." + std::to_string(::getpid());
    std::ofstream file_out;
    if (!to_stdout) {
      file_out.open(tmp_path);
      if (!file_out) fail(out_path, "cannot write");
    }
    std::ostream& out = to_stdout ? std::cout : file_out;

    const int cores = omp_get_num_procs();
    if (sim_threads == 0) sim_threads = std::max(1, cores / jobs);
    if (!quiet && sim_threads > 1 && static_cast<long>(jobs) * sim_threads > cores) {
      std::fprintf(stderr,
                   "lazyboe-query: warning: --jobs %d x --sim-threads %d is more threads than the "
                   "%d cores; waiting threads spin and slow the others (use fewer)\n",
                   jobs, sim_threads, cores);
    }

    std::vector<Outcome> outcomes;
    auto answer = [&](const std::string& text, int line, SimulatorWorkspace& ws,
                      RolloutPool& pool) {
      std::string id;
      Outcome o;
      nlohmann::json j;
      try {
        const Query q = parse_query(text, line, robot, sim, ws, defaults, id);
        o.planner = q.problem.params.planner;
        const PlanResult r = plan(context, ws, q.problem, &pool);
        Trajectory traj;
        bool have = false;
        if (r.success) {
          traj = realize_path(sim, ws, q.problem.start, r.best_path, q.problem.goal, sample_every);
          have = true;
        }
        std::string csv;
        if (have && mode == TrajectoryOutput::Csv) {
          csv = (std::filesystem::path(trajectory_dir) / (q.id + ".csv")).string();
          write_trajectory_csv(csv, traj);
        }
        j = result_json(q, r, have ? &traj : nullptr, mode, csv);
        o.success = r.success;
        o.ttfs = r.time_to_first_solution;
        o.cost = have ? traj.cost : 0;
      } catch (const std::exception& e) {  // Error, or anything else: never out of a job
        j = error_json(id, line, o.planner, e.what());
        o.error = true;
      }
      return std::make_pair(j.dump(), o);
    };

    if (queries_path == "-") {
      // Streaming: one result per query as soon as it is ready.
      SimulatorWorkspace ws(sim);
      RolloutPool pool(sim, sim_threads);
      std::string text;
      int line = 0;
      while (std::getline(std::cin, text)) {
        ++line;
        if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
        auto [json, o] = answer(text, line, ws, pool);
        out << json << "\n" << std::flush;
        outcomes.push_back(o);
      }
    } else {
      std::ifstream in(queries_path);
      if (!in) fail(queries_path, "cannot open file");
      std::vector<std::pair<int, std::string>> lines;
      std::string text;
      for (int line = 1; std::getline(in, text); ++line) {
        if (text.find_first_not_of(" \t\r") != std::string::npos) lines.emplace_back(line, text);
      }
      outcomes.resize(lines.size());
      std::vector<SimulatorWorkspace> workspaces;
      std::vector<std::unique_ptr<RolloutPool>> pools;  // not movable: they own threads
      for (int t = 0; t < jobs; ++t) {
        workspaces.emplace_back(sim);
        pools.push_back(std::make_unique<RolloutPool>(sim, sim_threads));
      }
#pragma omp parallel for num_threads(jobs) schedule(dynamic, 1) ordered
      for (long k = 0; k < static_cast<long>(lines.size()); ++k) {
        const int t = omp_get_thread_num();
        auto [json, o] = answer(lines[k].second, lines[k].first, workspaces[t], *pools[t]);
        outcomes[k] = o;
#pragma omp ordered
        { out << json << "\n" << std::flush; }
      }
    }
    if (!to_stdout) {
      file_out.close();
      if (!file_out || std::rename(tmp_path.c_str(), out_path.c_str()) != 0) {
        std::remove(tmp_path.c_str());
        fail(out_path, "cannot write");
      }
    }
    if (!quiet) {
      std::map<std::string, std::vector<const Outcome*>> by_planner;
      size_t errors = 0;
      for (const Outcome& o : outcomes) {
        if (o.error)
          ++errors;
        else
          by_planner[o.planner].push_back(&o);
      }
      std::fprintf(stderr, "%-11s %7s %8s %14s %14s %10s\n", "planner", "queries", "success",
                   "median TTFS s", "mean TTFS s", "mean cost");
      for (const auto& [name, list] : by_planner) {
        std::vector<double> ttfs, cost;
        for (const Outcome* o : list) {
          if (!o->success) continue;
          ttfs.push_back(o->ttfs);
          cost.push_back(o->cost);
        }
        const Quantiles qt = quantiles(ttfs), qc = quantiles(cost);
        std::fprintf(stderr, "%-11s %7zu %7.0f%% %14.4f %14.4f %10.3f\n", name.c_str(), list.size(),
                     100.0 * ttfs.size() / list.size(), qt.median, qt.mean, qc.mean);
      }
      if (errors)
        std::fprintf(stderr, "%zu queries had errors (see their \"error\" field)\n", errors);
      std::fprintf(stderr, "resident memory %.0f MiB\n", resident_memory_mib());
    }
    return 0;
  });
}
