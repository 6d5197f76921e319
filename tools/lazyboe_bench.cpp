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
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/data_dir.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/planning/ompl/ompl_planners.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/robot/payload.h"
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

void write_text(const fs::path& path, const std::string& text) {
  AtomicFile file(path.string());
  file.stream() << text;
  file.commit();
}

// Runs the plotting script when python3 with matplotlib is there; says so when it is not.
void draw_figures(const fs::path& out_dir, bool quiet) {
  // Debian's python3-matplotlib belongs to the system interpreter, whatever else is on PATH.
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  // Installed beside the data (<prefix>/share/lazyboe/scripts), else the source tree's.
  const fs::path installed = fs::path(data_dir()) / "scripts" / "plot-bench.py";
  const std::string script = fs::exists(installed)
                                 ? installed.string()
                                 : std::string(LAZYBOE_SCRIPTS_DIR) + "/plot-bench.py";
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

// The command line.
struct BenchOptions {
  std::string bundle_path, problems_file, planners = "all", out_dir, robot_path, env_path;
  int problems = 25, repeats = 1, jobs = 1;
  double budget = 60, tolerance = 0;
  uint64_t seed = 1;
  bool resume = false, force = false, no_figures = false, no_mmap = false, quiet = false;
  bool raw = false, no_direct = false;
  int shortcut_attempts = ExecutionOptions{}.shortcut_attempts;
  std::string goals = "joint", payload, end_effector_limits;  // the study's goals and task
};

// The parameters a resumed study must share with the interrupted one.
nlohmann::json study_parameters(const BenchOptions& o) {
  return {{"bundle", fs::absolute(o.bundle_path).string()},
          {"planners", o.planners},
          {"budget", o.budget},
          {"repeats", o.repeats},
          {"seed", o.seed},
          {"problems", o.problems},
          {"problems_file", o.problems_file.empty() ? "" : fs::absolute(o.problems_file).string()},
          {"tolerance", o.tolerance},
          {"raw", o.raw},
          {"no_direct", o.no_direct},
          {"shortcut_attempts", o.shortcut_attempts},
          {"goals", o.goals},
          {"payload", o.payload},
          {"end_effector_limits", o.end_effector_limits}};
}

void add_options(CLI::App& app, BenchOptions& o) {
  app.add_option("--bundle", o.bundle_path, "Bundle file (HDF5) with its perturbation analysis")
      ->required();
  app.add_option("--out", o.out_dir, "Directory for problems.jsonl, runs.csv, summary.md, figures")
      ->required();
  app.add_option("--problems", o.problems, "Random problems to draw in the bundle's region")
      ->capture_default_str()
      ->check(whole_number(false));
  CLI::Option* problems_file =
      app.add_option("--problems-file", o.problems_file,
                     "Read the problems from a JSON Lines query file instead (e.g. an earlier "
                     "study's problems.jsonl)");
  app.add_option("--budget", o.budget, "Wall-clock seconds per run")
      ->capture_default_str()
      ->check(real_in({0, kMaxBudgetSeconds, true}, " s"));
  app.add_option("--seed", o.seed, "Study seed (problems and per-run planner seeds)")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--planners", o.planners,
                 "all, or a comma-separated list of " + planner_names_text() +
                     " (sst = sst-0.5x, sst-1x, sst-2x; see lazyboe-query --list-planners)")
      ->capture_default_str();
  app.add_option("--repeats", o.repeats, "Runs per planner and problem, with different seeds")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--jobs", o.jobs, "Runs in parallel (at most one per core: budgets are wall time)")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--tolerance", o.tolerance,
                 "Radius of the joint-space goal region of drawn problems, rad (default: the "
                 "bundle's theta)")
      ->check(real_in({0, 1e3, true}, " rad"));
  app.add_option("--robot", o.robot_path, "Robot config (default: the bundle's)");
  app.add_option("--env", o.env_path,
                 "Environment the study plans in (default: the bundle's own; any scene for "
                 "the bundle's robot)");
  app.add_flag("--resume", o.resume, "Continue an interrupted study in --out");
  app.add_flag("--force", o.force, "Overwrite the results of an earlier study in --out");
  app.add_flag("--no-figures", o.no_figures, "Do not draw the PNG figures");
  app.add_flag("--no-mmap", o.no_mmap, "Read the bundle into memory instead of mapping it");
  app.add_flag("--raw", o.raw,
               "Do not post-process returned paths (runs.csv's execution columns are then the "
               "raw chain's)");
  app.add_flag("--no-direct", o.no_direct,
               "The bundle planners search every problem (their parameter direct = false, which "
               "also turns off lazysp's waypoints): the study measures their searches, also on "
               "problems one straight command, or two through a waypoint, solve");
  app.add_option("--shortcut-attempts", o.shortcut_attempts,
                 "Post-processing budget: direct commands tried per path (0: junction blending "
                 "only)")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--goals", o.goals,
                 "Goals of drawn problems: joint (a region of --tolerance around the goal "
                 "configuration) or pose (the tip's pose there, 1 cm and 0.05 rad)")
      ->capture_default_str()
      ->check(CLI::IsMember({"joint", "pose"}))
      ->excludes(problems_file);
  app.add_option("--payload", o.payload,
                 "A payload carried in every run, as a query's \"payload\" (JSON text)");
  app.add_option("--end-effector-limits", o.end_effector_limits,
                 "End-effector limits of every run, as a query's \"end_effector_limits\" (JSON "
                 "text, with its \"axis\" when max_tilt is given)");
  app.add_flag("--quiet", o.quiet, "No progress output");
}

