// Planning queries through the lazyboe-query tool, on one small dense bundle built with the real
// tools (lazyboe-build, lazyboe-perturb). Covered: the tools build the same bundle as the
// library (test_planners plans on that one); every planner solves an easy problem; every
// returned trajectory passes the independent re-validation of planning_fixture; the output is
// made of simulated edges only, and LazyBoE does take edges lazily while BoE never does;
// identical results for a fixed seed, and with parallel rollouts; error results for bad query
// lines while the rest of the batch succeeds; memory-mapped and read-into-memory bundles agree;
// refusal of incomplete, missing and unperturbed bundles; streaming from standard input;
// robot identity, any environment; CSV trajectories; a start or goal outside the bundle's coverage
// fails with a reason.
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
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// ------------------------------------------------------------------------------------------
// The bundle: built once per process with the real tools
// ------------------------------------------------------------------------------------------

// Builds <temp>/bundle/unperturbed.h5 (lazyboe-build) and <temp>/bundle/bundle.h5 (a copy,
// then lazyboe-perturb with p = 4). Returns the perturbed bundle's path.
std::string make_bundles() {
  const std::string dir = fresh_dir("bundle");
  const std::string unperturbed = dir + "/unperturbed.h5", bundle = dir + "/bundle.h5";
  const CommandResult b =
      run(watchdog(300) + quote(tool_path("lazyboe-build")) + " --out " + quote(unperturbed) +
          " --edges " + std::to_string(kEdges) + " --region=" + kRegion + " --theta " +
          std::to_string(kTheta) + " --quiet");
  if (b.exit_code != 0) throw std::runtime_error("lazyboe-build failed: " + describe(b));
  fs::copy_file(unperturbed, bundle);
  const CommandResult p =
      run(watchdog(300) + quote(tool_path("lazyboe-perturb")) + " --bundle " + quote(bundle) +
          " --perturbations " + std::to_string(kPerturbations) + " --quiet");
  if (p.exit_code != 0) throw std::runtime_error("lazyboe-perturb failed: " + describe(p));
  return bundle;
}

struct Fixture : PlanningFixture {
  Fixture() : Fixture(make_bundles()) {}
  explicit Fixture(const std::string& bundle_path)
      : PlanningFixture(std::make_shared<const Bundle>(read_bundle(bundle_path)),
                        BundleView::open(bundle_path)),
        path(bundle_path) {}
  std::string path;
  std::string unperturbed = (fs::path(path).parent_path() / "unperturbed.h5").string();
};

const Fixture& fixture() { return shared_fixture<Fixture>(); }

// ------------------------------------------------------------------------------------------
// Queries and the tool
// ------------------------------------------------------------------------------------------

json query(const std::string& id, const JointVectorRef& start, const JointVectorRef& goal,
           const std::string& planner, double budget, bool stop_at_first, uint64_t seed = 1) {
  json q;
  q["id"] = id;
  q["start"] = vec(start);
  q["goal"] = {{"q", vec(goal)}, {"tolerance", kTolerance}};
  q["planner"] = planner;
  q["budget"] = budget * time_scale();  // the sanitizers slow the planners
  q["seed"] = seed;
  if (stop_at_first) q["stop_at_first"] = true;
  return q;
}

std::string jsonl(const std::vector<json>& queries) {
  std::string s;
  for (const json& q : queries) s += q.dump() + "\n";
  return s;
}

std::string query_command(const std::vector<std::string>& args) {
  std::string cmd = watchdog(120) + quote(tool_path("lazyboe-query"));
  for (const std::string& a : args) cmd += " " + quote(a);
  return cmd;
}

struct ToolRun {
  CommandResult r;
  std::vector<json> results;
  std::string problems;  // lines of stdout that are not JSON
};

std::vector<json> parse_lines(const std::string& out, std::string& problems) {
  std::vector<json> results;
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    try {
      results.push_back(json::parse(line));
    } catch (const std::exception& e) {
      problems += "  stdout line is not JSON: " + line.substr(0, 200) + "\n";
    }
  }
  return results;
}

