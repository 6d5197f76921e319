// The planner registry: each planner once, with its name, description, needs, parameters and
// factory. Query parsing, the query schema's planner list (checked by a test), lazyboe-bench's
// planners and `lazyboe-query --list-planners` all come from it. Adding a planner: one file
// pair under planners/ that defines its PlannerInfo, and one line in registry.cpp; or, from
// outside the library, register_planner().
#pragma once

#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "lazyboe/planning/parameters.h"
#include "lazyboe/planning/planner.h"

namespace lazyboe {

struct PlannerInfo {
  std::string name;
  std::string description;  // one line
  PlannerNeeds needs;
  std::vector<ParameterSpec> parameters;
  // Makes the planner from values for every parameter with a fixed default (make_planner
  // fills those in); parameters with a context default may be missing.
  std::function<std::unique_ptr<Planner>(const ParameterValues&)> make;

  const ParameterSpec* parameter(const std::string& name) const;
  // False when the planner is not built in (OMPL's, without OMPL); `why` says so.
  bool available(std::string* why = nullptr) const;
};

// The factory of planner class P, made from (values, identity) with the name and needs `info`
// declares (set them before this): what DeclaredPlanner's subclasses take.
template <class P>
decltype(PlannerInfo::make) planner_factory(const PlannerInfo& info) {
  static_assert(std::is_base_of_v<Planner, P>, "a planner derives from lazyboe::Planner");
  return [identity = PlannerIdentity{info.name, info.needs}](const ParameterValues& values) {
    return std::make_unique<P>(values, identity);
  };
}

// Every planner, in the order they are listed: the built-in ones, then those registered.
const std::deque<PlannerInfo>& planner_registry();

// Adds a planner defined outside the library (OMPL's "subclass base::Planner"): from then on
// queries can name it, lazyboe-bench can run it, and --list-planners and Python's planners()
// show it. Call it before planning starts (not while another thread plans or reads the
// registry). Throws Error for an empty or taken name, no factory, a parameter named like a
// query field, or a parameter another planner declares with another type.
void register_planner(PlannerInfo info);

// The planner of that name, or null.
const PlannerInfo* find_planner(const std::string& name);
// The same, throwing Error("<where>: unknown planner 'x' (expected lazyboe, boe, ...)").
const PlannerInfo& planner_info(const std::string& name, const std::string& where = "planner");

// Every planner's name, in the registry's order.
std::vector<std::string> planner_names();
// "lazyboe, boe, rrt, sst, lazysp, ompl-rrt, ompl-sst or ompl-kpiece".
std::string planner_names_text();

// Every parameter name any planner declares, each once.
std::vector<std::string> all_parameter_names();

// A planner with `values` checked against its declarations (Error("<name>: must be > 0") for
// a value out of range, Error("<planner>: no parameter 'x'") for one it does not declare) and
// the fixed defaults filled in.
std::unique_ptr<Planner> make_planner(const std::string& name, const ParameterValues& values);

// The registry as text, for `lazyboe-query --list-planners`: per planner its name,
// description, needs (and whether it is built in), and its parameters with type, default,
// range and description.
std::string planner_list_text();

// One query from start to finish: make_planner, setup, validate_problem, solve.
PlanResult plan(const PlanningContext& context, SimulatorWorkspace& ws, const std::string& planner,
                const ParameterValues& values, const PlanningProblem& problem,
                RolloutPool* pool = nullptr);

}  // namespace lazyboe
