#include "lazyboe/planning/ompl/ompl_planners.h"

#include "lazyboe/common/error.h"
#include "lazyboe/planning/planners/sst.h"
#include "lazyboe/planning/planners/tree_search.h"

#ifdef LAZYBOE_HAVE_OMPL
#include <ompl/base/Goal.h>
#include <ompl/base/OptimizationObjective.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/StateSampler.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/spaces/RealVectorStateProjections.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/control/ControlSampler.h>
#include <ompl/control/PathControl.h>
#include <ompl/control/SpaceInformation.h>
#include <ompl/control/StatePropagator.h>
#include <ompl/control/planners/kpiece/KPIECE1.h>
#include <ompl/control/planners/rrt/RRT.h>
#include <ompl/control/planners/sst/SST.h>
#include <ompl/control/spaces/RealVectorControlSpace.h>
#include <ompl/util/Console.h>
#include <ompl/util/Exception.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include "lazyboe/sim/random.h"
#endif

namespace lazyboe {

namespace {

// Runs OMPL planner `name` on one problem (defined below; without OMPL it only refuses).
PlanResult plan_ompl(const PlanningContext& ctx, SimulatorWorkspace& ws,
                     const PlanningProblem& problem, const std::string& name,
                     const ParameterValues& values);

class OmplPlanner final : public DeclaredPlanner {
 public:
  using DeclaredPlanner::DeclaredPlanner;

  void prepare(const PlanningContext& context) override {
    if (!ompl_available()) {
      fail("planner", "'" + name() +
                          "' is not available: lazyboe was built without OMPL (install "
                          "libompl-dev and rebuild)");
    }
    check_sampling_box(context, name());
  }

  PlanResult solve(const PlanningProblem& problem, SimulatorWorkspace& ws, RolloutPool*) override {
    return plan_ompl(context(), ws, problem, name(), values());
  }
};

PlannerInfo ompl_info(const std::string& name, const std::string& description,
                      std::vector<ParameterSpec> parameters) {
  PlannerInfo info;
  info.name = name;
  info.description = description;
  info.needs.ompl = true;
  info.parameters = std::move(parameters);
  info.make = planner_factory<OmplPlanner>(info);
  return info;
}

}  // namespace

PlannerInfo ompl_rrt_planner_info() {
  return ompl_info("ompl-rrt", "OMPL's control RRT on our simulator, checks and goal",
                   {goal_bias_parameter()});
}

PlannerInfo ompl_sst_planner_info() {
  return ompl_info(
      "ompl-sst", "OMPL's control SST on our simulator, checks and goal; anytime",
      {goal_bias_parameter(), selection_radius_parameter(), pruning_ratio_parameter()});
}

PlannerInfo ompl_kpiece_planner_info() {
  return ompl_info("ompl-kpiece", "OMPL's control KPIECE1 on our simulator, checks and goal", {});
}

#ifndef LAZYBOE_HAVE_OMPL

bool ompl_available() { return false; }

void seed_ompl(uint64_t) {}

namespace {

PlanResult plan_ompl(const PlanningContext&, SimulatorWorkspace&, const PlanningProblem&,
                     const std::string& name, const ParameterValues&) {
  fail("planner", "'" + name + "' is not available: lazyboe was built without OMPL");
}

}  // namespace

#else

namespace ob = ompl::base;
namespace oc = ompl::control;

bool ompl_available() { return true; }

namespace {

using Clock = std::chrono::steady_clock;

// A control holds one command profile: [duration, knot count, knots (row-major, dof per knot),
// zero padding up to max_knots rows].
constexpr int kControlHeader = 2;

double* values(ob::State* s) { return s->as<ob::RealVectorStateSpace::StateType>()->values; }
const double* values(const ob::State* s) {
  return s->as<ob::RealVectorStateSpace::StateType>()->values;
}
double* values(oc::Control* c) { return c->as<oc::RealVectorControlSpace::ControlType>()->values; }
const double* values(const oc::Control* c) {
  return c->as<oc::RealVectorControlSpace::ControlType>()->values;
}

// OMPL seeds are 32-bit and must not be 0.
std::uint_fast32_t ompl_seed(uint64_t seed, uint64_t stream) {
  Random r(seed, stream);
  const auto s = static_cast<std::uint_fast32_t>(r.next() >> 32);
  return s == 0 ? 1 : s;
}

// Everything one query shares with the OMPL objects that call back into our code. The planners
// run single-threaded inside one plan_ompl call, so plain members suffice.
class Search {
 public:
  Search(const PlanningContext& ctx, SimulatorWorkspace& workspace, const PlanningProblem& p)
      : sim(ctx.sim),
        ctx(ctx),
        ws(workspace),
        problem(p),
        dof(ctx.sim.robot.dof),
        max_knots(1 + std::max(2, static_cast<int>(std::lround(ctx.command.max_duration /
                                                               ctx.command.knot_interval)))),
        control_rng(p.seed, 2),
        state_rng(p.seed, 3),
        goal_data_(ctx.sim.robot),
        last_from_(dof),
        last_to_(dof) {}