// The task of every run (--payload, --end-effector-limits), read as a query's fields are. A
// tilt limit needs its axis: the default (the link's axis vertical at the start) would differ
// from problem to problem, and a study plans in one world.
Task study_task(const BenchOptions& o, const RobotModel& robot) {
  Task task;
  if (!o.payload.empty()) {
    const nlohmann::json doc = parse_json_text(o.payload, "--payload", false);
    task.payload = payload_from_json(JsonField(doc, "--payload", ""), robot);
  }
  if (!o.end_effector_limits.empty()) {
    const nlohmann::json doc =
        parse_json_text(o.end_effector_limits, "--end-effector-limits", false);
    const JsonField f(doc, "--end-effector-limits", "");
    if (f.value().is_object() && f.has("max_tilt") && !f.has("axis"))
      f.fail(
          "give \"axis\" with \"max_tilt\" in a study (its default, the axis vertical at "
          "the start, would differ between problems)");
    RobotData data(robot);
    task.end_effector = end_effector_limits_from_json(f, robot, robot.q_min, data);
  }
  return task;
}

// The files of a study in --out.
struct StudyPaths {
  explicit StudyPaths(const fs::path& out)
      : dir(out),
        problems(out / "problems.jsonl"),
        runs(out / "runs.csv"),
        partial(out / "runs.partial.csv"),
        study(out / "study.json"),
        summary(out / "summary.md") {}
  fs::path dir, problems, runs, partial, study, summary;
};

// Refuses --resume without a study, or overwriting one without --force; warns about more jobs
// than cores.
void check_out_dir(const BenchOptions& o, const StudyPaths& paths) {
  if (o.resume && o.force) fail("--resume", "cannot be combined with --force");
  if (o.resume && !fs::exists(paths.study)) {
    fail(paths.study.string(), "no study to resume (run without --resume first)");
  }
  if (!o.resume && !o.force && (fs::exists(paths.runs) || fs::exists(paths.partial))) {
    fail(paths.dir.string(),
         "holds an earlier study; use --resume to continue it or --force to "
         "replace it");
  }
  const unsigned cores = std::thread::hardware_concurrency();  // 0 when unknown
  if (cores > 0 && o.jobs > static_cast<int>(cores)) {
    std::fprintf(stderr,
                 "lazyboe-bench: warning: %d jobs on %u cores: budgets are wall time, so runs "
                 "sharing a core get less planning time\n",
                 o.jobs, std::thread::hardware_concurrency());
  }
}