ToolRun query_tool(const std::vector<std::string>& args) {
  ToolRun t;
  t.r = run(query_command(args));
  t.results = parse_lines(t.r.out, t.problems);
  return t;
}

// Runs a batch (written to <temp>/<name>.jsonl) on the fixture's bundle.
ToolRun run_batch(const std::string& name, const std::vector<json>& queries,
                  std::vector<std::string> extra = {}) {
  const std::string file = write_temp_file(name + ".jsonl", jsonl(queries));
  std::vector<std::string> args = {"--bundle", fixture().path, "--queries", file};
  args.insert(args.end(), extra.begin(), extra.end());
  return query_tool(args);
}

// A result without the fields that depend on the wall clock.
json timeless(json r) {
  r.erase("time_to_first_solution");
  if (r.contains("post_processing")) {
    r["post_processing"].erase("seconds");
    r["post_processing"].erase("raw_seconds");
  }
  return r;
}

// ------------------------------------------------------------------------------------------
// Shared runs (computed once per process, used by several tests)
// ------------------------------------------------------------------------------------------

// The same problem with every planner through the tool, trajectories inline.
const ToolRun& tool_easy_run() {
  static const ToolRun run = [] {
    const Fixture& f = fixture();
    std::vector<json> queries;
    for (const std::string& p : kPlanners)
      queries.push_back(query(p, f.a, f.b, p, easy_budget(p), false));
    return run_batch("easy", queries, {"--trajectories", "inline", "--jobs", "4", "--quiet"});
  }();
  return run;
}

// A batch that stops at the first solution (deterministic for a fixed seed; the budgets are
// only a bound, far above the time the first solution takes): every planner a -> b, LazyBoE,
// BoE and lazysp b -> a, lazysp a -> c, and last LazyBoE and BoE a -> c (paths of several steps,
// the slowest queries).
std::vector<json> deterministic_queries() {
  const Fixture& f = fixture();
  std::vector<json> q;
  for (const std::string& p : kPlanners) q.push_back(query(p + "-ab", f.a, f.b, p, 5, true, 3));
  q.push_back(query("lazyboe-ba", f.b, f.a, "lazyboe", 5, true, 5));
  q.push_back(query("boe-ba", f.b, f.a, "boe", 5, true, 5));
  q.push_back(query("lazysp-ba", f.b, f.a, "lazysp", 5, true, 5));
  q.push_back(query("lazysp-ac", f.a, f.c, "lazysp", 10, true, 7));
  q.push_back(query("lazyboe-ac", f.a, f.c, "lazyboe", 10, true, 7));
  q.push_back(query("boe-ac", f.a, f.c, "boe", 10, true, 7));
  return q;
}

// Its quick part (all but the a -> c queries), for the tests that compare other ways of running
// the tool with the reference run below.
std::vector<json> quick_queries() {
  std::vector<json> q = deterministic_queries();
  q.resize(q.size() - 2);
  return q;
}

const ToolRun& deterministic_run() {
  static const ToolRun run =
      run_batch("deterministic", deterministic_queries(),
                {"--trajectories", "inline", "--jobs", "1", "--sim-threads", "1", "--quiet"});
  return run;
}

// Checks a run of the deterministic batch worked at all: exit 0, one result per query.
void expect_batch_ran(const ToolRun& t, size_t queries) {
  ASSERT_EQ(t.r.exit_code, 0) << describe(t.r);
  ASSERT_TRUE(t.problems.empty()) << t.problems;
  ASSERT_EQ(t.results.size(), queries) << describe(t.r);
}

// A result that solved its query with an inline trajectory.
void expect_solved(const json& r, const std::string& what) {
  EXPECT_FALSE(r.contains("error")) << what << ": " << r.dump().substr(0, 1000);
  EXPECT_EQ(r.value("success", false), true) << what << ": " << r.dump().substr(0, 1000);
}

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
  ASSERT_EQ(t.r.exit_code, 0) << describe(t.r);
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

// ------------------------------------------------------------------------------------------
// 6. Memory-mapped and read-into-memory bundles; refused bundles
// ------------------------------------------------------------------------------------------