  const Simulator& sim;
  const PlanningContext& ctx;
  SimulatorWorkspace& ws;
  const PlanningProblem& problem;
  const int dof, max_knots;
  Random control_rng, state_rng;
  PlannerCounters counters;
  std::vector<double> knots;  // scratch of the control sampler
  Clock::time_point solve_start = Clock::now();
  double first_solution = std::numeric_limits<double>::quiet_NaN();
  int improvements = 0;  // improving exact solutions reported (SST)
  uint64_t tree_states = 0;

  CommandProfile profile(const double* control) const {
    return {control + kControlHeader, static_cast<int>(std::lround(control[1])), dof, control[0]};
  }

  // The propagator: one whole command, every check of the simulator. NaN marks an invalid end.
  void propagate(const double* from, const double* control, double* to) {
    const JointVector q0 = Eigen::Map<const Eigen::VectorXd>(from, dof);
    ++counters.simulations;
    const RolloutResult r = simulate(sim, ws, q0, profile(control));
    counters.collision_checks += r.collision_checks;
    if (!r.valid()) {
      std::fill(to, to + dof, std::numeric_limits<double>::quiet_NaN());
      has_last_ = false;
      return;
    }
    for (int i = 0; i < dof; ++i) to[i] = r.qf[i];
    last_from_ = q0;
    last_to_ = r.qf;
    last_length_ = r.path_length;
    has_last_ = true;
  }

  bool valid(const double* q) {
    for (int i = 0; i < dof; ++i) {
      if (std::isnan(q[i])) return false;
    }
    ++counters.collision_checks;
    return check_state(sim, ws, Eigen::Map<const Eigen::VectorXd>(q, dof)) == RolloutStatus::Valid;
  }

  // Arc length of the motion from a to b: the last rollout's (OMPL 1.5's SST asks for the cost
  // of a motion right after propagating it); for any other pair, the straight-line distance,
  // a lower bound of the arc length.
  double motion_length(const double* a, const double* b) const {
    const Eigen::Map<const Eigen::VectorXd> qa(a, dof), qb(b, dof);
    if (has_last_ && qa == last_from_ && qb == last_to_) return last_length_;
    return (qb - qa).norm();
  }

  double goal_distance(const double* q) {
    for (int i = 0; i < dof; ++i) {
      if (std::isnan(q[i])) return std::numeric_limits<double>::infinity();
    }
    return problem.goal.distance(sim.robot, goal_data_, Eigen::Map<const Eigen::VectorXd>(q, dof));
  }

  // Every one of the three planners tests each state it adds to its tree against the goal,
  // once; the first state inside the goal region is its first exact solution.
  void tree_state_tested(bool in_goal) {
    ++tree_states;
    if (in_goal && std::isnan(first_solution)) first_solution = elapsed();
  }

  // SST found an exact solution cheaper than its previous best (counted once per cost).
  void improved(double cost) {
    if (!(cost < best_reported_)) return;
    best_reported_ = cost;
    ++improvements;
    if (std::isnan(first_solution)) first_solution = elapsed();
  }

  double elapsed() const {
    return std::chrono::duration<double>(Clock::now() - solve_start).count();
  }

 private:
  RobotData goal_data_;
  JointVector last_from_, last_to_;
  double last_length_ = 0;
  bool has_last_ = false;
  double best_reported_ = std::numeric_limits<double>::infinity();
};

// Uniform states in the sampling box, from our Random (the planners' state samples).
class BoxSampler : public ob::StateSampler {
 public:
  BoxSampler(const ob::StateSpace* space, Search& s) : ob::StateSampler(space), s_(s) {}

