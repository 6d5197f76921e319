// The planner registry and what comes from it: the query schema lists exactly the registered
// planners and every declared parameter with the same range; make_planner checks values and
// fills defaults; the listing of --list-planners names everything. validate_problem's
// checks and messages. The RolloutScheduler: the same results as running every rollout
// directly, waves bounded by the pool, and only needed rollouts run.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "lazyboe/common/error.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/planning/rollout_scheduler.h"
#include "lazyboe/sim/random.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

nlohmann::json query_schema() {
  std::ifstream in(source_path("schemas/query.schema.json"));
  return nlohmann::json::parse(in);
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Registry, SchemaListsExactlyTheRegisteredPlanners) {
  const nlohmann::json schema = query_schema();
  std::set<std::string> in_schema, registered;
  for (const auto& name : schema.at("properties").at("planner").at("enum"))
    in_schema.insert(name.get<std::string>());
  for (const PlannerInfo& info : planner_registry()) registered.insert(info.name);
  EXPECT_EQ(in_schema, registered);
  EXPECT_EQ(planner_registry().front().name, "lazyboe");  // the default planner
}

// A double: with a float default, json::value would read the bound as a float.
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Registry, SchemaDeclaresEveryParameterWithItsRange) {
  const nlohmann::json props = query_schema().at("properties");
  for (const PlannerInfo& info : planner_registry()) {
    for (const ParameterSpec& p : info.parameters) {
      SCOPED_TRACE(info.name + "." + p.name);
      ASSERT_TRUE(props.contains(p.name));
      const nlohmann::json& s = props.at(p.name);
      if (p.type == ParameterType::Choice) {
        EXPECT_EQ(s.at("enum").get<std::vector<std::string>>(), p.choices);
        EXPECT_FALSE(p.description.empty());
        continue;
      }
      const char* type = p.type == ParameterType::Boolean   ? "boolean"
                         : p.type == ParameterType::Integer ? "integer"
                                                            : "number";
      EXPECT_EQ(s.value("type", ""), type);
      if (std::isfinite(p.lower)) {
        EXPECT_EQ(s.value(p.lower_exclusive ? "exclusiveMinimum" : "minimum", kNaN), p.lower);
      }
      if (std::isfinite(p.upper)) {
        EXPECT_EQ(s.value("maximum", kNaN), p.upper);
      }
      EXPECT_FALSE(p.description.empty());
      EXPECT_TRUE(p.has_fixed_default() || !p.default_from.empty());
    }
    EXPECT_FALSE(info.description.empty()) << info.name;
  }
}

TEST(Registry, NamesAndLookups) {
  EXPECT_EQ(planner_names_text(),
            "lazyboe, boe, rrt, sst, lazysp, ompl-rrt, ompl-sst or ompl-kpiece");
  EXPECT_EQ(find_planner("prm"), nullptr);
  const std::string e = message_of([] { planner_info("prm"); });
  EXPECT_EQ(e, "planner: unknown planner 'prm' (expected " + planner_names_text() + ")");
  EXPECT_EQ(message_of([] { planner_info("lazyps"); }),
            "planner: unknown planner 'lazyps' (expected " + planner_names_text() +
                ") (did you mean 'lazysp'?)");
  EXPECT_TRUE(find_planner("lazyboe")->needs.perturbation);
  EXPECT_TRUE(find_planner("boe")->needs.bundle);
  EXPECT_FALSE(find_planner("boe")->needs.perturbation);
  EXPECT_FALSE(find_planner("rrt")->needs.bundle);
  EXPECT_TRUE(find_planner("lazysp")->needs.bundle);
  EXPECT_FALSE(find_planner("lazysp")->needs.perturbation);
  const std::vector<std::string> all = all_parameter_names();
  EXPECT_EQ(
      std::set<std::string>(all.begin(), all.end()),
      (std::set<std::string>{
          "theta",       "lazy_model", "goal_bias",          "selection_radius", "pruning_ratio",
          "epsilon",     "resolution", "risk_weight",        "edge_penalty",     "expansion_limit",
          "mark_weight", "direct",     "connect_radius",     "candidate_radius", "precheck",
          "approaches",  "goal_look",  "candidate_shortcut", "look_again",       "waypoints"}));
  EXPECT_EQ(all.size(), 20u);  // each once
}