// A resumed study must have been run with the same parameters.
void check_same_study(const fs::path& study_path, const nlohmann::json& parameters) {
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

// The study's problems: those of the study resumed, read from --problems-file, or drawn; a new
// study writes them and its parameters to --out. `source` says where they came from.
std::vector<BenchProblem> study_problems(const BenchOptions& o, const StudyPaths& paths,
                                         const PlanningSession& session,
                                         const PlanningContext& context,
                                         const nlohmann::json& parameters, std::string& source) {
  const Simulator& sim = context.sim;
  SimulatorWorkspace ws(sim);
  const QueryDefaults query_defaults;
  if (o.resume) {
    source = "resumed from " + paths.problems.string();
    return read_problems(paths.problems.string(), sim, ws, query_defaults, &session.end_poses);
  }
  if (o.force) {  // study.json first: its absence marks the directory as not resumable
    for (const fs::path& p : {paths.study, paths.runs, paths.partial, paths.summary}) fs::remove(p);
  }
  std::vector<BenchProblem> problems;
  if (!o.problems_file.empty()) {
    problems = read_problems(o.problems_file, sim, ws, query_defaults, &session.end_poses);
    source = "read from " + o.problems_file;
  } else {
    const double radius = o.tolerance > 0 ? o.tolerance : context.theta;
    ProblemGoals goals;
    goals.pose = o.goals == "pose";
    goals.coverage = &session.end_poses;
    problems = sample_problems(sim, ws, context.sample_lower, context.sample_upper, o.problems,
                               radius, o.seed, goals);
    source = "drawn with seed " + std::to_string(o.seed) + " in the bundle's region, " +
             (goals.pose ? "pose goals (the tip at the goal configuration, 1 cm and 0.05 rad)"
                         : "goal tolerance " + std::to_string(radius) + " rad");
  }
  write_problems(paths.problems.string(), session.robot, problems);
  write_text(paths.study, parameters.dump(2) + "\n");
  return problems;
}

// Runs already done: the partial file of an interrupted study, or the runs.csv of a finished
// one (resuming it only writes its summary and figures again).
std::vector<RunRecord> runs_done(const BenchOptions& o, const StudyPaths& paths,
                                 const std::vector<std::string>& problem_ids) {
  if (o.resume && fs::exists(paths.partial))
    return read_runs_csv(paths.partial.string(), problem_ids);
  if (o.resume && fs::exists(paths.runs)) return read_runs_csv(paths.runs.string(), problem_ids);
  return {};
}

// The runs still to do: problem by problem, every planner in turn, so that a partial study is
// balanced across planners.
std::vector<StudyTask> tasks_to_do(const std::vector<PlannerSpec>& specs, int problems, int repeats,
                                   const std::vector<RunRecord>& done) {
  std::map<std::tuple<std::string, int, int>, bool> have;
  for (const RunRecord& r : done) have[{r.planner, r.problem, r.repeat}] = true;
  std::vector<StudyTask> tasks;
  for (int rep = 0; rep < repeats; ++rep) {
    for (int p = 0; p < problems; ++p) {
      for (int s = 0; s < static_cast<int>(specs.size()); ++s) {
        if (specs[s].available && !have.count({specs[s].name, p, rep}))
          tasks.push_back({s, p, rep});
      }
    }
  }
  return tasks;
}

void print_run(const RunRecord& r, const std::string& problem_id, size_t finished, size_t total) {
  if (r.success) {
    std::fprintf(stderr, "[%zu/%zu] %-11s %s repeat %d: solved, first after %.3f s, cost %.2f\n",
                 finished, total, r.planner.c_str(), problem_id.c_str(), r.repeat,
                 r.time_to_first_solution, r.best_cost);
  } else {
    std::fprintf(stderr, "[%zu/%zu] %-11s %s repeat %d: no solution (%s)\n", finished, total,
                 r.planner.c_str(), problem_id.c_str(), r.repeat, r.failure.c_str());
  }
}

// Writes runs.csv (sorted by repeat, problem, planner order) and summary.md.
void write_results(const BenchOptions& o, const StudyPaths& paths, const StudyInfo& info,
                   const std::vector<PlannerSpec>& specs, std::vector<RunRecord>& runs,
                   const std::vector<std::string>& problem_ids) {
  std::map<std::string, int> order;
  for (size_t s = 0; s < specs.size(); ++s) order[specs[s].name] = static_cast<int>(s);
  std::sort(runs.begin(), runs.end(), [&](const RunRecord& a, const RunRecord& b) {
    return std::make_tuple(a.repeat, a.problem, order[a.planner]) <
           std::make_tuple(b.repeat, b.problem, order[b.planner]);
  });
  write_runs_csv(paths.runs.string(), runs, problem_ids);
  write_text(paths.summary, summary_markdown(info, specs, runs));
  fs::remove(paths.partial);
  if (!o.no_figures) draw_figures(paths.dir, o.quiet);
  if (!o.quiet) {
    std::fprintf(stderr, "lazyboe-bench: wrote %s, %s and %s\n", paths.problems.c_str(),
                 paths.runs.c_str(), paths.summary.c_str());
  }
}

StudyInfo study_info(const BenchOptions& o, const PlanningSession& session,
                     const PlanningContext& context, const PlanningWorld& world,
                     const std::vector<BenchProblem>& problems, const std::string& problems_source,
                     const std::string& command_line) {
  StudyInfo info;
  info.direct = direct_solutions(context, problems);
  if (!o.payload.empty()) info.task = "payload " + o.payload;
  if (!o.end_effector_limits.empty())
    info.task += (info.task.empty() ? "" : ", ") + ("end-effector limits " + o.end_effector_limits);
  info.bundle = o.bundle_path;
  info.edges = session.bundle.size();
  info.robot = session.robot.files.config;
  info.environment = world.env.path;
  info.problems = static_cast<int>(problems.size());
  info.problems_source = problems_source;
  info.repeats = o.repeats;
  info.jobs = o.jobs;
  info.budget = o.budget;
  info.seed = o.seed;
  info.machine = machine_description();
  info.command_line = command_line;
  return info;
}

// The exit status for a script: 0 every run ended (solved or not), kSomeRunsFailed when some
// runs ended in an error (runs.csv's failure column says which and why).
constexpr int kSomeRunsFailed = 3;

int errors_status(const std::vector<RunRecord>& runs, const StudyPaths& paths) {
  size_t errors = 0;
  for (const RunRecord& r : runs) errors += r.failure.rfind("error: ", 0) == 0;
  if (errors == 0) return 0;
  std::fprintf(stderr, "lazyboe-bench: %zu of %zu runs ended in an error (%s's failure column)\n",
               errors, runs.size(), paths.runs.c_str());
  return kSomeRunsFailed;
}

int run(const BenchOptions& o, const std::string& command_line) {
  const StudyPaths paths{fs::path(o.out_dir)};
  check_out_dir(o, paths);
  const nlohmann::json parameters = study_parameters(o);
  if (o.resume) check_same_study(paths.study, parameters);  // before anything is loaded

  planner_specs(o.planners);  // names checked before the bundle is loaded
  const PlanningSession session(o.bundle_path, !o.no_mmap, o.robot_path, o.env_path);
  // The study's world: the session's scene with the task of every run.
  const WorldPtr world =
      session.scenes.with_task(session.scenes.default_world(), study_task(o, session.robot));
  if (!o.quiet) {
    std::fprintf(stderr, "lazyboe-bench: %s: %zu edges loaded in %.3f s\n", o.bundle_path.c_str(),
                 session.bundle.size(), session.load_seconds);
  }
  std::vector<PlannerSpec> specs = planner_specs(o.planners);
  if (o.no_direct) search_only(specs);
  const PlanningContext context = session.context(*world);
  check_planner_specs(context, specs);
  for (const PlannerSpec& s : specs) {
    if (!s.available)
      std::fprintf(stderr, "lazyboe-bench: skipping %s: %s\n", s.name.c_str(),
                   s.unavailable_reason.c_str());
  }
  if (ompl_available()) seed_ompl(o.seed);

  fs::create_directories(paths.dir);
  std::string problems_source;
  const std::vector<BenchProblem> problems =
      study_problems(o, paths, session, context, parameters, problems_source);
  std::vector<std::string> problem_ids;
  for (const BenchProblem& p : problems) problem_ids.push_back(p.id);

  std::vector<RunRecord> runs = runs_done(o, paths, problem_ids);
  const std::vector<StudyTask> tasks =
      tasks_to_do(specs, static_cast<int>(problems.size()), o.repeats, runs);
  if (!o.quiet) {
    std::fprintf(stderr,
                 "lazyboe-bench: %zu problems, %zu planners, %d repeat(s): %zu runs to do%s, "
                 "at most %.0f s each\n",
                 problems.size(), specs.size(), o.repeats, tasks.size(),
                 runs.empty() ? "" : (" (" + std::to_string(runs.size()) + " done)").c_str(),
                 o.budget);
  }

  install_stop_handlers();
  PartialRunsFile partial(paths.partial.string());
  StudyControl control;
  control.jobs = o.jobs;
  control.stop_requested = stop_requested;
  control.output.raw = o.raw;
  control.output.shortcut_attempts = o.shortcut_attempts;
  control.on_run = [&](const RunRecord& r, size_t finished, size_t total) {
    partial.append(r, problem_ids[r.problem]);
    if (!o.quiet) print_run(r, problem_ids[r.problem], finished, total);
  };
  const std::vector<RunRecord> fresh =
      run_study(context, specs, problems, tasks, o.budget, o.seed, control);
  runs.insert(runs.end(), fresh.begin(), fresh.end());
  if (fresh.size() < tasks.size()) {  // stopped before every run was done
    std::fprintf(stderr,
                 "lazyboe-bench: interrupted: %zu runs saved in %s; continue with --resume\n",
                 runs.size(), paths.partial.c_str());
    return 130;
  }
  const StudyInfo info =
      study_info(o, session, context, *world, problems, problems_source, command_line);
  write_results(o, paths, info, specs, runs, problem_ids);
  return errors_status(runs, paths);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Benchmark study: every planner on the same random problems with the same budget (the "
      "paper's evaluation), side by side with OMPL's control planners."};
  BenchOptions options;
  add_options(app, options);
  one_line_cli_errors(app, "lazyboe-bench");
  CLI11_PARSE(app, argc, argv);
  std::string command_line;
  for (int k = 0; k < argc; ++k) command_line += (k ? " " : "") + std::string(argv[k]);
  return run_tool("lazyboe-bench", [&]() -> int { return run(options, command_line); });
}