TEST(QueryCli, MemoryMappedAndReadIntoMemoryGiveIdenticalAnswers) {
  const Fixture& f = fixture();
  const BundleView mapped = BundleView::open(f.path, true);
  const BundleView read = BundleView::open(f.path, false);
  EXPECT_TRUE(mapped.memory_mapped()) << "contiguous datasets should be mapped";
  EXPECT_FALSE(read.memory_mapped());
  ASSERT_EQ(mapped.size(), static_cast<size_t>(kEdges));
  ASSERT_EQ(read.size(), mapped.size());
  ASSERT_EQ(mapped.dof(), 7);
  ASSERT_TRUE(mapped.has_perturbation());
  ASSERT_TRUE(read.has_perturbation());
  EXPECT_EQ(mapped.perturbation_theta(), read.perturbation_theta());
  const Bundle& truth = f.data;  // read_bundle, the reference
  const int n = 7;
  size_t mismatches = 0;
  for (size_t e = 0; e < mapped.size() && mismatches < 10; ++e) {
    const auto before = mismatches;
    for (int j = 0; j < n; ++j) {
      if (mapped.q0(e)[j] != read.q0(e)[j] || mapped.q0(e)[j] != truth.q0[e * n + j]) ++mismatches;
      if (mapped.qf(e)[j] != read.qf(e)[j] || mapped.qf(e)[j] != truth.qf[e * n + j]) ++mismatches;
    }
    if (mapped.duration(e) != read.duration(e) || mapped.duration(e) != truth.duration[e])
      ++mismatches;
    const CommandProfile cm = mapped.command(e), cr = read.command(e);
    if (cm.n_knots != cr.n_knots || cm.dof != cr.dof || cm.duration != cr.duration ||
        cm.duration != truth.command_duration[e] ||
        cm.n_knots != static_cast<int>(truth.knot_offset[e + 1] - truth.knot_offset[e])) {
      ++mismatches;
    } else {
      for (int k = 0; k < cm.n_knots * n; ++k) {
        if (cm.knots[k] != cr.knots[k] ||
            cm.knots[k] != truth.knots[truth.knot_offset[e] * n + k]) {
          ++mismatches;
          break;
        }
      }
    }
    if (mapped.p_lazy_prop(e) != read.p_lazy_prop(e) ||
        mapped.p_lazy_prop(e) != truth.perturbation.p_lazy_prop[e]) {
      ++mismatches;
    }
    if (mapped.p_collision(e) != read.p_collision(e) ||
        mapped.p_collision(e) != truth.perturbation.p_collision[e]) {
      ++mismatches;
    }
    EXPECT_EQ(mismatches, before) << "edge " << e
                                  << " differs between the mapped, read and stored bundle";
  }
  EXPECT_EQ(mismatches, 0u);

  // The tool with and without --no-mmap: the same results.
  const std::vector<json> queries = quick_queries();
  const ToolRun& mapped_run = deterministic_run();
  expect_batch_ran(mapped_run, deterministic_queries().size());
  const ToolRun read_run = run_batch(
      "quick", queries, {"--trajectories", "inline", "--jobs", "1", "--quiet", "--no-mmap"});
  expect_batch_ran(read_run, queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    expect_solved(read_run.results[i], "--no-mmap");
    EXPECT_EQ(timeless(mapped_run.results[i]).dump(), timeless(read_run.results[i]).dump());
  }
  // Without --quiet, the tool says which path it took.
  const std::string one = write_temp_file("one.jsonl", queries[0].dump() + "\n");
  const ToolRun loud = query_tool({"--bundle", f.path, "--queries", one, "--no-mmap"});
  EXPECT_EQ(loud.r.exit_code, 0) << describe(loud.r);
  EXPECT_TRUE(contains(loud.r.err, "read into memory")) << loud.r.err;
}