// The refusals only: a planner registered here would stay for the other tests of a process that
// runs them all (the install test registers one and plans with it, examples/plan_one_query).
TEST(Registry, RegisterPlannerRefusesWhatWouldClash) {
  auto make = [](const ParameterValues&) -> std::unique_ptr<Planner> { return nullptr; };
  auto info = [&](const std::string& name, std::vector<ParameterSpec> parameters = {}) {
    PlannerInfo i;
    i.name = name;
    i.description = "a test planner";
    i.parameters = std::move(parameters);
    i.make = make;
    return i;
  };
  const size_t before = planner_registry().size();
  EXPECT_EQ(message_of([&] { register_planner(info("")); }),
            "register_planner: a planner needs a name");
  EXPECT_EQ(message_of([&] { register_planner(info("rrt")); }),
            "register_planner: a planner 'rrt' is registered already");
  PlannerInfo no_factory = info("mine");
  no_factory.make = nullptr;
  EXPECT_EQ(message_of([&] { register_planner(no_factory); }),
            "register_planner: planner 'mine' has no factory (make)");
  ParameterSpec budget = real_parameter("budget", 1, 0, true, "clashes with the query field");
  EXPECT_EQ(message_of([&] { register_planner(info("mine", {budget})); }),
            "register_planner: planner 'mine': 'budget' is a query field");
  ParameterSpec theta = real_parameter("theta", 1, 0, true, "a real theta");
  theta.type = ParameterType::Integer;
  EXPECT_NE(message_of([&] {
              register_planner(info("mine", {theta}));
            }).find("parameter 'theta' has another type"),
            std::string::npos);
  EXPECT_EQ(planner_registry().size(), before);
  EXPECT_EQ(find_planner("mine"), nullptr);
}

TEST(Registry, MakePlannerChecksValues) {
  EXPECT_EQ(message_of([] { make_planner("rrt", {{"theta", 0.3}}); }), "rrt: no parameter 'theta'");
  EXPECT_EQ(message_of([] { make_planner("boe", {{"theta", -1}}); }), "theta: must be > 0");
  EXPECT_EQ(message_of([] {
              make_planner("sst", {{"goal_bias", 1.5}});
            }),
            "goal_bias: must be in [0, 1]");
  EXPECT_EQ(message_of([] {
              make_planner("sst", {{"pruning_ratio", NAN}});
            }),
            "pruning_ratio: must be a finite number");
  EXPECT_NE(make_planner("sst", {{"pruning_ratio", 2.0}}), nullptr);
  EXPECT_NE(make_planner("lazyboe", {}), nullptr);
}

TEST(Registry, ParameterSpecTexts) {
  ParameterSpec p;
  p.name = "x";
  p.lower = 0;
  p.upper = 1;
  EXPECT_EQ(p.range_text(), "[0, 1]");
  EXPECT_EQ(p.check(0), "");
  EXPECT_EQ(p.check(1), "");
  EXPECT_EQ(p.check(-0.1), "must be in [0, 1]");
  p.lower_exclusive = true;
  EXPECT_EQ(p.check(0), "must be in (0, 1]");
  p.upper = INFINITY;
  EXPECT_EQ(p.range_text(), "> 0");
  p.type = ParameterType::Integer;
  EXPECT_EQ(p.check(2.5), "must be an integer");
  p.type = ParameterType::Boolean;
  EXPECT_EQ(p.check(2), "must be true or false");
  p.default_value = 1;
  EXPECT_EQ(p.default_text(), "true");
  p.type = ParameterType::Choice;
  p.choices = {"stored", "transfer"};
  EXPECT_EQ(p.range_text(), "stored or transfer");
  EXPECT_EQ(p.default_text(), "transfer");
  EXPECT_EQ(p.choice_index("stored"), 0);
  EXPECT_EQ(p.choice_index("other"), -1);
  EXPECT_EQ(p.check(1), "");
  EXPECT_EQ(p.check(2), "must be stored or transfer");
}