  void sampleUniform(ob::State* state) override {
    const PlanningContext& c = s_.ctx;
    double* q = values(state);
    for (int i = 0; i < s_.dof; ++i)
      q[i] = s_.state_rng.uniform(c.sample_lower[i], c.sample_upper[i]);
  }
  // Not used by RRT, SST or KPIECE1; given for completeness.
  void sampleUniformNear(ob::State* state, const ob::State* near, double distance) override {
    const PlanningContext& p = s_.ctx;
    double* q = values(state);
    const double* c = values(near);
    for (int i = 0; i < s_.dof; ++i) {
      q[i] = std::clamp(c[i] + s_.state_rng.uniform(-distance, distance), p.sample_lower[i],
                        p.sample_upper[i]);
    }
  }
  void sampleGaussian(ob::State* state, const ob::State* mean, double std_dev) override {
    double* q = values(state);
    const double* m = values(mean);
    for (int i = 0; i < s_.dof; ++i) q[i] = m[i] + std_dev * s_.state_rng.normal();
  }

 private:
  Search& s_;
};

// Random commands of our family (the same draws as our rrt/sst make, from our Random).
class CommandSampler : public oc::ControlSampler {
 public:
  CommandSampler(const oc::ControlSpace* space, Search& s) : oc::ControlSampler(space), s_(s) {}

  using oc::ControlSampler::sample;
  void sample(oc::Control* control) override {
    const double duration =
        sample_command_profile(s_.sim.robot, s_.ctx.command, s_.control_rng, s_.knots);
    const int n_knots = static_cast<int>(s_.knots.size()) / s_.dof;
    if (n_knots > s_.max_knots) fail("planner", "command profile has more knots than expected");
    double* v = values(control);
    v[0] = duration;
    v[1] = n_knots;
    std::copy(s_.knots.begin(), s_.knots.end(), v + kControlHeader);
    std::fill(v + kControlHeader + s_.knots.size(), v + kControlHeader + s_.max_knots * s_.dof,
              0.0);
  }

 private:
  Search& s_;
};

class Propagator : public oc::StatePropagator {
 public:
  Propagator(const oc::SpaceInformationPtr& si, Search& s) : oc::StatePropagator(si), s_(s) {}
  void propagate(const ob::State* state, const oc::Control* control, double /*duration*/,
                 ob::State* result) const override {
    s_.propagate(values(state), values(control), values(result));
  }

 private:
  Search& s_;
};

class ValidityChecker : public ob::StateValidityChecker {
 public:
  ValidityChecker(const ob::SpaceInformationPtr& si, Search& s)
      : ob::StateValidityChecker(si), s_(s) {}
  bool isValid(const ob::State* state) const override { return s_.valid(values(state)); }

 private:
  Search& s_;
};

class GoalRegion : public ob::GoalSampleableRegion {
 public:
  GoalRegion(const ob::SpaceInformationPtr& si, Search& s) : ob::GoalSampleableRegion(si), s_(s) {
    setThreshold(s.problem.goal.tolerance);
  }
  double distanceGoal(const ob::State* state) const override {
    return s_.goal_distance(values(state));
  }
  // Inclusive, as Goal::contains (OMPL's GoalRegion uses distance < threshold).
  bool isSatisfied(const ob::State* state, double* distance) const override {
    const double d = distanceGoal(state);
    if (distance) *distance = d;
    const bool in = d <= threshold_;
    s_.tree_state_tested(in);
    return in;
  }
  bool isSatisfied(const ob::State* state) const override {
    return distanceGoal(state) <= threshold_;
  }
  void sampleGoal(ob::State* state) const override {
    const JointVector& q = s_.problem.goal.q;
    std::copy(q.data(), q.data() + s_.dof, values(state));
  }
  unsigned int maxSampleCount() const override {
    return s_.problem.goal.kind == lazyboe::Goal::Kind::Joint ? 1 : 0;
  }

 private:
  Search& s_;
};

// Cost = simulated arc length. isSatisfied(cost) is where OMPL 1.5.2's SST tells that it has
// a new, cheaper exact solution (it calls it exactly then, to decide whether to stop).
class ArcLengthObjective : public ob::OptimizationObjective {
 public:
  ArcLengthObjective(const ob::SpaceInformationPtr& si, Search& s)
      : ob::OptimizationObjective(si), s_(s) {
    description_ = "simulated joint-space arc length";
  }
  ob::Cost stateCost(const ob::State*) const override { return identityCost(); }
  ob::Cost motionCost(const ob::State* a, const ob::State* b) const override {
    return ob::Cost(s_.motion_length(values(a), values(b)));
  }
  bool isSatisfied(ob::Cost c) const override {
    s_.improved(c.value());
    return s_.problem.termination.stop_at_first;
  }