TEST(QueryCli, IncompleteMissingAndUnperturbedBundlesAreRefused) {
  const Fixture& f = fixture();
  // Incomplete: the resume hint.
  Bundle incomplete = f.data;
  incomplete.header.complete = false;
  const std::string dir = fresh_dir("refused");
  const std::string incomplete_path = dir + "/incomplete.h5";
  write_bundle(incomplete_path, incomplete);
  for (bool mmap : {true, false}) {
    try {
      BundleView::open(incomplete_path, mmap);
      ADD_FAILURE() << "an incomplete bundle was opened (mmap " << mmap << ")";
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "lazyboe-build --resume")) << e.what();
      EXPECT_TRUE(contains(e.what(), incomplete_path)) << e.what();
    }
  }
  const std::string good =
      write_temp_file("refused/one.jsonl", query("q", f.a, f.b, "boe", 1, true).dump() + "\n");
  const ToolRun t1 = query_tool({"--bundle", incomplete_path, "--queries", good});
  EXPECT_EQ(t1.r.exit_code, 1) << describe(t1.r);
  EXPECT_EQ(count_lines(t1.r.err), 1) << describe(t1.r);
  EXPECT_TRUE(contains(t1.r.err, "--resume")) << describe(t1.r);
  EXPECT_TRUE(t1.r.out.empty()) << describe(t1.r);

  // Missing file.
  const std::string missing = dir + "/no-such-bundle.h5";
  try {
    BundleView::open(missing);
    ADD_FAILURE() << "a missing bundle was opened";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), missing)) << e.what();
  }
  const ToolRun t2 = query_tool({"--bundle", missing, "--queries", good});
  EXPECT_EQ(t2.r.exit_code, 1) << describe(t2.r);
  EXPECT_EQ(count_lines(t2.r.err), 1) << describe(t2.r);
  EXPECT_TRUE(contains(t2.r.err, missing)) << describe(t2.r);

  // No perturbation analysis: lazyboe gets an error result saying to run lazyboe-perturb;
  // boe and lazysp on the same bundle still work. (The library refuses it too: test_planners.)
  const BundleView plain = BundleView::open(f.unperturbed);
  EXPECT_FALSE(plain.has_perturbation());
  const std::string batch = write_temp_file(
      "refused/unperturbed.jsonl",
      jsonl({query("lazy", f.a, f.b, "lazyboe", 1, true), query("plain", f.a, f.b, "boe", 2, true),
             query("plain-sp", f.a, f.b, "lazysp", 2, true)}));
  const ToolRun t3 = query_tool({"--bundle", f.unperturbed, "--queries", batch, "--quiet"});
  ASSERT_EQ(t3.r.exit_code, 0) << describe(t3.r);
  ASSERT_EQ(t3.results.size(), 3u) << describe(t3.r);
  EXPECT_EQ(t3.results[0].value("success", true), false);
  EXPECT_EQ(t3.results[0].value("line", -1), 1);
  EXPECT_TRUE(t3.results[0].contains("error") &&
              contains(t3.results[0]["error"].get<std::string>(), "lazyboe-perturb"))
      << t3.results[0].dump();
  expect_solved(t3.results[1], "boe without perturbation");
  expect_solved(t3.results[2], "lazysp without perturbation");  // P_collision taken as 0
  EXPECT_EQ(t3.results[2].value("found_by", ""), "bundle") << t3.results[2].dump();
}

// ------------------------------------------------------------------------------------------
// 7. Streaming from standard input
// ------------------------------------------------------------------------------------------