TEST(Registry, TheListingNamesEveryPlannerAndParameter) {
  const std::string text = planner_list_text();
  for (const PlannerInfo& info : planner_registry()) {
    EXPECT_TRUE(contains(text, info.name + ": " + info.description)) << info.name;
    for (const ParameterSpec& p : info.parameters)
      EXPECT_TRUE(contains(text, "  " + p.name + " (")) << info.name << "." << p.name;
  }
  EXPECT_TRUE(contains(text, "pruning_ratio (real, > 0, default 1)"));
  // Study variants are the bench's (lib/bench/study.h), not the planner's declaration.
  EXPECT_FALSE(contains(text, "study variants"));
}

// A planner that needs a bundle refuses a context without one, naming what is missing.
TEST(Registry, SetupRefusesAContextWithoutWhatThePlannerNeeds) {
  static const Scene scene("empty");
  const PlanningContext no_bundle{scene.sim};
  EXPECT_EQ(message_of([&] { make_planner("boe", {})->setup(no_bundle); }),
            "planner: boe needs an edge bundle");
  EXPECT_EQ(message_of([&] { make_planner("sst", {})->setup(no_bundle); }),
            "planner: sst needs a sampling box of 7 joints");
}

// A solve before any setup, or after a setup that failed, is one clear error naming the
// planner, for every library planner (built in or not).
TEST(Registry, SolveBeforeSetupIsAClearError) {
  static const Scene scene("empty");
  const PlanningContext no_bundle{scene.sim};
  SimulatorWorkspace ws(scene.sim);
  PlanningProblem problem;
  problem.start = JointVector::Zero(7);
  problem.goal.q = problem.start;
  for (const std::string& name : planner_names()) {
    std::unique_ptr<Planner> planner = make_planner(name, {});
    EXPECT_EQ(message_of([&] { planner->solve(problem, ws); }), name + ": solve before setup");
    if (name == "boe") {
      EXPECT_NE(message_of([&] { planner->setup(no_bundle); }), "");
      EXPECT_EQ(message_of([&] { planner->solve(problem, ws); }), "boe: solve before setup");
    }
  }
}

// ---- validate_problem ----------------------------------------------------------------------

const Scene& table() {
  static const Scene s("table");
  return s;
}

PlanningProblem ready_problem() {
  PlanningProblem p;
  p.start = JointVector(7);
  p.start << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  p.goal.q = p.start;
  p.goal.q[0] += 0.5;
  p.goal.tolerance = 0.1;
  return p;
}

std::string issue(const PlanningProblem& p) {
  SimulatorWorkspace ws(table().sim);
  const ProblemIssue i = find_problem_issue(table().sim, ws, p);
  return i.any() ? i.field + ": " + i.what : "";
}

TEST(ValidateProblem, AcceptsAValidProblem) {
  EXPECT_EQ(issue(ready_problem()), "");
  SimulatorWorkspace ws(table().sim);
  EXPECT_NO_THROW(validate_problem(table().sim, ws, ready_problem()));
}

TEST(ValidateProblem, NamesTheFieldAndTheReason) {
  PlanningProblem p = ready_problem();
  p.start[3] = 0.5;  // joint 4's upper limit is -0.0698
  EXPECT_EQ(issue(p),
            "start: outside the joint limits: joint 4 (panda_joint4) is 0.5, its limits (-3.0718, "
            "-0.0698)");
  p.start << 0, -45, 0, -135, 0, 90, 45;  // degrees
  EXPECT_EQ(issue(p),
            "start: outside the joint limits: joint 2 (panda_joint2) is -45, its limits (-1.7628, "
            "1.7628) (joint values are in rad, not degrees)");
  p = ready_problem();
  p.goal.q = JointVector::Zero(6);
  EXPECT_EQ(issue(p), "goal.q: expected 7 joint values");
  p = ready_problem();
  p.goal.q << 0, 1.2, 0, -0.8, 0, 1.5, 0;  // reaching down into the table
  EXPECT_EQ(issue(p), "goal.q: in collision with the environment");
  p.goal.q << 0, 0, 0, -3.0, 0, 0.2, 0;  // folded onto itself
  EXPECT_EQ(issue(p), "goal.q: in self-collision");
  p = ready_problem();
  p.goal.tolerance = 0.6;
  EXPECT_EQ(issue(p), "");  // the start in the goal is answered, not refused
  p = ready_problem();
  p.goal.kind = Goal::Kind::Position;
  p.goal.link = table().robot.tip_link();
  p.goal.position = Eigen::Vector3d(5, 0, 0.5);
  EXPECT_EQ(issue(p), "goal.position: unreachable: farther than the arm can reach");
  p.goal.link = 999;
  EXPECT_EQ(issue(p), "goal.link: no link 999");
  p = ready_problem();
  p.termination.budget = 0;
  EXPECT_EQ(issue(p), "budget: must be in (0, 1000000] s");
  SimulatorWorkspace ws(table().sim);
  EXPECT_EQ(message_of([&] { validate_problem(table().sim, ws, p); }),
            "budget: must be in (0, 1000000] s");
  p.termination.budget = 9.3e9;  // would overflow the deadline's nanosecond clock
  EXPECT_EQ(issue(p), "budget: must be in (0, 1000000] s");
  p.termination.budget = std::nan("");
  EXPECT_EQ(issue(p), "budget: must be in (0, 1000000] s");
}