 private:
  Search& s_;
};

// The planners with their own generator seeded from the query (goal bias, selection draws).
template <class P>
class Seeded : public P {
 public:
  Seeded(const oc::SpaceInformationPtr& si, std::uint_fast32_t seed) : P(si) {
    this->rng_.setLocalSeed(seed);
  }
};

std::once_flag& log_once() {
  static std::once_flag flag;
  return flag;
}

std::once_flag& seed_once() {
  static std::once_flag flag;
  return flag;
}

// OMPL writes information messages to stdout, which carries our results: warnings and errors
// only (on stderr).
void quiet_ompl() {
  std::call_once(log_once(), [] { ompl::msg::setLogLevel(ompl::msg::LOG_WARN); });
}

}  // namespace

void seed_ompl(uint64_t seed) {
  quiet_ompl();
  std::call_once(seed_once(), [seed] { ompl::RNG::setSeed(ompl_seed(seed, 4)); });
}

namespace {

// States: the sampling box, widened to hold the start and a joint goal.
std::shared_ptr<ob::RealVectorStateSpace> state_space(Search& search) {
  const PlanningContext& ctx = search.ctx;
  const PlanningProblem& problem = search.problem;
  const int n = search.dof;
  auto space = std::make_shared<ob::RealVectorStateSpace>(n);
  ob::RealVectorBounds bounds(n);
  for (int i = 0; i < n; ++i) {
    double lo = std::min(ctx.sample_lower[i], problem.start[i]);
    double hi = std::max(ctx.sample_upper[i], problem.start[i]);
    if (problem.goal.kind == Goal::Kind::Joint) {
      lo = std::min(lo, problem.goal.q[i]);
      hi = std::max(hi, problem.goal.q[i]);
    }
    bounds.setLow(i, lo);
    bounds.setHigh(i, hi);
  }
  space->setBounds(bounds);
  space->setStateSamplerAllocator([&search](const ob::StateSpace* s) -> ob::StateSamplerPtr {
    return std::make_shared<BoxSampler>(s, search);
  });
  return space;
}

// Controls: duration, knot count, knots.
std::shared_ptr<oc::RealVectorControlSpace> control_space(
    Search& search, const std::shared_ptr<ob::RealVectorStateSpace>& space) {
  const CommandSampling& command = search.ctx.command;
  const RobotModel& robot = search.sim.robot;
  const int n = search.dof;
  const int control_dim = kControlHeader + search.max_knots * n;
  auto cspace = std::make_shared<oc::RealVectorControlSpace>(space, control_dim);
  ob::RealVectorBounds cbounds(control_dim);
  cbounds.setLow(0, command.min_duration);
  cbounds.setHigh(0, std::max(command.max_duration, command.min_duration + 1e-9));
  cbounds.setLow(1, 2);
  cbounds.setHigh(1, std::max(search.max_knots, 3));
  for (int k = 0; k < search.max_knots; ++k) {
    for (int i = 0; i < n; ++i) {
      cbounds.setLow(kControlHeader + k * n + i, -robot.dq_max[i]);
      cbounds.setHigh(kControlHeader + k * n + i, robot.dq_max[i]);
    }
  }
  cspace->setBounds(cbounds);
  cspace->setControlSamplerAllocator([&search](const oc::ControlSpace* c) -> oc::ControlSamplerPtr {
    return std::make_shared<CommandSampler>(c, search);
  });
  return cspace;
}

std::shared_ptr<ob::ProblemDefinition> problem_definition(
    Search& search, const oc::SpaceInformationPtr& si,
    const std::shared_ptr<ob::RealVectorStateSpace>& space) {
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  ob::ScopedState<> start(space);
  for (int i = 0; i < search.dof; ++i) start[i] = search.problem.start[i];
  pdef->addStartState(start);
  pdef->setGoal(std::make_shared<GoalRegion>(si, search));
  pdef->setOptimizationObjective(std::make_shared<ArcLengthObjective>(si, search));
  // Later OMPL versions also report SST's improving solutions here (counted once per cost).
  pdef->setIntermediateSolutionCallback(
      [&search](const ob::Planner*, const std::vector<const ob::State*>&, const ob::Cost c) {
        search.improved(c.value());
      });
  return pdef;
}

ob::PlannerPtr ompl_planner(const std::string& name, const ParameterValues& values,
                            const Search& search, const oc::SpaceInformationPtr& si,
                            const std::shared_ptr<ob::RealVectorStateSpace>& space) {
  const std::uint_fast32_t planner_seed = ompl_seed(search.problem.seed, 5);
  if (name == "ompl-rrt") {
    auto rrt = std::make_shared<Seeded<oc::RRT> >(si, planner_seed);
    rrt->setGoalBias(values.get("goal_bias"));
    return rrt;
  }
  if (name == "ompl-sst") {
    auto sst = std::make_shared<Seeded<oc::SST> >(si, planner_seed);
    sst->setGoalBias(values.get("goal_bias"));
    sst->setSelectionRadius(values.get("selection_radius"));
    sst->setPruningRadius(values.get("pruning_ratio") * values.get("selection_radius"));
    return sst;
  }
  auto kpiece = std::make_shared<Seeded<oc::KPIECE1> >(si, planner_seed);
  // Projection: the first three joints (the ones that move the arm most), grid cells of a
  // twentieth of the sampling box, as OMPL infers for its own projections. Fixed, unlike
  // RealVectorStateSpace's default random linear projection, so a query is repeatable.
  std::vector<unsigned int> joints;
  std::vector<double> cells;
  for (int i = 0; i < std::min(3, search.dof); ++i) {
    joints.push_back(static_cast<unsigned int>(i));
    cells.push_back((search.ctx.sample_upper[i] - search.ctx.sample_lower[i]) / 20);
  }
  kpiece->setProjectionEvaluator(
      std::make_shared<ob::RealVectorOrthogonalProjectionEvaluator>(space, cells, joints));
  return kpiece;
}

// The solution path as our commands, each re-simulated for its cost.
void take_solution(const std::string& name, Search& search, const ob::ProblemDefinition& pdef,
                   PlanResult& result) {
  const auto path = std::static_pointer_cast<oc::PathControl>(pdef.getSolutionPath());
  const int n = search.dof;
  JointVector q = search.problem.start;
  double cost = 0;
  for (const oc::Control* c : path->getControls()) {
    const CommandProfile p = search.profile(values(c));
    result.best_path.push_back(
        {-1, std::vector<double>(p.knots, p.knots + p.n_knots * n), p.duration});
    // The same deterministic rollout the planner made: its arc length is the step's cost.
    const RolloutResult r = simulate(search.sim, search.ws, q, p);
    if (!r.valid()) fail("planner", name + " returned a command that fails simulation");
    cost += r.path_length;
    q = r.qf;
  }
  result.success = true;
  result.best_cost = cost;
  result.time_to_first_solution =
      std::isnan(search.first_solution) ? search.elapsed() : search.first_solution;
  result.n_solutions = name == "ompl-sst" ? std::max(1, search.improvements) : 1;
}

PlanResult solve_with_ompl(const std::string& name, const ParameterValues& values, Search& search) {
  auto space = state_space(search);
  auto cspace = control_space(search, space);
  auto si = std::make_shared<oc::SpaceInformation>(space, cspace);
  si->setStatePropagator(std::make_shared<Propagator>(si, search));
  si->setStateValidityChecker(std::make_shared<ValidityChecker>(si, search));
  si->setPropagationStepSize(1.0);  // one step = one whole command
  si->setMinMaxControlDuration(1, 1);
  si->setup();
  const auto pdef = problem_definition(search, si, space);
  const ob::PlannerPtr planner = ompl_planner(name, values, search, si, space);
  planner->setProblemDefinition(pdef);
  planner->setup();

  const Termination& termination = search.problem.termination;
  const ob::PlannerTerminationCondition ptc = ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(std::max(0.0, termination.budget - search.elapsed())),
      ob::PlannerTerminationCondition([&termination] { return termination.cancelled(); }));
  const ob::PlannerStatus status = planner->solve(ptc);