TEST(QueryCli, StreamingFromStandardInputFlushesOneLinePerQuery) {
  const Fixture& f = fixture();
  const std::vector<json> queries = quick_queries();
  const ToolRun& file_run = deterministic_run();
  expect_batch_ran(file_run, deterministic_queries().size());
  const std::string dir = fresh_dir("stream");
  const std::string first = dir + "/first.jsonl", rest = dir + "/rest.jsonl",
                    out = dir + "/out.jsonl", err = dir + "/err.txt", seen = dir + "/seen.txt";
  std::ofstream(first) << queries[0].dump() << "\n";
  {
    std::ofstream r(rest);
    for (size_t i = 1; i < queries.size(); ++i) r << queries[i].dump() << "\n";
  }
  // The producer sends the first query, waits (up to 30 s) for its result to appear in the
  // output while standard input is still open, notes how many lines it saw, then sends the rest.
  const std::string producer =
      "( cat " + quote(first) + "; i=0; while [ $i -lt 300 ]; do " + "[ \"$(wc -l < " + quote(out) +
      " 2>/dev/null || echo 0)\" -ge 1 ] && break; " + "sleep 0.1; i=$((i+1)); done; (wc -l < " +
      quote(out) + " 2>/dev/null || echo 0) > " + quote(seen) + "; cat " + quote(rest) + " )";
  const std::string consumer =
      query_command({"--bundle", f.path, "--queries", "-", "--trajectories", "inline", "--quiet"});
  const CommandResult r = run(
      "bash -c " + quote(producer + " | " + consumer + " > " + quote(out) + " 2> " + quote(err)));
  ASSERT_EQ(r.exit_code, 0) << describe(r) << read_file(err);
  std::string seen_text = read_file(seen);
  seen_text.erase(std::remove_if(seen_text.begin(), seen_text.end(), ::isspace), seen_text.end());
  EXPECT_EQ(seen_text, "1")
      << "the first result was not written (flushed) while standard input was still open";
  std::string problems;
  const std::vector<json> streamed = parse_lines(read_file(out), problems);
  ASSERT_TRUE(problems.empty()) << problems;
  ASSERT_EQ(streamed.size(), queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    expect_solved(streamed[i], "streamed");
    EXPECT_EQ(timeless(streamed[i]).dump(), timeless(file_run.results[i]).dump());
  }
}

// ------------------------------------------------------------------------------------------
// 8. Robot and environment identity; CSV trajectories
// ------------------------------------------------------------------------------------------

TEST(QueryCli, RobotOtherThanTheBundlesIsRefusedAtStartAnyEnvironmentIsPlannedIn) {
  const Fixture& f = fixture();
  const std::string dir = fresh_dir("identity");
  const std::string queries =
      write_temp_file("identity/q.jsonl", query("q", f.a, f.b, "boe", 1, true).dump() + "\n");
  // The bundle's own robot and environment, given explicitly: accepted.
  {
    const std::string out = dir + "/same.jsonl";
    const ToolRun t =
        query_tool({"--bundle", f.path, "--queries", queries, "--out", out, "--quiet", "--robot",
                    f.data.header.robot_config, "--env", f.data.header.env_file});
    EXPECT_EQ(t.r.exit_code, 0) << describe(t.r);
    EXPECT_TRUE(fs::exists(out));
  }
  // Another robot: the Panda config with its URDF path made absolute (other content).
  json robot = json::parse(read_file(source_path("data/robots/panda.json")));
  robot["urdf"] = source_path("data/robots/panda.urdf");
  robot["description"] = "a copy of the Panda, not the bundle's";
  const std::string other_robot = write_temp_file("identity/other-robot.json", robot.dump(2));
  ASSERT_NO_THROW(load_robot(other_robot));  // a valid robot, only not the bundle's
  {
    const std::string out = dir + "/refused.jsonl";
    const CommandResult r = run(query_command(
        {"--bundle", f.path, "--queries", queries, "--out", out, "--robot", other_robot}));
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_EQ(count_lines(r.err), 1) << describe(r);
    EXPECT_TRUE(contains(r.err, other_robot)) << describe(r);
    EXPECT_TRUE(contains(r.err, "not the robot")) << describe(r);
    EXPECT_TRUE(r.out.empty()) << describe(r);
    EXPECT_FALSE(fs::exists(out)) << "results written although refused";
  }
  // Another environment: the scene the queries are planned in (the bundle's edges are
  // dynamics, true in any scene); each result names it.
  const ToolRun t = query_tool({"--bundle", f.path, "--queries", queries, "--env",
                                source_path("data/environments/empty.json"), "--quiet"});
  EXPECT_EQ(t.r.exit_code, 0) << describe(t.r);
  ASSERT_EQ(t.results.size(), 1u) << describe(t.r);
  EXPECT_EQ(t.results[0]["scene"]["name"], "empty") << t.results[0].dump();
  EXPECT_TRUE(t.results[0]["success"].get<bool>()) << t.results[0].dump();
}

// Parses a CSV file into its header and rows of numbers.
bool read_csv(const std::string& path, std::string& header,
              std::vector<std::vector<double>>& rows) {
  std::ifstream in(path);
  if (!in) return false;
  std::getline(in, header);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return true;
}

