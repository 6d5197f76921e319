// Planning queries through the lazyboe-query tool, on one small dense bundle built with the real
// tools (lazyboe-build, lazyboe-perturb). Covered: the tools build the same bundle as the
// library (test_planners plans on that one); every planner solves an easy problem; every
// returned trajectory passes the independent re-validation of planning_fixture; the output is
// made of simulated edges only, and LazyBoE does take edges lazily while BoE never does;
// identical results for a fixed seed, and with parallel rollouts; error results for bad query
// lines while the rest of the batch succeeds. Bundles, streams and outputs: test_query_io_cli.
//
// Run time matters (the whole binary should stay well under a minute on two cores): one bundle
// of 2000 edges in a small region (p = 4 perturbations) is built once per process, budgets
// are 1-3 s, and batches are a handful of queries, mostly `stop_at_first`.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/sim/simulator.h"
#include "planning_fixture.h"
#include "query_cli_util.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// ------------------------------------------------------------------------------------------
// 0. The tools and the library build the same bundle
// ------------------------------------------------------------------------------------------

// Every field of a bundle built by the tools equals the library's bit for bit, but the wall-clock
// times.
void expect_same_bundle(const Bundle& a, const Bundle& b) {
  const BundleHeader& h = a.header;
  const BundleHeader& g = b.header;
  EXPECT_EQ(h.schema_version, g.schema_version);
  EXPECT_EQ(h.tool_version, g.tool_version);
  EXPECT_EQ(h.complete, g.complete);
  EXPECT_EQ(h.robot_name, g.robot_name);
  EXPECT_EQ(h.robot_config, g.robot_config);
  EXPECT_EQ(h.robot_hash, g.robot_hash);
  EXPECT_EQ(h.env_name, g.env_name);
  EXPECT_EQ(h.env_file, g.env_file);
  EXPECT_EQ(h.env_hash, g.env_hash);
  EXPECT_EQ(h.dof, g.dof);
  EXPECT_EQ(h.seed, g.seed);
  EXPECT_EQ(h.target_edges, g.target_edges);
  EXPECT_TRUE(same_array("region_lower", h.region_lower, g.region_lower));
  EXPECT_TRUE(same_array("region_upper", h.region_upper, g.region_upper));
  EXPECT_TRUE(
      same_array("durations, scales, rates, theta",
                 std::vector<double>{h.min_duration, h.max_duration, h.knot_interval,
                                     h.velocity_scale, h.limit_scale, h.control_rate,
                                     h.sample_interval, h.design_theta, h.simulated_seconds},
                 std::vector<double>{g.min_duration, g.max_duration, g.knot_interval,
                                     g.velocity_scale, g.limit_scale, g.control_rate,
                                     g.sample_interval, g.design_theta, g.simulated_seconds}));
  EXPECT_EQ(h.integrator, g.integrator);
  EXPECT_EQ(h.substeps, g.substeps);
  EXPECT_EQ(h.attempts, g.attempts);
  EXPECT_EQ(h.valid, g.valid);
  EXPECT_EQ(h.rejected, g.rejected);
  EXPECT_EQ(h.start_resamples, g.start_resamples);
  EXPECT_EQ(a.size(), static_cast<size_t>(kEdges));
  expect_same_edge_arrays(a, b);
  const Perturbation& p = a.perturbation;
  const Perturbation& q = b.perturbation;
  EXPECT_EQ(p.present, q.present);
  EXPECT_EQ(p.complete, q.complete);
  EXPECT_TRUE(same_array("theta, simulated_seconds",
                         std::vector<double>{p.theta, p.simulated_seconds},
                         std::vector<double>{q.theta, q.simulated_seconds}));
  EXPECT_EQ(p.perturbations, q.perturbations);
  EXPECT_EQ(p.seed, q.seed);
  expect_same_perturbation_arrays(p, q);
}

