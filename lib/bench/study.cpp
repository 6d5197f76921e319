#include "lazyboe/bench/study.h"

#include <omp.h>

#include <algorithm>
#include <optional>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/text.h"
#include "lazyboe/planning/registry.h"

namespace lazyboe {

namespace {

// The index of `choice` among the choices of `planner`'s parameter `parameter`.
double choice_index(const std::string& planner, const std::string& parameter,
                    const std::string& choice) {
  for (const ParameterSpec& p : find_planner(planner)->parameters) {
    if (p.name != parameter) continue;
    const auto at = std::find(p.choices.begin(), p.choices.end(), choice);
    if (at != p.choices.end()) return static_cast<double>(at - p.choices.begin());
  }
  fail(planner, "has no " + parameter + " " + choice);
}

}  // namespace

const std::vector<StudyVariant>& study_variants(const std::string& planner) {
  static const std::vector<StudyVariant> none;
  static const std::vector<StudyVariant> lazyboe = {
      {"lazyboe", {}},
      {"lazyboe-transfer", {{"lazy_model", choice_index("lazyboe", "lazy_model", "transfer")}}}};
  static const std::vector<StudyVariant> sst = {{"sst-0.5x", {{"pruning_ratio", 0.5}}},
                                                {"sst-1x", {{"pruning_ratio", 1.0}}},
                                                {"sst-2x", {{"pruning_ratio", 2.0}}}};
  return planner == "lazyboe" ? lazyboe : planner == "sst" ? sst : none;
}

namespace {

// The names a study runs for a planner in "all": its variants, or itself.
std::vector<std::string> study_names(const PlannerInfo& info) {
  if (study_variants(info.name).empty()) return {info.name};
  std::vector<std::string> names;
  for (const StudyVariant& v : study_variants(info.name)) names.push_back(v.name);
  return names;
}

bool has_variant(const PlannerInfo& info, const std::string& name) {
  for (const StudyVariant& v : study_variants(info.name))
    if (v.name == name) return true;
  return false;
}

// What a planner's name means in --planners: the variant of that name when it has one
// (lazyboe), else every variant (sst), else the planner.
std::vector<std::string> named_planners(const PlannerInfo& info) {
  if (has_variant(info, info.name)) return {info.name};
  return study_names(info);
}

std::string study_names_text() {
  std::vector<std::string> names = {"all"};
  for (const PlannerInfo& info : planner_registry()) {
    names.push_back(info.name);
    for (const StudyVariant& v : study_variants(info.name))
      if (v.name != info.name) names.push_back(v.name);
  }
  return list_text(names);
}

PlannerSpec spec_named(const std::string& name) {
  for (const PlannerInfo& info : planner_registry()) {
    PlannerSpec s;
    s.planner = info.name;
    s.available = info.available(&s.unavailable_reason);
    s.name = name;
    if (study_variants(info.name).empty() && info.name == name) return s;
    for (const StudyVariant& v : study_variants(info.name)) {
      if (v.name != name) continue;
      s.parameters = v.values;
      return s;
    }
  }
  fail("--planners", "unknown planner '" + name + "' (expected " + study_names_text() + ")");
}

}  // namespace

std::vector<PlannerSpec> planner_specs(const std::string& list) {
  std::vector<std::string> names;
  std::stringstream in(list);
  for (std::string name; std::getline(in, name, ',');) {
    const PlannerInfo* info = find_planner(name);
    if (name == "all") {
      for (const PlannerInfo& i : planner_registry())
        for (const std::string& n : study_names(i)) names.push_back(n);
    } else if (info) {
      for (const std::string& n : named_planners(*info)) names.push_back(n);
    } else {
      names.push_back(name);
    }
  }
  if (names.empty()) fail("--planners", "no planner named");
  std::vector<PlannerSpec> specs;
  for (const std::string& name : names) {
    for (const PlannerSpec& other : specs) {
      if (other.name == name) fail("--planners", "'" + name + "' named twice");
    }
    specs.push_back(spec_named(name));
  }
  return specs;
}

void check_planner_specs(const PlanningContext& context, std::vector<PlannerSpec>& specs) {
  for (PlannerSpec& s : specs) {
    if (!s.available) continue;
    try {
      make_planner(s.planner, s.parameters)->setup(context);
    } catch (const Error& e) {
      s.available = false;
      s.unavailable_reason = e.what();
    }
  }
}

void search_only(std::vector<PlannerSpec>& specs) {
  for (PlannerSpec& s : specs) {
    const PlannerInfo* info = find_planner(s.planner);
    if (info && info->parameter("direct")) s.parameters.set("direct", 0);
  }
}

namespace {

// The returned trajectory's figures; the raw chain's come from the post-processing (the
// planner's own simulations of it, or its re-simulation: the same cost to the bit).
void record_trajectory(const PlanAnswer& a, RunRecord& r) {
  r.duration = a.trajectory.duration;
  r.stops = a.trajectory.stops;
  r.arc_length = a.trajectory.cost;
  if (a.raw) {
    r.best_cost = a.trajectory.cost;
    r.raw_duration = a.trajectory.duration;
    r.raw_stops = a.trajectory.stops;
    return;
  }
  const ExecutionStats& e = a.execution;
  r.best_cost = e.raw_cost;
  r.raw_duration = e.raw_duration;
  r.raw_stops = e.raw_stops;
  r.post_seconds = e.seconds;
  r.junctions = e.junctions;
  r.blends_kept = e.blends_kept;
  r.shortcuts = e.shortcuts;
}

}  // namespace

uint64_t run_seed(uint64_t study_seed, int problem, int repeat) {
  Random rng(study_seed, (static_cast<uint64_t>(problem) << 20) ^ static_cast<uint64_t>(repeat));
  return rng.next() >> 1;  // fits the query format's non-negative JSON integer
}

RunRecord run_planner(const PlanningContext& context, SimulatorWorkspace& ws,
                      const PlannerSpec& planner, const BenchProblem& problem, int problem_index,
                      int repeat, uint64_t seed, double budget, const ReturnOptions& output) {
  RunRecord r;
  r.planner = planner.name;
  r.problem = problem_index;
  r.repeat = repeat;
  r.seed = seed;
  r.budget = budget;
  PlanRequest request{planner.planner, planner.parameters, {}, output};
  request.problem.start = problem.start;
  request.problem.goal = problem.goal;
  request.problem.termination.budget = budget;
  request.problem.seed = seed;
  PlanAnswer a;
  try {
    a = answer_request(context, request, ws);
  } catch (const std::exception& e) {               // nothing may leave a run (an OpenMP region)
    r.failure = std::string("error: ") + e.what();  // a path that failed its re-check, too
    return r;
  }
  r.counters = a.result.counters;
  r.n_solutions = a.result.n_solutions;
  if (!a.result.success) {
    r.failure = a.result.failure;
    return r;
  }
  record_trajectory(a, r);
  r.found_by = a.result.found_by;
  r.success = true;
  r.time_to_first_solution = a.result.time_to_first_solution;
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
    RunRecord r =
        run_planner(context, workspaces[omp_get_thread_num()], planners[task.planner],
                    problems[task.problem], task.problem, task.repeat,
                    run_seed(study_seed, task.problem, task.repeat), budget, control.output);
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

int direct_solutions(const PlanningContext& context, const std::vector<BenchProblem>& problems) {
  SimulatorWorkspace ws(context.sim);
  int solved = 0;
  for (const BenchProblem& b : problems) {
    PlanningProblem p;
    p.start = b.start;
    p.goal = b.goal;
    solved += solved_by_direct_command(context.sim, ws, context.command, p);
  }
  return solved;
}

}  // namespace lazyboe