// A query id names its CSV file: an id that would leave --trajectory-dir gets an error result
// (the others are answered) and writes nothing outside.
TEST(QueryCli, CsvTrajectoryIdsMustNameAFileInTheDirectory) {
  const Fixture& f = fixture();
  const std::string dir = fresh_dir("csv-ids");
  const std::string traj_dir = dir + "/trajectories";
  const std::vector<json> queries = {query("../escape", f.a, f.b, "boe", 2, true),
                                     query("..", f.a, f.b, "boe", 2, true),
                                     query("fine", f.a, f.b, "boe", 2, true)};
  const ToolRun t = run_batch("csv-ids", queries,
                              {"--trajectories", "csv", "--trajectory-dir", traj_dir, "--quiet"});
  ASSERT_EQ(t.results.size(), 3u) << describe(t.r);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_TRUE(contains(t.results[i].value("error", ""), "cannot name a file"))
        << t.results[i].dump();
  }
  EXPECT_TRUE(t.results[2].value("success", false)) << t.results[2].dump();
  EXPECT_FALSE(fs::exists(dir + "/escape.csv"));
  EXPECT_EQ(files_in(traj_dir), std::vector<std::string>{"fine.csv"});
}

TEST(QueryCli, CsvTrajectoriesHaveTheInlineRows) {
  const Fixture& f = fixture();
  const std::vector<json> queries = quick_queries();
  const ToolRun& inline_run = deterministic_run();
  expect_batch_ran(inline_run, deterministic_queries().size());
  const std::string dir = fresh_dir("csv");
  const std::string traj_dir = dir + "/trajectories";
  const ToolRun t =
      run_batch("quick", queries,
                {"--trajectories", "csv", "--trajectory-dir", traj_dir, "--jobs", "1", "--quiet"});
  expect_batch_ran(t, queries.size());
  // The raw chain's columns first (as before post-processing), then acceleration and command.
  std::string expected_header = "t";
  for (const char* column : {"q", "dq", "ddq", "cmd"})
    for (int i = 1; i <= 7; ++i) expected_header += "," + std::string(column) + std::to_string(i);
  size_t successes = 0;
  for (size_t i = 0; i < queries.size(); ++i) {
    const json& r = t.results[i];
    const json& ref = inline_run.results[i];
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    EXPECT_FALSE(r.contains("trajectory")) << "inline trajectory in csv mode";
    if (!r.value("success", false)) {
      EXPECT_FALSE(r.contains("trajectory_file"));
      continue;
    }
    ++successes;
    ASSERT_TRUE(r.contains("trajectory_file") && r["trajectory_file"].is_string()) << r.dump();
    const std::string file = r["trajectory_file"];
    EXPECT_TRUE(contains(file, traj_dir)) << file;
    std::string header;
    std::vector<std::vector<double>> rows;
    ASSERT_TRUE(read_csv(file, header, rows)) << "cannot read " << file;
    EXPECT_EQ(header, expected_header);
    ASSERT_TRUE(ref.contains("trajectory"));
    const Trajectory traj = trajectory_from_json(ref);
    ASSERT_EQ(rows.size(), traj.t.size()) << "CSV rows vs inline samples";
    size_t bad = 0;
    for (size_t k = 0; k < rows.size(); ++k) {
      ASSERT_EQ(rows[k].size(), 29u) << "row " << k;
      ASSERT_EQ(traj.ddq.size(), traj.t.size());
      std::vector<double> want = {traj.t[k]};
      for (const std::vector<JointVector>* v : {&traj.q, &traj.dq, &traj.ddq, &traj.cmd})
        for (int j = 0; j < 7; ++j) want.push_back((*v)[k][j]);
      for (size_t c = 0; c < 29; ++c) {
        // Written with 10 significant digits.
        if (std::abs(rows[k][c] - want[c]) > 1e-9 * std::max(1.0, std::abs(want[c]))) {
          if (bad++ < 5)
            ADD_FAILURE() << "row " << k << " column " << c << ": " << rows[k][c] << " vs "
                          << want[c];
        }
      }
    }
    EXPECT_EQ(bad, 0u);
    // The rest of the result is as in inline mode.
    json a = timeless(r), b = timeless(ref);
    a.erase("trajectory_file");
    b.erase("trajectory");
    EXPECT_EQ(a.dump(), b.dump());
  }
  // One CSV per successful query, nothing else.
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(traj_dir)) files += e.path().extension() == ".csv";
  EXPECT_EQ(files, successes);
  EXPECT_EQ(successes, queries.size());
  (void)f;
}