  PlanResult result;
  result.counters = search.counters;
  result.counters.nodes = 1 + search.tree_states;  // the start and every state added
  if (status == ob::PlannerStatus::EXACT_SOLUTION && pdef->hasExactSolution()) {
    take_solution(name, search, *pdef, result);
  } else if (status == ob::PlannerStatus::INVALID_START) {
    result.failure = "OMPL rejected the start state (" + status.asString() + ")";
  } else {
    result.failure = "no solution within the time budget";
  }
  return result;
}

PlanResult plan_ompl(const PlanningContext& ctx, SimulatorWorkspace& ws,
                     const PlanningProblem& problem, const std::string& name,
                     const ParameterValues& values) {
  const int n = ctx.sim.robot.dof;
  if (problem.start.size() != n) fail("start", "expected " + std::to_string(n) + " joints");
  seed_ompl(problem.seed);
  Search search(ctx, ws, problem);  // outlives every OMPL object of solve_with_ompl
  // The clock starts here, as our planners' does at their start: OMPL's setup is part of the
  // time to first solution and of the budget.
  search.solve_start = Clock::now();
  try {
    return solve_with_ompl(name, values, search);
  } catch (const ompl::Exception& e) {
    fail("planner", name + ": OMPL: " + e.what());
  }
}

}  // namespace

#endif

}  // namespace lazyboe
