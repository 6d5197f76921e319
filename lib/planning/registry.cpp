#include "lazyboe/planning/registry.h"

#include <algorithm>
#include <deque>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/text.h"
#include "lazyboe/planning/ompl/ompl_planners.h"
#include "lazyboe/planning/planners/boe.h"
#include "lazyboe/planning/planners/lazyboe.h"
#include "lazyboe/planning/planners/lazysp.h"
#include "lazyboe/planning/planners/rrt.h"
#include "lazyboe/planning/planners/sst.h"

namespace lazyboe {

const PlanningContext& DeclaredPlanner::context() const {
  if (!context_) fail(name(), "solve before setup");
  return *context_;
}

namespace {

// A deque: registering a planner keeps every reference to the others valid.
std::deque<PlannerInfo>& registry() {
  static std::deque<PlannerInfo> planners = {
      lazyboe_planner_info(),  // the paper's planner first: the default
      boe_planner_info(),         rrt_planner_info(),      sst_planner_info(),
      lazysp_planner_info(),      ompl_rrt_planner_info(), ompl_sst_planner_info(),
      ompl_kpiece_planner_info(),
  };
  return planners;
}

void check_new_planner(const PlannerInfo& info) {
  const std::string where = "register_planner";
  if (info.name.empty()) fail(where, "a planner needs a name");
  if (find_planner(info.name)) fail(where, "a planner '" + info.name + "' is registered already");
  if (!info.make) fail(where, "planner '" + info.name + "' has no factory (make)");
  for (const ParameterSpec& p : info.parameters) {
    if (p.name.empty()) fail(where, "planner '" + info.name + "': a parameter needs a name");
    const std::string known[] = {
        "id",   "start", "goal", "planner",         "stop_at_first",    "budget",
        "seed", "scene", "raw",  "sample_interval", "shortcut_attempts"};
    if (std::find(std::begin(known), std::end(known), p.name) != std::end(known))
      fail(where, "planner '" + info.name + "': '" + p.name + "' is a query field");
    for (const PlannerInfo& other : registry()) {
      const ParameterSpec* same = other.parameter(p.name);
      if (same && same->type != p.type)
        fail(where, "planner '" + info.name + "': parameter '" + p.name + "' has another type " +
                        "in " + other.name);
    }
  }
}

}  // namespace

const std::deque<PlannerInfo>& planner_registry() { return registry(); }

void register_planner(PlannerInfo info) {
  check_new_planner(info);
  registry().push_back(std::move(info));
}

const ParameterSpec* PlannerInfo::parameter(const std::string& key) const {
  for (const ParameterSpec& p : parameters)
    if (p.name == key) return &p;
  return nullptr;
}

bool PlannerInfo::available(std::string* why) const {
  if (needs.ompl && !ompl_available()) {
    if (why) *why = "built without OMPL (install libompl-dev and rebuild)";
    return false;
  }
  return true;
}

const PlannerInfo* find_planner(const std::string& name) {
  for (const PlannerInfo& info : planner_registry())
    if (info.name == name) return &info;
  return nullptr;
}

const PlannerInfo& planner_info(const std::string& name, const std::string& where) {
  const PlannerInfo* info = find_planner(name);
  if (!info) {
    fail(where, "unknown planner '" + name + "' (expected " + planner_names_text() + ")" +
                    did_you_mean(name, planner_names()));
  }
  return *info;
}

std::vector<std::string> planner_names() {
  std::vector<std::string> names;
  for (const PlannerInfo& info : planner_registry()) names.push_back(info.name);
  return names;
}

std::string planner_names_text() { return list_text(planner_names()); }

std::vector<std::string> all_parameter_names() {
  std::vector<std::string> out;
  for (const PlannerInfo& info : planner_registry()) {
    for (const ParameterSpec& p : info.parameters) {
      if (std::find(out.begin(), out.end(), p.name) == out.end()) out.push_back(p.name);
    }
  }
  return out;
}

std::unique_ptr<Planner> make_planner(const std::string& name, const ParameterValues& values) {
  const PlannerInfo& info = planner_info(name);
  ParameterValues resolved;
  for (const auto& [key, value] : values.all()) {
    const ParameterSpec* spec = info.parameter(key);
    if (!spec) fail(name, "no parameter '" + key + "'");
    const std::string why = spec->check(value);
    if (!why.empty()) fail(key, why);
    resolved.set(key, value);
  }
  for (const ParameterSpec& p : info.parameters) {
    if (!resolved.has(p.name) && p.has_fixed_default()) resolved.set(p.name, p.default_value);
  }
  return info.make(resolved);
}

namespace {

std::string needs_text(const PlannerInfo& info) {
  std::vector<std::string> needs;
  if (info.needs.bundle) needs.push_back("an edge bundle");
  if (info.needs.perturbation) needs.push_back("its perturbation analysis");
  if (info.needs.ompl) needs.push_back("OMPL");
  if (needs.empty()) return "a simulator (the bundle's sampling region and commands)";
  return list_text(needs, ", ");
}

const char* type_name(ParameterType t) {
  switch (t) {
    case ParameterType::Integer:
      return "integer";
    case ParameterType::Boolean:
      return "boolean";
    case ParameterType::Choice:
      return "choice";
    default:
      return "real";
  }
}

// A start already inside the goal region is answered, not refused (issue 30): the path of no
// motion, whatever the planner.
PlanResult start_in_goal() {
  PlanResult r;
  r.success = true;
  r.time_to_first_solution = 0;
  r.n_solutions = 1;
  r.best_cost = 0;
  r.found_by = "start";
  return r;
}

}  // namespace

std::string planner_list_text() {
  std::ostringstream o;
  for (const PlannerInfo& info : planner_registry()) {
    std::string why;
    o << info.name << ": " << info.description << "\n";
    o << "  needs: " << needs_text(info);
    if (!info.available(&why)) o << " (not available: " << why << ")";
    o << "\n";
    for (const ParameterSpec& p : info.parameters) {
      o << "  " << p.name << " (" << type_name(p.type) << ", " << p.range_text() << ", default "
        << p.default_text() << "): " << p.description << "\n";
    }
  }
  return o.str();
}

PlanResult plan(const PlanningContext& context, SimulatorWorkspace& ws, const std::string& planner,
                const ParameterValues& values, const PlanningProblem& problem, RolloutPool* pool) {
  const std::unique_ptr<Planner> p = make_planner(planner, values);
  p->setup(context);
  PlanningProblem resolved;
  const PlanningProblem* solved = &problem;
  if (needs_configurations(problem.goal) && !problem.goal.resolved) {
    resolved = problem;
    resolve_goal(context.sim, ws, resolved.start, resolved.seed, resolved.goal, context.end_poses);
    solved = &resolved;
  }
  validate_problem(context.sim, ws, *solved);
  if (solved->goal.contains(context.sim.robot, ws.robot, solved->start)) return start_in_goal();
  return p->solve(*solved, ws, pool);
}

}  // namespace lazyboe