// --raw: the planners' edge chains as they are (the paper's comparisons): the same edges and
// counters as the post-processed run, the raw figures it reports, and trajectories that are
// exactly the bundle edges simulated one after another.
TEST(QueryCli, RawGivesThePlannersEdgeChainsAndPostProcessingIsShorter) {
  const Fixture& f = fixture();
  const std::vector<json> queries = quick_queries();
  const ToolRun& post = deterministic_run();
  expect_batch_ran(post, deterministic_queries().size());
  const ToolRun raw =
      run_batch("quick", queries, {"--trajectories", "inline", "--jobs", "1", "--quiet", "--raw"});
  expect_batch_ran(raw, queries.size());
  int shorter = 0;
  for (size_t i = 0; i < queries.size(); ++i) {
    const json& r = raw.results[i];
    const json& p = post.results[i];
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    expect_solved(r, "--raw");
    EXPECT_FALSE(r.contains("post_processing"));
    EXPECT_TRUE(p.contains("post_processing"));
    EXPECT_EQ(r["edges"], p["edges"]);
    EXPECT_EQ(r["counters"], p["counters"]);
    EXPECT_EQ(r["n_solutions"], p["n_solutions"]);
    EXPECT_EQ(r["raw_duration"], r["duration"]);
    EXPECT_EQ(r["raw_duration"], p["raw_duration"]);
    EXPECT_EQ(r["best_cost"], p["raw_cost"]);
    EXPECT_EQ(r["stops"].get<int>(), static_cast<int>(r["edges"].size()) - 1);
    EXPECT_LE(p["duration"].get<double>(), r["duration"].get<double>());
    EXPECT_LE(p["stops"].get<int>(), r["stops"].get<int>());
    shorter += p["duration"].get<double>() < r["duration"].get<double>();
    if (!r.contains("trajectory") || !is_bundle_planner(r.value("planner", ""))) continue;
    const Trajectory traj = trajectory_from_json(r);
    EXPECT_TRUE(traj.ddq.empty()) << "a raw trajectory has the raw columns only";
    const JointVector start = joint(queries[i]["start"].get<std::vector<double>>());
    EXPECT_EQ(resimulate(f, start, bundle_commands(f, traj.edges), traj), "");
  }
  EXPECT_GT(shorter, 0) << "post-processing never shortened a trajectory";

  // A query's own "raw" overrides the flag: the same answer as --raw.
  json first = queries[0];
  first["raw"] = true;
  const ToolRun one = run_batch("raw-field", {first}, {"--trajectories", "inline", "--quiet"});
  expect_batch_ran(one, 1);
  json a = one.results[0], b = raw.results[0];
  for (json* r : {&a, &b}) r->erase("time_to_first_solution");
  EXPECT_EQ(a, b);
}

// Result lines, post-processed and raw, follow schemas/result.schema.json (validated by
// tests/validate_schemas.py with python3-jsonschema).
TEST(QueryCli, ResultLinesFollowTheResultSchema) {
  const ToolRun& post = deterministic_run();
  expect_batch_ran(post, deterministic_queries().size());
  std::vector<json> quick = quick_queries();
  quick.resize(2);
  const ToolRun raw = run_batch("quick", quick, {"--trajectories", "inline", "--quiet", "--raw"});
  expect_batch_ran(raw, quick.size());
  std::string lines;
  for (const ToolRun* t : {&post, &raw})
    for (const json& r : t->results) lines += r.dump() + "\n";
  const std::string file = write_temp_file("results.jsonl", lines);
  const CommandResult r = run(
      "/usr/bin/python3 " + quote(std::string(LAZYBOE_SOURCE_DIR) + "/tests/validate_schemas.py") +
      " " + quote(LAZYBOE_SOURCE_DIR) + " " + quote(file));
  EXPECT_EQ(r.exit_code, 0) << describe(r);
}