// test_planners plans on the library's bundle: it is this one.
TEST(QueryCli, TheToolsBuildTheSameBundleAsTheLibrary) {
  const Fixture& f = fixture();
  const SmallBundles built = build_small_bundles();
  {
    SCOPED_TRACE("unperturbed");
    const Bundle tool = read_bundle(f.unperturbed);
    EXPECT_FALSE(tool.perturbation.present);
    expect_same_bundle(tool, *built.unperturbed);
  }
  SCOPED_TRACE("perturbed");
  EXPECT_TRUE(f.data.perturbation.complete);
  expect_same_bundle(f.data, *built.perturbed);
}

// ------------------------------------------------------------------------------------------
// 1. Every planner finds a path on an easy problem
// ------------------------------------------------------------------------------------------

TEST(QueryCli, EveryPlannerSolvesAnEasyProblem) {
  const Fixture& f = fixture();
  ASSERT_GE((f.a - f.b).norm(), 0.35);
  ASSERT_LE((f.a - f.b).norm(), 0.45);
  const ToolRun& t = tool_easy_run();
  ASSERT_EQ(t.r.exit_code, 0) << describe(t.r);
  ASSERT_TRUE(t.problems.empty()) << t.problems;
  ASSERT_EQ(t.results.size(), kPlanners.size()) << describe(t.r);
  for (size_t i = 0; i < kPlanners.size(); ++i) {
    const json& r = t.results[i];
    SCOPED_TRACE("tool, " + kPlanners[i]);
    EXPECT_EQ(r.value("id", ""), kPlanners[i]);
    EXPECT_EQ(r.value("planner", ""), kPlanners[i]);
    expect_solved(r, kPlanners[i]);
    EXPECT_GE(r.value("n_solutions", 0), 1);
    EXPECT_TRUE(r.contains("trajectory")) << "no inline trajectory";
    EXPECT_FALSE(r.contains("failure"));
    std::cout << "[ path    ] " << kPlanners[i] << ": edges " << r.value("edges", json()).dump()
              << ", cost " << r.value("best_cost", json()).dump() << ", counters "
              << r.value("counters", json()).dump() << "\n";
  }
}

// ------------------------------------------------------------------------------------------
// 2. Every returned trajectory passes an independent re-validation
// ------------------------------------------------------------------------------------------

TEST(QueryCli, EveryReturnedTrajectoryPassesIndependentRevalidation) {
  const Fixture& f = fixture();
  int checked = 0;
  const ToolRun& t = tool_easy_run();
  for (const json& r : t.results) {
    if (!r.contains("trajectory")) continue;
    const std::string planner = r.value("planner", "");
    SCOPED_TRACE("tool (easy batch), " + planner);
    EXPECT_EQ(validate(f, trajectory_from_json(r), f.a, f.b, kTolerance, planner), "");
    ++checked;
  }
  const ToolRun& d = deterministic_run();
  const std::vector<json> queries = deterministic_queries();
  for (size_t i = 0; i < d.results.size() && i < queries.size(); ++i) {
    const json& r = d.results[i];
    if (!r.contains("trajectory")) continue;
    SCOPED_TRACE("tool (stop_at_first batch), " + r.value("id", ""));
    const JointVector start = joint(queries[i]["start"].get<std::vector<double>>());
    const JointVector goal = joint(queries[i]["goal"]["q"].get<std::vector<double>>());
    EXPECT_EQ(validate(f, trajectory_from_json(r), start, goal, kTolerance, r.value("planner", "")),
              "");
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(kPlanners.size() + queries.size()))
      << "every query should have returned a trajectory";
}

// ------------------------------------------------------------------------------------------
// 3. No lazy edge in any output
// ------------------------------------------------------------------------------------------

