#include "lazyboe/bench/study.h"

#include <omp.h>

#include <optional>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/ompl_planners.h"
#include "lazyboe/planning/planners.h"

namespace lazyboe {

std::vector<PlannerSpec> planner_specs(const std::string& list, const PlannerParams& defaults) {
  static const std::vector<std::string> all = {"lazyboe",  "boe",      "rrt",
                                               "sst-0.5x", "sst-1x",   "sst-2x",
                                               "ompl-rrt", "ompl-sst", "ompl-kpiece"};
  std::vector<std::string> names;
  std::stringstream in(list);
  for (std::string name; std::getline(in, name, ',');) {
    if (name == "all") {
      names.insert(names.end(), all.begin(), all.end());
    } else if (name == "sst") {
      names.insert(names.end(), {"sst-0.5x", "sst-1x", "sst-2x"});
    } else {
      names.push_back(name);
    }
  }
  if (names.empty()) fail("--planners", "no planner named");
  std::vector<PlannerSpec> specs;
  for (const std::string& name : names) {
    PlannerSpec s;
    s.name = name;
    s.params = defaults;
    if (name == "lazyboe" || name == "boe" || name == "rrt") {
      s.params.planner = name;
    } else if (name == "sst-0.5x" || name == "sst-1x" || name == "sst-2x") {
      s.params.planner = "sst";
      s.params.pruning_ratio = name == "sst-0.5x" ? 0.5 : name == "sst-1x" ? 1.0 : 2.0;
    } else if (is_ompl_planner(name)) {
      s.params.planner = name;
      if (!ompl_available()) {
        s.available = false;
        s.unavailable_reason = "built without OMPL (install libompl-dev and rebuild)";
      }
    } else {
      fail("--planners", "unknown planner '" + name +
                             "' (expected all, lazyboe, boe, rrt, sst, sst-0.5x, sst-1x, sst-2x, "
                             "ompl-rrt, ompl-sst or ompl-kpiece)");
    }
    for (const PlannerSpec& other : specs) {
      if (other.name == name) fail("--planners", "'" + name + "' named twice");
    }
    specs.push_back(std::move(s));
  }
  return specs;
}

uint64_t run_seed(uint64_t study_seed, int problem, int repeat) {
  Random rng(study_seed, (static_cast<uint64_t>(problem) << 20) ^ static_cast<uint64_t>(repeat));
  return rng.next() >> 1;  // fits the query format's non-negative JSON integer
}

RunRecord run_planner(const PlanningContext& context, SimulatorWorkspace& ws,
                      const PlannerSpec& planner, const BenchProblem& problem, int problem_index,
                      int repeat, uint64_t seed, double budget) {
  RunRecord r;
  r.planner = planner.name;
  r.problem = problem_index;
  r.repeat = repeat;
  r.seed = seed;
  r.budget = budget;
  PlanningProblem p{problem.start, problem.goal, planner.params};
  p.params.seed = seed;
  p.params.budget = budget;
  try {
    const PlanResult result = plan(context, ws, p);
    r.counters = result.counters;
    r.n_solutions = result.n_solutions;
    if (!result.success) {
      r.failure = result.failure;
      return r;
    }
    const Trajectory t = [&] {
      try {
        return realize_path(context.sim, ws, p.start, result.best_path, p.goal, 1000);
      } catch (const Error&) {
        r.n_solutions = 0;  // the path failed the re-check: it is not a solution
        throw;
      }
    }();
    r.success = true;
    r.time_to_first_solution = result.time_to_first_solution;
    r.best_cost = t.cost;
  } catch (const std::exception& e) {  // nothing may leave a run (an OpenMP region)
    r.success = false;
    r.failure = std::string("error: ") + e.what();
  }
  return r;
}

std::vector<RunRecord> run_study(const PlanningContext& context,
                                 const std::vector<PlannerSpec>& planners,
                                 const std::vector<BenchProblem>& problems,
                                 const std::vector<StudyTask>& tasks, double budget,
                                 uint64_t study_seed, const StudyControl& control) {
  std::vector<std::optional<RunRecord>> done(tasks.size());
  std::vector<SimulatorWorkspace> workspaces;
  for (int t = 0; t < control.jobs; ++t) workspaces.emplace_back(context.sim);
  size_t finished = 0;
  std::string error;  // the first failure of on_run (a file that cannot be written): stop
#pragma omp parallel for num_threads(control.jobs) schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(tasks.size()); ++k) {
    bool stop = false;
#pragma omp critical(lazyboe_study_finished)
    stop = !error.empty();
    if (stop || (control.stop_requested && control.stop_requested())) continue;
    const StudyTask& task = tasks[k];
    RunRecord r = run_planner(context, workspaces[omp_get_thread_num()], planners[task.planner],
                              problems[task.problem], task.problem, task.repeat,
                              run_seed(study_seed, task.problem, task.repeat), budget);
#pragma omp critical(lazyboe_study_finished)
    {
      ++finished;
      try {
        if (control.on_run && error.empty()) control.on_run(r, finished, tasks.size());
      } catch (const std::exception& e) {
        error = e.what();
      }
      done[k] = std::move(r);
    }
  }
  if (!error.empty()) throw Error(error);
  std::vector<RunRecord> runs;
  for (auto& r : done) {
    if (r) runs.push_back(std::move(*r));
  }
  return runs;
}

}  // namespace lazyboe
