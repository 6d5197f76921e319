// lazyboe-bench: the paper's evaluation as a command. Every planner (ours and, when built with
// OMPL, OMPL's control planners on the same simulator) on the same random problems with the
// same budget; runs.csv, summary.md with Mann-Whitney U tests, and the paper's four figures.
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "lazyboe/bench/report.h"
#include "lazyboe/planning/ompl/ompl_planners.h"
#include "lazyboe/planning/planning_session.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;
namespace fs = std::filesystem;

std::string machine_description() {
  std::string model;
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos && colon + 2 <= line.size()) model = line.substr(colon + 2);
      break;
    }
  }
  long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  char text[256];
  std::snprintf(text, sizeof text, "%s, %u cores, %.0f GiB", model.empty() ? "?" : model.c_str(),
                std::thread::hardware_concurrency(),
                static_cast<double>(pages) * page / (1024.0 * 1024 * 1024));
  return text;
}

// The parameters a resumed study must share with the interrupted one.
nlohmann::json study_parameters(const std::string& bundle, const std::string& planners,
                                double budget, int repeats, uint64_t seed, int problems,
                                const std::string& problems_file, double tolerance) {
  return {{"bundle", fs::absolute(bundle).string()},
          {"planners", planners},
          {"budget", budget},
          {"repeats", repeats},
          {"seed", seed},
          {"problems", problems},
          {"problems_file", problems_file.empty() ? "" : fs::absolute(problems_file).string()},
          {"tolerance", tolerance}};
}

void write_text(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out || !(out << text) || !out.flush()) fail(path.string(), "cannot write");
  }
  fs::rename(tmp, path);
}