// A post-processed result: its bundle edges simulated one after another from the start give
// the raw chain it reports (duration and arc length). Empty when they agree.
std::string resimulate_raw_chain(const Fixture& f, const JointVectorRef& start,
                                 const std::vector<CommandProfile>& commands, const json& r) {
  SimulatorWorkspace ws(f.sim);
  JointVector q = start;
  double duration = 0, cost = 0;
  for (size_t k = 0; k < commands.size(); ++k) {
    const RolloutResult s = simulate(f.sim, ws, q, commands[k]);
    if (!s.valid()) return "step " + std::to_string(k) + ": " + rollout_status_name(s.status);
    q = s.qf;
    duration += s.duration;
    cost += s.path_length;
  }
  std::ostringstream p;
  p.precision(17);
  if (!(std::abs(duration - r.value("raw_duration", -1.0)) <= 1e-9))
    p << "raw chain duration " << duration << " vs raw_duration " << r["raw_duration"] << "\n";
  if (!(std::abs(cost - r.value("raw_cost", -1.0)) <= 1e-9))
    p << "raw chain arc length " << cost << " vs raw_cost " << r["raw_cost"] << "\n";
  if (r.value("raw_stops", -1) != static_cast<int>(commands.size()) - 1)
    p << "raw_stops " << r["raw_stops"] << " for " << commands.size() << " steps\n";
  return p.str();
}

TEST(QueryCli, OutputsAreMadeOfSimulatedEdgesOnly) {
  const Fixture& f = fixture();
  bool lazy_somewhere = false;
  auto check_tool = [&](const ToolRun& t, const std::vector<JointVector>& starts,
                        const std::string& what) {
    for (size_t i = 0; i < t.results.size() && i < starts.size(); ++i) {
      const json& r = t.results[i];
      const std::string planner = r.value("planner", "");
      SCOPED_TRACE(what + ", " + r.value("id", ""));
      if (!r.contains("counters")) continue;
      const uint64_t lazy = r["counters"].value("lazy_edges", uint64_t{0});
      if (planner == "lazyboe") lazy_somewhere |= lazy > 0;
      if (planner == "boe") {
        EXPECT_EQ(lazy, 0u);
      }
      if (!r.contains("trajectory") || !is_bundle_planner(planner)) continue;
      const Trajectory traj = trajectory_from_json(r);
      bool edges_ok = !traj.edges.empty();
      for (int64_t e : traj.edges) edges_ok &= e >= 0 && e < static_cast<int64_t>(f.view.size());
      ASSERT_TRUE(edges_ok) << r["edges"].dump();
      if (r.contains("post_processing")) {
        EXPECT_EQ(resimulate_raw_chain(f, starts[i], bundle_commands(f, traj.edges), r), "");
      } else {
        EXPECT_EQ(resimulate(f, starts[i], bundle_commands(f, traj.edges), traj), "");
      }
    }
  };
  std::vector<JointVector> starts(kPlanners.size(), f.a);
  check_tool(tool_easy_run(), starts, "tool (easy batch)");
  starts.clear();
  for (const json& q : deterministic_queries())
    starts.push_back(joint(q["start"].get<std::vector<double>>()));
  check_tool(deterministic_run(), starts, "tool (stop_at_first batch)");
  EXPECT_TRUE(lazy_somewhere)
      << "lazyboe never took an edge lazily (counters.lazy_edges = 0 everywhere)";
}

// ------------------------------------------------------------------------------------------
// 4. Fixed seed, one job: identical results
// ------------------------------------------------------------------------------------------

TEST(QueryCli, FixedSeedAndOneJobGiveIdenticalResults) {
  const std::vector<json> queries = deterministic_queries();
  const ToolRun& first = deterministic_run();
  expect_batch_ran(first, queries.size());
  const ToolRun second =
      run_batch("deterministic", queries, {"--trajectories", "inline", "--jobs", "1", "--quiet"});
  expect_batch_ran(second, queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    const json& x = first.results[i];
    const json& y = second.results[i];
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    expect_solved(x, "first run");
    EXPECT_EQ(x.value("success", false), y.value("success", false));
    EXPECT_EQ(x.value("n_solutions", -1), y.value("n_solutions", -2));
    EXPECT_EQ(x.value("edges", json()), y.value("edges", json()));
    EXPECT_TRUE(x.value("trajectory", json()) == y.value("trajectory", json()))
        << "trajectories differ";
    // Everything else too, but the wall-clock time.
    EXPECT_EQ(timeless(x).dump(), timeless(y).dump());
  }
}