// --control-rate: one sample per control tick (1 ms), from the exact start at rest to rest
// inside the goal, with the acceleration and command columns.
TEST(QueryCli, ControlRateTrajectoriesStartAndEndAtRest) {
  const Fixture& f = fixture();
  std::vector<json> queries = quick_queries();
  queries.resize(2);
  const std::string dir = fresh_dir("control-rate");
  const std::string traj_dir = dir + "/trajectories";
  const ToolRun t = run_batch(
      "rate", queries,
      {"--trajectories", "csv", "--trajectory-dir", traj_dir, "--control-rate", "--quiet"});
  expect_batch_ran(t, queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    const json& r = t.results[i];
    SCOPED_TRACE(queries[i]["id"].get<std::string>());
    expect_solved(r, "--control-rate");
    std::string header;
    std::vector<std::vector<double>> rows;
    ASSERT_TRUE(read_csv(r["trajectory_file"], header, rows));
    ASSERT_GE(rows.size(), 2u);
    const JointVector start = joint(queries[i]["start"].get<std::vector<double>>());
    const JointVector goal = joint(queries[i]["goal"]["q"].get<std::vector<double>>());
    for (size_t k = 1; k < rows.size(); ++k)
      ASSERT_NEAR(rows[k][0] - rows[k - 1][0], f.sim.dt, 1e-9) << "row " << k;
    EXPECT_NEAR(rows.back()[0], r["duration"].get<double>(), 1e-9);
    for (int j = 0; j < 7; ++j) {
      EXPECT_NEAR(rows[0][1 + j], start[j], 1e-9);  // 10 significant digits
      EXPECT_EQ(rows[0][8 + j], 0.0);               // dq
      EXPECT_EQ(rows[0][15 + j], 0.0);              // ddq
      EXPECT_LE(std::abs(rows.back()[8 + j]), f.sim.options.settle_velocity);
      EXPECT_EQ(rows.back()[22 + j], 0.0);  // no command
    }
    JointVector last(7);
    for (int j = 0; j < 7; ++j) last[j] = rows.back()[1 + j];
    EXPECT_LE((last - goal).norm(), kTolerance);
  }
}

// ------------------------------------------------------------------------------------------
// 9. Start or goal outside the bundle's coverage
// ------------------------------------------------------------------------------------------

TEST(QueryCli, StartOrGoalOutsideTheCoverageFailsWithAReason) {
  const Fixture& f = fixture();
  const JointVector far_start = far_start_state(f), far_goal = far_goal_state(f);
  ASSERT_EQ(far_start.size(), 7) << "no collision-free state far from the bundle's starts";
  ASSERT_EQ(far_goal.size(), 7) << "no collision-free state far from the bundle's ends";

  // Tool: the reason in the result.
  const ToolRun t = run_batch("far",
                              {query("far-start", far_start, f.b, "lazyboe", 3, false),
                               query("far-goal", f.a, far_goal, "lazyboe", 3, false),
                               query("far-start-boe", far_start, f.b, "boe", 3, false)},
                              {"--quiet"});
  ASSERT_EQ(t.r.exit_code, 0) << describe(t.r);
  ASSERT_EQ(t.results.size(), 3u) << describe(t.r);
  for (const json& r : t.results) {
    SCOPED_TRACE(r.dump().substr(0, 600));
    EXPECT_FALSE(r.contains("error"));
    EXPECT_EQ(r.value("success", true), false);
    ASSERT_TRUE(r.contains("failure") && r["failure"].is_string());
    const std::string failure = r["failure"];
    EXPECT_TRUE(contains(failure, "theta") && contains(failure, "bundle")) << failure;
    EXPECT_FALSE(contains(failure, "time budget")) << failure;
  }
  std::cout << "[ reason  ] far start: "
            << (t.results.empty() ? "" : t.results[0].value("failure", "")) << "\n"
            << "[ reason  ] far goal:  "
            << (t.results.size() < 2 ? "" : t.results[1].value("failure", "")) << "\n";
}

}  // namespace
}  // namespace lazyboe::test