// Runs the plotting script when python3 with matplotlib is there; says so when it is not.
void draw_figures(const fs::path& out_dir, bool quiet) {
  // Debian's python3-matplotlib belongs to the system interpreter, whatever else is on PATH.
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string script = std::string(LAZYBOE_SCRIPTS_DIR) + "/plot-bench.py";
  const std::string command = python + " '" + script + "' '" + out_dir.string() + "'";
  if (std::system((python + " -c 'import matplotlib' > /dev/null 2>&1").c_str()) != 0) {
    std::fprintf(stderr,
                 "lazyboe-bench: figures skipped: python3-matplotlib is not installed "
                 "(apt-get install python3-matplotlib, then run %s)\n",
                 command.c_str());
    return;
  }
  if (std::system((command + (quiet ? " > /dev/null" : "")).c_str()) != 0) {
    std::fprintf(stderr, "lazyboe-bench: warning: the figures could not be drawn (%s)\n",
                 command.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark study: every planner on the same random problems with the same budget (the "
      "paper's evaluation), side by side with OMPL's control planners."};
  std::string bundle_path, problems_file, planners = "all", out_dir, robot_path, env_path;
  int problems = 25, repeats = 1, jobs = 1;
  double budget = 60, tolerance = 0;
  uint64_t seed = 1;
  bool resume = false, force = false, no_figures = false, no_mmap = false, quiet = false;
  app.add_option("--bundle", bundle_path, "Bundle file (HDF5) with its perturbation analysis")
      ->required();
  app.add_option("--out", out_dir, "Directory for problems.jsonl, runs.csv, summary.md, figures")
      ->required();
  app.add_option("--problems", problems, "Random problems to draw in the bundle's region")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--problems-file", problems_file,
                 "Read the problems from a JSON Lines query file instead (e.g. an earlier "
                 "study's problems.jsonl)");
  app.add_option("--budget", budget, "Wall-clock seconds per run")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "Study seed (problems and per-run planner seeds)")
      ->capture_default_str();
  app.add_option("--planners", planners,
                 "all, or a comma-separated list of lazyboe, boe, rrt, sst (= sst-0.5x, sst-1x, "
                 "sst-2x), lazysp, ompl-rrt, ompl-sst, ompl-kpiece")
      ->capture_default_str();
  app.add_option("--repeats", repeats, "Runs per planner and problem, with different seeds")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--jobs", jobs, "Runs in parallel (at most one per core: budgets are wall time)")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--tolerance", tolerance,
                 "Radius of the joint-space goal region of drawn problems, rad (default: the "
                 "bundle's theta)")
      ->check(CLI::PositiveNumber);
  app.add_option("--robot", robot_path, "Robot config (default: the bundle's)");
  app.add_option("--env", env_path, "Environment (default: the bundle's)");
  app.add_flag("--resume", resume, "Continue an interrupted study in --out");
  app.add_flag("--force", force, "Overwrite the results of an earlier study in --out");
  app.add_flag("--no-figures", no_figures, "Do not draw the PNG figures");
  app.add_flag("--no-mmap", no_mmap, "Read the bundle into memory instead of mapping it");
  app.add_flag("--quiet", quiet, "No progress output");
  one_line_cli_errors(app, "lazyboe-bench");
  CLI11_PARSE(app, argc, argv);

  return run_tool("lazyboe-bench", [&]() -> int {
    const fs::path dir(out_dir);
    const fs::path problems_path = dir / "problems.jsonl", runs_path = dir / "runs.csv",
                   partial_path = dir / "runs.partial.csv", study_path = dir / "study.json";
    if (resume && force) fail("--resume", "cannot be combined with --force");
    if (resume && !fs::exists(study_path)) {
      fail(study_path.string(), "no study to resume (run without --resume first)");
    }
    if (!resume && !force && (fs::exists(runs_path) || fs::exists(partial_path))) {
      fail(dir.string(),
           "holds an earlier study; use --resume to continue it or --force to "
           "replace it");
    }
    const unsigned cores = std::thread::hardware_concurrency();  // 0 when unknown
    if (cores > 0 && jobs > static_cast<int>(cores)) {
      std::fprintf(stderr,
                   "lazyboe-bench: warning: %d jobs on %u cores: budgets are wall time, so runs "
                   "sharing a core get less planning time\n",
                   jobs, std::thread::hardware_concurrency());
    }

    const nlohmann::json parameters = study_parameters(bundle_path, planners, budget, repeats, seed,
                                                       problems, problems_file, tolerance);
    if (resume) {  // before anything is loaded: a mismatch is refused at once
      std::ifstream in(study_path);
      nlohmann::json saved;
      try {
        in >> saved;
      } catch (const nlohmann::json::exception&) {
        fail(study_path.string(), "not valid JSON");
      }
      if (saved != parameters) {
        fail(study_path.string(), "the study there was run with other parameters (" + saved.dump() +
                                      "); rerun with the same ones to resume");
      }
    }

    planner_specs(planners);  // names checked before the bundle is loaded
    const PlanningSession session(bundle_path, !no_mmap, robot_path, env_path);
    if (!quiet) {
      std::fprintf(stderr, "lazyboe-bench: %s: %zu edges loaded in %.3f s\n", bundle_path.c_str(),
                   session.bundle.size(), session.load_seconds);
    }
    const std::vector<PlannerSpec> specs = planner_specs(planners);
    for (const PlannerSpec& s : specs) {
      if (!s.available)
        std::fprintf(stderr, "lazyboe-bench: skipping %s: %s\n", s.name.c_str(),
                     s.unavailable_reason.c_str());
    }
    if (ompl_available()) seed_ompl(seed);

    fs::create_directories(dir);
    SimulatorWorkspace ws(session.sim);
    std::vector<BenchProblem> study_problems;
    std::string problems_source;
    QueryDefaults query_defaults;
    if (resume) {
      study_problems = read_problems(problems_path.string(), session.sim, ws, query_defaults);
      problems_source = "resumed from " + problems_path.string();
    } else {
      if (force) {  // study.json first: its absence marks the directory as not resumable
        for (const fs::path& p : {study_path, runs_path, partial_path, dir / "summary.md"})
          fs::remove(p);
      }
      if (!problems_file.empty()) {
        study_problems = read_problems(problems_file, session.sim, ws, query_defaults);
        problems_source = "read from " + problems_file;
      } else {
        const PlanningContext defaults = session.context();
        const double radius = tolerance > 0 ? tolerance : defaults.theta;
        study_problems = sample_problems(session.sim, ws, defaults.sample_lower,
                                         defaults.sample_upper, problems, radius, seed);
        problems_source = "drawn with seed " + std::to_string(seed) +
                          " in the bundle's region, goal tolerance " + std::to_string(radius) +
                          " rad";
      }
      write_problems(problems_path.string(), session.scene.robot, study_problems);
      write_text(study_path, parameters.dump(2) + "\n");
    }
    std::vector<std::string> problem_ids;
    for (const BenchProblem& p : study_problems) problem_ids.push_back(p.id);

    std::vector<RunRecord> runs;
    // Runs already done: the partial file of an interrupted study, or the runs.csv of a
    // finished one (resuming it only writes its summary and figures again).
    if (resume && fs::exists(partial_path)) {
      runs = read_runs_csv(partial_path.string(), problem_ids);
    } else if (resume && fs::exists(runs_path)) {
      runs = read_runs_csv(runs_path.string(), problem_ids);
    }
    std::map<std::tuple<std::string, int, int>, bool> have;
    for (const RunRecord& r : runs) have[{r.planner, r.problem, r.repeat}] = true;
    // The rest: problem by problem, every planner in turn, so that a partial study is balanced
    // across planners.
    std::vector<StudyTask> tasks;
    for (int rep = 0; rep < repeats; ++rep) {
      for (int p = 0; p < static_cast<int>(study_problems.size()); ++p) {
        for (int s = 0; s < static_cast<int>(specs.size()); ++s) {
          if (specs[s].available && !have.count({specs[s].name, p, rep}))
            tasks.push_back({s, p, rep});
        }
      }
    }
    if (!quiet) {
      std::fprintf(stderr,
                   "lazyboe-bench: %zu problems, %zu planners, %d repeat(s): %zu runs to do%s, "
                   "at most %.0f s each\n",
                   study_problems.size(), specs.size(), repeats, tasks.size(),
                   runs.empty() ? "" : (" (" + std::to_string(runs.size()) + " done)").c_str(),
                   budget);
    }

    install_stop_handlers();
    PartialRunsFile partial(partial_path.string());
    StudyControl control;
    control.jobs = jobs;
    control.stop_requested = stop_requested;
    control.on_run = [&](const RunRecord& r, size_t finished, size_t total) {
      partial.append(r, problem_ids[r.problem]);
      if (quiet) return;
      if (r.success) {
        std::fprintf(stderr,
                     "[%zu/%zu] %-11s %s repeat %d: solved, first after %.3f s, cost %.2f\n",
                     finished, total, r.planner.c_str(), problem_ids[r.problem].c_str(), r.repeat,
                     r.time_to_first_solution, r.best_cost);
      } else {
        std::fprintf(stderr, "[%zu/%zu] %-11s %s repeat %d: no solution (%s)\n", finished, total,
                     r.planner.c_str(), problem_ids[r.problem].c_str(), r.repeat,
                     r.failure.c_str());
      }
    };
    const std::vector<RunRecord> fresh =
        run_study(session.context(), specs, study_problems, tasks, budget, seed, control);
    runs.insert(runs.end(), fresh.begin(), fresh.end());
    if (fresh.size() < tasks.size()) {  // stopped before every run was done
      std::fprintf(stderr,
                   "lazyboe-bench: interrupted: %zu runs saved in %s; continue with --resume\n",
                   runs.size(), partial_path.c_str());
      return 130;
    }

    std::map<std::string, int> order;
    for (size_t s = 0; s < specs.size(); ++s) order[specs[s].name] = static_cast<int>(s);
    std::sort(runs.begin(), runs.end(), [&](const RunRecord& a, const RunRecord& b) {
      return std::make_tuple(a.repeat, a.problem, order[a.planner]) <
             std::make_tuple(b.repeat, b.problem, order[b.planner]);
    });
    write_runs_csv(runs_path.string(), runs, problem_ids);
    StudyInfo info;
    info.bundle = bundle_path;
    info.edges = session.bundle.size();
    info.robot = session.scene.robot.config_path;
    info.environment = session.scene.env.path;
    info.problems = static_cast<int>(study_problems.size());
    info.problems_source = problems_source;
    info.repeats = repeats;
    info.jobs = jobs;
    info.budget = budget;
    info.seed = seed;
    info.machine = machine_description();
    for (int k = 0; k < argc; ++k) info.command_line += (k ? " " : "") + std::string(argv[k]);
    write_text(dir / "summary.md", summary_markdown(info, specs, runs));
    fs::remove(partial_path);
    if (!no_figures) draw_figures(dir, quiet);
    if (!quiet) {
      std::fprintf(stderr, "lazyboe-bench: wrote %s, %s and %s\n", problems_path.c_str(),
                   runs_path.c_str(), (dir / "summary.md").c_str());
    }
    return 0;
  });
}