// ---- RolloutScheduler ----------------------------------------------------------------------

struct Commands {
  std::vector<std::vector<double>> knots;
  std::vector<CommandProfile> profiles;
};

Commands random_commands(const Simulator& sim, int count) {
  Commands c;
  Random rng(5, 0);
  CommandSampling family;
  for (int k = 0; k < count; ++k) {
    c.knots.emplace_back();
    const double duration = sample_command_profile(sim.robot, family, rng, c.knots.back());
    c.profiles.push_back({nullptr, 0, sim.robot.dof, duration});
  }
  for (int k = 0; k < count; ++k) {
    c.profiles[k].knots = c.knots[k].data();
    c.profiles[k].n_knots = static_cast<int>(c.knots[k].size()) / sim.robot.dof;
  }
  return c;
}

TEST(RolloutScheduler, WithoutAPoolOfSeveralThreadsItIsOff) {
  EXPECT_FALSE(RolloutScheduler(table().sim, nullptr).enabled());
  RolloutPool one(table().sim, 1);
  EXPECT_FALSE(RolloutScheduler(table().sim, &one).enabled());
}

TEST(RolloutScheduler, GivesTheDirectResultsAndRunsOnlyWhatIsNeeded) {
  const Simulator& sim = table().sim;
  const Commands c = random_commands(sim, 40);
  const JointVector q0 = ready_problem().start;
  SimulatorWorkspace ws(sim);
  for (int threads : {2, 3}) {
    SCOPED_TRACE(threads);
    RolloutPool pool(sim, threads);
    RolloutScheduler s(sim, &pool);
    ASSERT_TRUE(s.enabled());
    s.begin(7, c.profiles.size());
    EXPECT_EQ(s.node(), 7);
    EXPECT_FALSE(s.planned());
    // Neighbours from 3 on; every third one is not needed.
    s.plan(3, [](size_t j) { return j % 3 != 0; });
    EXPECT_TRUE(s.planned());
    size_t taken = 0;
    for (size_t k = 3; k < c.profiles.size(); ++k) {
      if (k % 3 == 0) continue;
      const RolloutResult& r = s.take(k, q0.data(), [&](size_t j) { return c.profiles[j]; });
      const RolloutResult direct = simulate(sim, ws, q0, c.profiles[k]);
      EXPECT_EQ(r.status, direct.status) << k;
      EXPECT_EQ(r.ticks, direct.ticks) << k;
      EXPECT_EQ(r.qf, direct.qf) << k;
      ++taken;
    }
    EXPECT_EQ(s.rollouts_run(), taken) << "rollouts not needed were run, or some twice";
    // A wave holds at most kWavePerThread per thread: stopping after the first take leaves at
    // most that many run.
    s.begin(8, c.profiles.size());
    s.plan(0, [](size_t) { return true; });
    const size_t before = s.rollouts_run();
    s.take(0, q0.data(), [&](size_t j) { return c.profiles[j]; });
    EXPECT_EQ(s.rollouts_run() - before,
              std::min(c.profiles.size(), static_cast<size_t>(kWavePerThread * threads)));
  }
}

}  // namespace
}  // namespace lazyboe::test