TEST(QueryCli, ParallelRolloutsGiveTheSameAnswersAsOneThread) {
  const std::vector<json> queries = deterministic_queries();
  const ToolRun& one = deterministic_run();
  expect_batch_ran(one, queries.size());
  const ToolRun three =
      run_batch("deterministic", queries,
                {"--trajectories", "inline", "--jobs", "1", "--sim-threads", "3", "--quiet"});
  expect_batch_ran(three, queries.size());
  const ToolRun nested =
      run_batch("deterministic", queries,
                {"--trajectories", "inline", "--jobs", "2", "--sim-threads", "2", "--quiet"});
  expect_batch_ran(nested, queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    expect_solved(three.results[i], "--sim-threads 3");
    EXPECT_EQ(timeless(one.results[i]).dump(), timeless(three.results[i]).dump());
    EXPECT_EQ(timeless(one.results[i]).dump(), timeless(nested.results[i]).dump());
  }
}

TEST(QueryCli, BadSimThreadsAreRefusedWithOneLine) {
  const Fixture& f = fixture();
  const std::string good =
      write_temp_file("simthreads/one.jsonl", query("q", f.a, f.b, "boe", 1, true).dump() + "\n");
  for (const std::string bad : {"-1", "two", "2000"}) {
    SCOPED_TRACE(bad);
    const ToolRun t = query_tool({"--bundle", f.path, "--queries", good, "--sim-threads", bad});
    EXPECT_NE(t.r.exit_code, 0) << describe(t.r);
    EXPECT_EQ(count_lines(t.r.err), 1) << describe(t.r);
    EXPECT_TRUE(contains(t.r.err, "--sim-threads")) << describe(t.r);
    EXPECT_FALSE(contains(t.r.err, "loaded")) << describe(t.r);
    EXPECT_TRUE(t.r.out.empty()) << describe(t.r);
  }
}

TEST(QueryCli, MoreSimThreadsThanCoresWarns) {
  const Fixture& f = fixture();
  const std::string one =
      write_temp_file("simthreads/warn.jsonl", query("q", f.a, f.b, "boe", 1, true).dump() + "\n");
  const int threads = 4 * static_cast<int>(std::thread::hardware_concurrency()) + 4;
  const ToolRun t =
      query_tool({"--bundle", f.path, "--queries", one, "--sim-threads", std::to_string(threads)});
  ASSERT_EQ(t.r.exit_code, 0) << describe(t.r);
  EXPECT_TRUE(contains(t.r.err, "warning: --jobs 1 x --sim-threads " + std::to_string(threads)))
      << describe(t.r);
  ASSERT_EQ(t.results.size(), 1u) << describe(t.r);
  expect_solved(t.results[0], "many sim threads");
}

// ------------------------------------------------------------------------------------------
// 5. Bad query lines: error results naming the line; the rest of the batch still succeeds
// ------------------------------------------------------------------------------------------

TEST(QueryCli, BadLinesGetErrorResultsAndTheOthersStillSucceed) {
  const Fixture& f = fixture();
  SimulatorWorkspace ws(f.sim);
  // A start in the table: lean the good start forward until check_state says so.
  JointVector collide = f.a;
  RolloutStatus s = RolloutStatus::Valid;
  while (s == RolloutStatus::Valid && collide[1] + 0.05 < f.robot.q_max[1]) {
    collide[1] += 0.05;
    s = check_state(f.sim, ws, collide);
  }
  ASSERT_EQ(s, RolloutStatus::EnvCollision)
      << "leaning forward ended with " << rollout_status_name(s);
  JointVector outside = f.a;
  outside[0] = f.robot.q_max[0] + 0.1;
  ASSERT_EQ(check_state(f.sim, ws, outside), RolloutStatus::PositionLimit);

  json six = query("six", f.a, f.b, "lazyboe", 1, true);
  const std::vector<double> seven = vec(f.a);
  six["start"] = std::vector<double>(seven.begin(), seven.begin() + 6);
  std::vector<std::string> lines = {
      query("good-1", f.a, f.b, "lazyboe", 2, true).dump(),       // line 1
      query("collide", collide, f.b, "lazyboe", 1, true).dump(),  // line 2
      "",                                                         // line 3 (blank)
      "{\"id\": \"broken\", \"start\": [0, 0,",                   // line 4: not JSON
      six.dump(),                                                 // line 5
      query("unknown", f.a, f.b, "astar", 1, true).dump(),        // line 6
      "   ",                                                      // line 7 (blank)
      query("limits", outside, f.b, "boe", 1, true).dump(),       // line 8
      query("good-2", f.b, f.a, "boe", 2, true).dump(),           // line 9
  };
  json other = query("other", f.a, f.b, "boe", 1, true);
  other["lazy_model"] = "transfer";  // lazyboe's: silently ignored, it would mislead
  lines.push_back(other.dump());     // line 10
  json misspelt = query("misspelt", f.a, f.b, "boe", 1, true);
  misspelt["stop_at_frist"] = true;
  lines.push_back(misspelt.dump());  // line 11
  json no_scene = query("no-scene", f.a, f.b, "boe", 1, true);
  no_scene["scene"] = "no-such-scene.json";
  lines.push_back(no_scene.dump());  // line 12
  json foreign = query("foreign", f.a, f.b, "boe", 1, true);
  foreign["scene"] = {{"schema_version", 1},
                      {"name", "foreign"},
                      {"objects",
                       {{{"name", "floor"},
                         {"type", "box"},
                         {"size", {1, 1, 0.02}},
                         {"position", {0, 0, -0.01}},
                         {"allowed_links", {"ur5_base_link"}}}}}};
  lines.push_back(foreign.dump());  // line 13
  json empty_scene = query("empty-scene", f.a, f.b, "boe", 1, true);
  empty_scene["scene"] = "";
  lines.push_back(empty_scene.dump());  // line 14
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  const std::string file = write_temp_file("bad.jsonl", text);
  const ToolRun t = query_tool({"--bundle", f.path, "--queries", file, "--jobs", "2", "--quiet"});
  ASSERT_EQ(t.r.exit_code, 3) << describe(t.r);  // some lines had errors, the others ran
  ASSERT_TRUE(t.problems.empty()) << t.problems;
  struct Expected {
    int line;
    json id;
    std::vector<std::string> reason;  // empty: succeeds
  };
  const std::vector<Expected> expected = {
      {1, "good-1", {}},
      {2, "collide", {"collision"}},
      {4, nullptr, {"JSON"}},
      {5, "six", {"start", "7"}},
      {6, "unknown", {"planner", "astar"}},
      {8, "limits", {"start", "limit"}},
      {9, "good-2", {}},
      {10, "other", {"lazy_model: not a parameter of boe", "theta"}},
      {11, "misspelt", {"stop_at_frist: unknown field (did you mean 'stop_at_first'?)"}},
      {12, "no-scene", {"scene: no-such-scene.json"}},
      {13, "foreign", {"scene", "ur5_base_link", "is not a link of robot"}},
      {14, "empty-scene", {"scene: expected an environment file's name"}},
  };
  ASSERT_EQ(t.results.size(), expected.size()) << "one result per non-empty line\n"
                                               << describe(t.r);
  for (size_t i = 0; i < expected.size(); ++i) {
    const json& r = t.results[i];
    const Expected& e = expected[i];
    SCOPED_TRACE("line " + std::to_string(e.line) + ": " + r.dump().substr(0, 600));
    EXPECT_EQ(r.value("line", -1), e.line) << "results out of input order";
    if (e.id.is_null()) {
      EXPECT_TRUE(r.contains("id") && r["id"].is_null());
    } else {
      EXPECT_EQ(r.value("id", json()), e.id);
    }
    if (e.reason.empty()) {
      expect_solved(r, "good query");
      continue;
    }
    EXPECT_EQ(r.value("success", true), false);
    ASSERT_TRUE(r.contains("error") && r["error"].is_string());
    const std::string error = r["error"];
    EXPECT_TRUE(contains(error, "line " + std::to_string(e.line)))
        << "does not name its line: " << error;
    for (const std::string& word : e.reason)
      EXPECT_TRUE(contains(error, word)) << "no '" << word << "' in: " << error;
  }
}

}  // namespace
}  // namespace lazyboe::test
