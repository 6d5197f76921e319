// Planning queries end to end: the four planners (LazyBoE, BoE, RRT, SST) through the library
// (plan + realize_path) and through the lazyboe-query tool, on one small dense bundle.
// Covered: every planner solves an easy problem; every returned trajectory passes a
// re-validation written here (times, start, goal, limits, collision, continuity, edges); the
// output is made of simulated edges only (re-simulating the edge sequence lands exactly on the
// trajectory's end), and LazyBoE does take edges lazily while BoE never does; identical results
// for a fixed seed; error results for bad query lines while the rest of the batch succeeds;
// memory-mapped and read-into-memory bundles agree; refusal of incomplete, missing and
// unperturbed bundles; streaming from standard input; robot/environment identity; CSV
// trajectories; a start or goal outside the bundle's coverage fails with a reason.
//
// Run time matters (the whole binary should stay well under a minute on two cores): one bundle
// of 2000 edges in a small region (p = 4 perturbations) is built once per process, budgets
// are 1-3 s, and batches are a handful of queries, mostly `stop_at_first`.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/io/csv.h"
#include "lazyboe/planning/neighbour_index.h"
#include "lazyboe/planning/planners.h"
#include "lazyboe/planning/problem.h"
#include "lazyboe/sim/simulator.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// ------------------------------------------------------------------------------------------
// Small helpers
// ------------------------------------------------------------------------------------------

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

long count_lines(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

std::string describe(const CommandResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\n--- stdout:\n" + r.out.substr(0, 4000) +
         "\n--- stderr:\n" + r.err.substr(0, 4000);
}

std::string fresh_dir(const std::string& name) {
  const std::string dir = temp_dir() + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<double> vec(const JointVectorRef& q) {
  return std::vector<double>(q.data(), q.data() + q.size());
}
JointVector joint(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

std::string str(const JointVectorRef& q) {
  std::ostringstream s;
  s.precision(17);
  s << "[";
  for (Eigen::Index i = 0; i < q.size(); ++i) s << (i ? ", " : "") << q[i];
  return s.str() + "]";
}

// ------------------------------------------------------------------------------------------
// The bundle: built once per process with the real tools
// ------------------------------------------------------------------------------------------

constexpr int kEdges = 2000;
constexpr double kTheta = 0.45;
constexpr const char* kRegion = "-0.3:0.3,0.0:0.5,-0.3:0.3,-2.3:-1.7,-0.3:0.3,1.6:2.2,0.5:1.1";
constexpr double kTolerance = 0.3;

// Builds <temp>/bundle/unperturbed.h5 (lazyboe-build) and <temp>/bundle/bundle.h5 (a copy,
// then lazyboe-perturb with p = 4). Returns the perturbed bundle's path.
std::string make_bundles() {
  const std::string dir = fresh_dir("bundle");
  const std::string unperturbed = dir + "/unperturbed.h5", bundle = dir + "/bundle.h5";
  const CommandResult b =
      run("timeout -s KILL 300 " + quote(tool_path("lazyboe-build")) + " --out " +
          quote(unperturbed) + " --edges " + std::to_string(kEdges) + " --region=" + kRegion +
          " --theta " + std::to_string(kTheta) + " --quiet");
  if (b.exit_code != 0) throw std::runtime_error("lazyboe-build failed: " + describe(b));
  fs::copy_file(unperturbed, bundle);
  const CommandResult p = run("timeout -s KILL 300 " + quote(tool_path("lazyboe-perturb")) +
                              " --bundle " + quote(bundle) + " --perturbations 4 --quiet");
  if (p.exit_code != 0) throw std::runtime_error("lazyboe-perturb failed: " + describe(p));
  return bundle;
}

SimulationOptions options_of(const BundleHeader& h) {
  SimulationOptions o;
  o.integrator = h.integrator == "rk4" ? Integrator::RK4 : Integrator::SemiImplicitEuler;
  o.substeps = h.substeps;
  o.sample_every = 0;
  return o;
}

struct Fixture {
  std::string path = make_bundles();
  std::string unperturbed = (fs::path(path).parent_path() / "unperturbed.h5").string();
  Bundle data = read_bundle(path);
  RobotModel robot = load_robot(data.header.robot_config);
  Environment env = load_environment(data.header.env_file);
  CollisionModel collision = build_collision_model(robot, env);
  Simulator sim{robot, collision, options_of(data.header)};
  BundleView view = BundleView::open(path);
  EdgeStartIndex index{view};
  JointVector a, b;  // an easy pair: two edge starts 0.35-0.45 rad apart near the region's centre
  JointVector c;     // an edge start 0.7-0.85 rad from a: paths of several steps

  Fixture() {
    const int n = data.dof();
    const JointVector centre =
        (joint(data.header.region_lower) + joint(data.header.region_upper)) / 2;
    std::vector<size_t> order(data.size());
    for (size_t e = 0; e < order.size(); ++e) order[e] = e;
    auto start = [&](size_t e) {
      return joint(std::vector<double>(&data.q0[e * n], &data.q0[e * n] + n));
    };
    std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
      return (start(x) - centre).norm() < (start(y) - centre).norm();
    });
    for (size_t i = 0; i < 60 && a.size() == 0; ++i) {
      for (size_t j = i + 1; j < 60; ++j) {
        const double d = (start(order[i]) - start(order[j])).norm();
        if (d >= 0.35 && d <= 0.45) {
          a = start(order[i]);
          b = start(order[j]);
          break;
        }
      }
    }
    if (a.size() == 0)
      throw std::runtime_error("no easy start/goal pair among the bundle's edge starts");
    for (size_t i = 0; i < order.size() && c.size() == 0; ++i) {
      const double d = (start(order[i]) - a).norm();
      if (d >= 0.7 && d <= 0.85) c = start(order[i]);
    }
    if (c.size() == 0) throw std::runtime_error("no edge start 0.7-0.85 rad from the easy start");
  }

  JointVector edge_start(size_t e) const {
    const int n = data.dof();
    return joint(std::vector<double>(&data.q0[e * n], &data.q0[e * n] + n));
  }
};

// Built on first use; a failure is reported by every test without building again.
const Fixture& fixture() {
  static std::string failure;
  static const Fixture* f = []() -> const Fixture* {
    try {
      return new Fixture();
    } catch (const std::exception& e) {
      failure = e.what();
      return nullptr;
    }
  }();
  if (!f) throw std::runtime_error("the test bundle could not be set up: " + failure);
  return *f;
}

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
  q["budget"] = budget;
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
  std::string cmd = "timeout -s KILL 120 " + quote(tool_path("lazyboe-query"));
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
  return r;
}

// ------------------------------------------------------------------------------------------
// Independent re-validation of a trajectory
// ------------------------------------------------------------------------------------------

bool is_bundle_planner(const std::string& planner) {
  return planner == "lazyboe" || planner == "boe";
}

Trajectory trajectory_from_json(const json& r) {
  Trajectory t;
  const json& tj = r.at("trajectory");
  t.t = tj.at("t").get<std::vector<double>>();
  for (const json& row : tj.at("q")) t.q.push_back(joint(row.get<std::vector<double>>()));
  for (const json& row : tj.at("dq")) t.dq.push_back(joint(row.get<std::vector<double>>()));
  t.edges = r.at("edges").get<std::vector<int64_t>>();
  t.duration = r.at("duration").get<double>();
  t.cost = r.at("best_cost").get<double>();
  return t;
}

// Every problem found, one per line (at most a few per kind); empty when the trajectory is
// valid. Checks only what the trajectory itself shows, with the library's check_state.
std::string validate(const Fixture& f, const Trajectory& traj, const JointVectorRef& start,
                     const JointVectorRef& goal, double tolerance, const std::string& planner) {
  std::ostringstream p;
  p.precision(17);
  const RobotModel& robot = f.robot;
  const int n = robot.dof;
  const size_t rows = traj.t.size();
  if (rows < 2) return "  fewer than two samples\n";
  if (traj.q.size() != rows || traj.dq.size() != rows) return "  t, q and dq differ in length\n";
  for (size_t k = 0; k < rows; ++k) {
    if (traj.q[k].size() != n || traj.dq[k].size() != n)
      return "  a sample does not have 7 values\n";
  }
  int reported = 0;
  auto report = [&](const std::string& what) {
    if (reported++ < 12) p << "  " << what << "\n";
  };
  // Time.
  if (traj.t[0] != 0) report("t[0] = " + std::to_string(traj.t[0]) + ", expected 0");
  for (size_t k = 1; k < rows; ++k) {
    if (!(traj.t[k] > traj.t[k - 1])) {
      report("t not strictly increasing at sample " + std::to_string(k) + ": " +
             std::to_string(traj.t[k - 1]) + " then " + std::to_string(traj.t[k]));
    }
  }
  if (std::abs(traj.duration - traj.t.back()) > 1e-9) {
    report("duration " + std::to_string(traj.duration) + " differs from the last t " +
           std::to_string(traj.t.back()));
  }
  // Start: exactly the query's start, at rest.
  const double start_error = (traj.q[0] - start).cwiseAbs().maxCoeff();
  if (!(start_error <= 1e-12)) {
    std::ostringstream s;
    s.precision(17);
    s << "first q differs from the query start by " << start_error
      << " rad (max over joints): " << str(traj.q[0]) << " vs " << str(start);
    report(s.str());
  }
  if (!(traj.dq[0].cwiseAbs().maxCoeff() == 0)) report("first dq is not zero: " + str(traj.dq[0]));
  // Goal.
  const double goal_distance = (traj.q.back() - goal).norm();
  if (!(goal_distance <= tolerance)) {
    report("last q is " + std::to_string(goal_distance) + " rad from the goal (tolerance " +
           std::to_string(tolerance) + ")");
  }
  // Limits, collision and continuity at every sample.
  SimulatorWorkspace ws(f.sim);
  for (size_t k = 0; k < rows; ++k) {
    const JointVector& q = traj.q[k];
    const JointVector& dq = traj.dq[k];
    for (int j = 0; j < n; ++j) {
      if (!(q[j] >= robot.q_min[j] && q[j] <= robot.q_max[j])) {
        report("sample " + std::to_string(k) + ": q" + std::to_string(j + 1) + " = " +
               std::to_string(q[j]) + " outside the joint limits");
      }
      if (!(std::abs(dq[j]) <= robot.dq_max[j])) {
        report("sample " + std::to_string(k) + ": dq" + std::to_string(j + 1) + " = " +
               std::to_string(dq[j]) + " beyond the velocity limit");
      }
    }
    const RolloutStatus s = check_state(f.sim, ws, q);
    if (s != RolloutStatus::Valid) {
      report("sample " + std::to_string(k) + " (t = " + std::to_string(traj.t[k]) +
             "): check_state says " + rollout_status_name(s));
    }
    if (k > 0) {
      const double dt = traj.t[k] - traj.t[k - 1];
      for (int j = 0; j < n; ++j) {
        const double jump = std::abs(q[j] - traj.q[k - 1][j]);
        if (jump > robot.dq_max[j] * dt + 1e-6) {
          report("discontinuity between samples " + std::to_string(k - 1) + " and " +
                 std::to_string(k) + ": joint " + std::to_string(j + 1) + " moves " +
                 std::to_string(jump) + " rad in " + std::to_string(dt) + " s");
        }
      }
    }
  }
  // Edges: one per step; bundle edges for the bundle planners, -1 for RRT/SST commands.
  if (traj.edges.empty()) report("no edges listed");
  for (int64_t e : traj.edges) {
    if (is_bundle_planner(planner)) {
      if (e < 0 || e >= static_cast<int64_t>(f.view.size()))
        report("edge " + std::to_string(e) + " is not a bundle edge");
    } else if (e != -1) {
      report("edge " + std::to_string(e) + " listed for an " + planner + " command (expected -1)");
    }
  }
  if (reported > 12) p << "  (" << reported - 12 << " more)\n";
  return p.str();
}

// Simulates `commands` one after another from `start` (each from the previous simulated end)
// and compares the end and the total time with the trajectory's. Empty when they agree.
std::string resimulate(const Fixture& f, const JointVectorRef& start,
                       const std::vector<CommandProfile>& commands, const Trajectory& traj) {
  std::ostringstream p;
  p.precision(17);
  SimulatorWorkspace ws(f.sim);
  JointVector q = start;
  double time = 0;
  for (size_t k = 0; k < commands.size(); ++k) {
    const RolloutResult r = simulate(f.sim, ws, q, commands[k]);
    if (!r.valid()) {
      p << "  step " << k
        << " fails when simulated from the previous end: " << rollout_status_name(r.status) << "\n";
      return p.str();
    }
    q = r.qf;
    time += r.duration;
  }
  const double error = (q - traj.q.back()).cwiseAbs().maxCoeff();
  if (!(error <= 1e-9)) {
    p << "  re-simulated end " << str(q) << " differs from the trajectory's last q "
      << str(traj.q.back()) << " by " << error << " rad\n";
  }
  if (!(std::abs(time - traj.t.back()) <= 1e-9)) {
    p << "  re-simulated duration " << time << " s differs from the trajectory's " << traj.t.back()
      << " s\n";
  }
  return p.str();
}

std::vector<CommandProfile> bundle_commands(const Fixture& f, const std::vector<int64_t>& edges) {
  std::vector<CommandProfile> c;
  for (int64_t e : edges) c.push_back(f.view.command(static_cast<size_t>(e)));
  return c;
}

// ------------------------------------------------------------------------------------------
// Shared runs (computed once per process, used by several tests)
// ------------------------------------------------------------------------------------------

const std::vector<std::string> kPlanners = {"lazyboe", "boe", "rrt", "sst"};

double easy_budget(const std::string& planner) { return is_bundle_planner(planner) ? 1.5 : 3.0; }

struct LibraryRun {
  std::string planner;
  PlanningProblem problem;
  PlanResult result;
  Trajectory trajectory;
  bool realized = false;
  std::string error;  // plan or realize_path threw
};

PlanningProblem library_problem(const Fixture& f, const JointVectorRef& start,
                                const JointVectorRef& goal, const std::string& planner,
                                double budget) {
  const BundleHeader& h = f.view.header();
  PlanningProblem p;
  p.start = start;
  p.goal.kind = Goal::Kind::Joint;
  p.goal.q = goal;
  p.goal.tolerance = kTolerance;
  p.params.planner = planner;
  p.params.theta = f.view.has_perturbation() ? f.view.perturbation_theta() : h.design_theta;
  p.params.budget = budget;
  p.params.seed = 1;
  p.params.sample_lower = joint(h.region_lower);
  p.params.sample_upper = joint(h.region_upper);
  p.params.command.min_duration = h.min_duration;
  p.params.command.max_duration = h.max_duration;
  p.params.command.knot_interval = h.knot_interval;
  p.params.command.velocity_scale = h.velocity_scale;
  p.params.command.limit_scale = h.limit_scale;
  return p;
}

constexpr int kSampleEvery = 10;  // 0.01 s at 1 kHz, the tool's default

// The easy problem a -> b with every planner, through the library, in parallel threads (one
// workspace each; the simulator, bundle and index are shared read-only, as in the tool).
const std::vector<LibraryRun>& library_runs() {
  static const std::vector<LibraryRun> runs = [] {
    const Fixture& f = fixture();
    const PlanningContext context{f.sim, &f.view, &f.index};
    std::vector<LibraryRun> out(kPlanners.size());
    std::vector<std::thread> threads;
    for (size_t i = 0; i < kPlanners.size(); ++i) {
      threads.emplace_back([&, i] {
        LibraryRun& r = out[i];
        r.planner = kPlanners[i];
        r.problem = library_problem(f, f.a, f.b, r.planner, easy_budget(r.planner));
        SimulatorWorkspace ws(f.sim);
        try {
          r.result = plan(context, ws, r.problem);
          if (r.result.success) {
            r.trajectory = realize_path(f.sim, ws, r.problem.start, r.result.best_path,
                                        r.problem.goal, kSampleEvery);
            r.realized = true;
          }
        } catch (const std::exception& e) {
          r.error = e.what();
        }
      });
    }
    for (std::thread& t : threads) t.join();
    return out;
  }();
  return runs;
}

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
// only a bound, far above the time the first solution takes): every planner a -> b, LazyBoE and
// BoE b -> a, and last LazyBoE and BoE a -> c (paths of several steps, the slowest queries).
std::vector<json> deterministic_queries() {
  const Fixture& f = fixture();
  std::vector<json> q;
  for (const std::string& p : kPlanners) q.push_back(query(p + "-ab", f.a, f.b, p, 5, true, 3));
  q.push_back(query("lazyboe-ba", f.b, f.a, "lazyboe", 5, true, 5));
  q.push_back(query("boe-ba", f.b, f.a, "boe", 5, true, 5));
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
// 1. Every planner finds a path on an easy problem
// ------------------------------------------------------------------------------------------

TEST(Query, EveryPlannerSolvesAnEasyProblemThroughLibraryAndTool) {
  const Fixture& f = fixture();
  ASSERT_GE((f.a - f.b).norm(), 0.35);
  ASSERT_LE((f.a - f.b).norm(), 0.45);
  for (const LibraryRun& r : library_runs()) {
    SCOPED_TRACE("library, " + r.planner);
    EXPECT_TRUE(r.error.empty()) << r.error;
    EXPECT_TRUE(r.result.success) << "failure: " << r.result.failure;
    EXPECT_TRUE(r.realized);
    EXPECT_GE(r.result.n_solutions, 1);
    EXPECT_FALSE(r.result.best_path.empty());
    EXPECT_GE(r.result.time_to_first_solution, 0.0);
    EXPECT_LE(r.result.time_to_first_solution, r.problem.params.budget + 0.5);
    EXPECT_TRUE(r.result.failure.empty()) << r.result.failure;
  }
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

TEST(Query, EveryReturnedTrajectoryPassesIndependentRevalidation) {
  const Fixture& f = fixture();
  int checked = 0;
  for (const LibraryRun& r : library_runs()) {
    if (!r.realized) continue;
    SCOPED_TRACE("library, " + r.planner);
    EXPECT_EQ(validate(f, r.trajectory, f.a, f.b, kTolerance, r.planner), "");
    // One edges entry per path step, naming the step's bundle edge.
    ASSERT_EQ(r.trajectory.edges.size(), r.result.best_path.size());
    for (size_t k = 0; k < r.result.best_path.size(); ++k) {
      EXPECT_EQ(r.trajectory.edges[k], r.result.best_path[k].bundle_edge) << "step " << k;
    }
    ++checked;
  }
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
  EXPECT_EQ(checked, 8 + static_cast<int>(queries.size()))
      << "every query should have returned a trajectory";
}

// The checks above must catch what they look for: broken copies of a valid trajectory.
TEST(Query, TheRevalidationCatchesBrokenTrajectories) {
  const Fixture& f = fixture();
  const LibraryRun* run = nullptr;
  for (const LibraryRun& r : library_runs()) {
    if (r.realized && r.planner == "boe") run = &r;
  }
  ASSERT_NE(run, nullptr) << "boe found no path";
  const Trajectory& good = run->trajectory;
  ASSERT_GE(good.t.size(), 4u);
  const size_t mid = good.t.size() / 2;
  auto problems = [&](const Trajectory& t) {
    return validate(f, t, t.q[0], f.b, kTolerance, "boe");
  };
  SimulatorWorkspace ws(f.sim);
  JointVector collide = good.q[mid];
  while (check_state(f.sim, ws, collide) == RolloutStatus::Valid && collide[1] < f.robot.q_max[1])
    collide[1] += 0.05;
  ASSERT_NE(check_state(f.sim, ws, collide), RolloutStatus::Valid);

  Trajectory t = good;
  t.t[mid] = t.t[mid - 1];
  EXPECT_TRUE(contains(problems(t), "strictly increasing")) << problems(t);
  t = good;
  t.dq[0][3] = 0.01;
  EXPECT_TRUE(contains(problems(t), "first dq")) << problems(t);
  t = good;
  t.q[mid][2] += 0.2;
  EXPECT_TRUE(contains(problems(t), "discontinuity")) << problems(t);
  t = good;
  t.q[mid] = collide;
  EXPECT_TRUE(contains(problems(t), "check_state")) << problems(t);
  t = good;
  t.dq[mid][0] = f.robot.dq_max[0] * 1.01;
  EXPECT_TRUE(contains(problems(t), "velocity limit")) << problems(t);
  t = good;
  t.q.back() = f.a;
  EXPECT_TRUE(contains(problems(t), "from the goal")) << problems(t);
  t = good;
  t.edges.back() = static_cast<int64_t>(f.view.size());
  EXPECT_TRUE(contains(problems(t), "not a bundle edge")) << problems(t);
  EXPECT_TRUE(contains(validate(f, good, f.b, f.b, kTolerance, "boe"), "query start"));
  // An end state that is not the simulated one (a stored, lazy end would differ like this).
  t = good;
  t.q.back()[6] += 1e-6;
  EXPECT_TRUE(contains(resimulate(f, f.a, bundle_commands(f, good.edges), t), "differs"));
  t = good;
  t.t.back() += 0.01;
  EXPECT_TRUE(contains(resimulate(f, f.a, bundle_commands(f, good.edges), t), "duration"));
  EXPECT_EQ(resimulate(f, f.a, bundle_commands(f, good.edges), good), "");
}

// ------------------------------------------------------------------------------------------
// 3. No lazy edge in any output
// ------------------------------------------------------------------------------------------

TEST(Query, OutputsAreMadeOfSimulatedEdgesOnly) {
  const Fixture& f = fixture();
  bool lazy_somewhere = false;
  for (const LibraryRun& r : library_runs()) {
    if (!r.realized) continue;
    SCOPED_TRACE("library, " + r.planner);
    // The path's commands, simulated one after the other from the start, end exactly where
    // the trajectory ends; for the bundle planners the edge ids name the same commands.
    std::vector<CommandProfile> commands;
    for (const PathStep& s : r.result.best_path) {
      commands.push_back({s.knots.data(), static_cast<int>(s.knots.size() / f.robot.dof),
                          f.robot.dof, s.command_duration});
    }
    EXPECT_EQ(resimulate(f, f.a, commands, r.trajectory), "");
    if (is_bundle_planner(r.planner)) {
      EXPECT_EQ(resimulate(f, f.a, bundle_commands(f, r.trajectory.edges), r.trajectory), "");
    }
    // A lazy node's cost is an estimate from stored states; a path of simulated edges costs
    // exactly what re-simulating it measures.
    EXPECT_NEAR(r.result.best_cost, r.trajectory.cost, 1e-9);
    if (r.planner == "lazyboe") lazy_somewhere |= r.result.counters.lazy_edges > 0;
    if (r.planner != "lazyboe") {
      EXPECT_EQ(r.result.counters.lazy_edges, 0u);
    }
  }
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
      EXPECT_EQ(resimulate(f, starts[i], bundle_commands(f, traj.edges), traj), "");
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

TEST(Query, FixedSeedAndOneJobGiveIdenticalResults) {
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

// Rollouts of one query run in parallel (--sim-threads) give the same answers as one thread:
// the reference run above simulates everything in turn. Three threads on any machine: the
// waves of rollouts then differ from one and two threads.
TEST(Query, ParallelRolloutsGiveTheSameAnswersAsOneThread) {
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

// Bad --sim-threads values: one line naming the option, before the bundle is even opened.
TEST(Query, BadSimThreadsAreRefusedWithOneLine) {
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

// More threads than cores works, with a warning saying why it is slow.
TEST(Query, MoreSimThreadsThanCoresWarns) {
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

// Through the library: the pool does run rollouts, and the search uses them exactly as its own.
TEST(Query, ARolloutPoolChangesNothingButWhoSimulates) {
  const Fixture& f = fixture();
  const PlanningContext context{f.sim, &f.view, &f.index};
  for (const std::string planner : {"lazyboe", "boe"}) {
    SCOPED_TRACE(planner);
    PlanningProblem p = library_problem(f, f.a, f.c, planner, 10);
    p.params.stop_at_first = true;
    p.params.seed = 7;
    SimulatorWorkspace ws(f.sim);
    const PlanResult alone = plan(context, ws, p);
    RolloutPool pool(f.sim, 3);
    const PlanResult pooled = plan(context, ws, p, &pool);
    ASSERT_TRUE(alone.success) << alone.failure;
    EXPECT_GT(pool.rollouts(), 0u) << "the search did not use the pool";
    // Unused rollouts are only those of the last wave, when the search stops.
    EXPECT_LE(pool.rollouts(), pooled.counters.simulations + kWavePerThread * pool.threads() - 1);
    EXPECT_EQ(pooled.success, alone.success);
    EXPECT_EQ(pooled.n_solutions, alone.n_solutions);
    EXPECT_EQ(pooled.best_cost, alone.best_cost);
    EXPECT_EQ(pooled.counters.nodes, alone.counters.nodes);
    EXPECT_EQ(pooled.counters.simulations, alone.counters.simulations);
    EXPECT_EQ(pooled.counters.lazy_edges, alone.counters.lazy_edges);
    EXPECT_EQ(pooled.counters.collision_checks, alone.counters.collision_checks);
    ASSERT_EQ(pooled.best_path.size(), alone.best_path.size());
    for (size_t s = 0; s < alone.best_path.size(); ++s)
      EXPECT_EQ(pooled.best_path[s].bundle_edge, alone.best_path[s].bundle_edge) << "step " << s;
  }
}

// ------------------------------------------------------------------------------------------
// 5. Bad query lines: error results naming the line; the rest of the batch still succeeds
// ------------------------------------------------------------------------------------------

TEST(Query, BadLinesGetErrorResultsAndTheOthersStillSucceed) {
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

TEST(Query, MemoryMappedAndReadIntoMemoryGiveIdenticalAnswers) {
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

TEST(Query, IncompleteMissingAndUnperturbedBundlesAreRefused) {
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
  // boe on the same bundle still works.
  const BundleView plain = BundleView::open(f.unperturbed);
  EXPECT_FALSE(plain.has_perturbation());
  const std::string batch = write_temp_file("refused/unperturbed.jsonl",
                                            jsonl({query("lazy", f.a, f.b, "lazyboe", 1, true),
                                                   query("plain", f.a, f.b, "boe", 2, true)}));
  const ToolRun t3 = query_tool({"--bundle", f.unperturbed, "--queries", batch, "--quiet"});
  ASSERT_EQ(t3.r.exit_code, 0) << describe(t3.r);
  ASSERT_EQ(t3.results.size(), 2u) << describe(t3.r);
  EXPECT_EQ(t3.results[0].value("success", true), false);
  EXPECT_EQ(t3.results[0].value("line", -1), 1);
  EXPECT_TRUE(t3.results[0].contains("error") &&
              contains(t3.results[0]["error"].get<std::string>(), "lazyboe-perturb"))
      << t3.results[0].dump();
  expect_solved(t3.results[1], "boe without perturbation");
  // And through the library.
  const EdgeStartIndex plain_index(plain);
  const PlanningContext context{f.sim, &plain, &plain_index};
  SimulatorWorkspace ws(f.sim);
  try {
    plan(context, ws, library_problem(f, f.a, f.b, "lazyboe", 1));
    ADD_FAILURE() << "lazyboe planned on a bundle without perturbation analysis";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), "lazyboe-perturb")) << e.what();
  }
}

// ------------------------------------------------------------------------------------------
// 7. Streaming from standard input
// ------------------------------------------------------------------------------------------

TEST(Query, StreamingFromStandardInputFlushesOneLinePerQuery) {
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

TEST(Query, RobotOrEnvironmentOtherThanTheBundlesIsRefusedAtStart) {
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
  const std::string shelf = source_path("data/environments/shelf.json");
  struct Case {
    std::vector<std::string> args;
    std::string names;
  };
  for (const Case& c :
       {Case{{"--robot", other_robot}, other_robot}, Case{{"--env", shelf}, shelf}}) {
    SCOPED_TRACE(c.names);
    const std::string out = dir + "/refused.jsonl";
    std::vector<std::string> args = {"--bundle", f.path, "--queries", queries, "--out", out};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const CommandResult r = run(query_command(args));
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_EQ(count_lines(r.err), 1) << describe(r);
    EXPECT_TRUE(contains(r.err, c.names)) << describe(r);
    EXPECT_TRUE(r.out.empty()) << describe(r);
    EXPECT_FALSE(fs::exists(out)) << "results written although refused";
  }
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

TEST(Query, CsvTrajectoriesHaveTheInlineRows) {
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
  std::string expected_header = "t";
  for (int i = 1; i <= 7; ++i) expected_header += ",q" + std::to_string(i);
  for (int i = 1; i <= 7; ++i) expected_header += ",dq" + std::to_string(i);
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
      ASSERT_EQ(rows[k].size(), 15u) << "row " << k;
      std::vector<double> want = {traj.t[k]};
      for (int j = 0; j < 7; ++j) want.push_back(traj.q[k][j]);
      for (int j = 0; j < 7; ++j) want.push_back(traj.dq[k][j]);
      for (size_t c = 0; c < 15; ++c) {
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

// ------------------------------------------------------------------------------------------
// 9. Start or goal outside the bundle's coverage
// ------------------------------------------------------------------------------------------

// The smallest distance from q to the starts (or ends) of every edge.
double nearest_distance(const Fixture& f, const JointVectorRef& q, bool ends) {
  const int n = f.data.dof();
  const std::vector<double>& v = ends ? f.data.qf : f.data.q0;
  double best = std::numeric_limits<double>::infinity();
  for (size_t e = 0; e < f.data.size(); ++e) {
    best = std::min(best, (joint(std::vector<double>(&v[e * n], &v[e * n] + n)) - q).norm());
  }
  return best;
}

// A collision-free state within the limits whose first joint is moved by one of `offsets`
// from `base`, farther than `clearance` from every edge start (or end).
JointVector far_state(const Fixture& f, const JointVectorRef& base,
                      const std::vector<double>& offsets, double clearance, bool ends) {
  SimulatorWorkspace ws(f.sim);
  for (double d : offsets) {
    JointVector q = base;
    q[0] += d;
    if (check_state(f.sim, ws, q) == RolloutStatus::Valid &&
        nearest_distance(f, q, ends) > clearance)
      return q;
  }
  return JointVector();
}

TEST(Query, StartOrGoalOutsideTheCoverageFailsWithAReason) {
  const Fixture& f = fixture();
  const double theta = f.view.perturbation_theta();
  const JointVector far_start = far_state(f, f.a, {1.5, -1.5, 2.0, -2.0, 1.2, -1.2}, theta, false);
  ASSERT_EQ(far_start.size(), 7) << "no collision-free state far from the bundle's starts";
  const JointVector far_goal =
      far_state(f, f.b, {2.2, -2.2, 2.5, -2.5, 1.8, -1.8}, theta + kTolerance, true);
  ASSERT_EQ(far_goal.size(), 7) << "no collision-free state far from the bundle's ends";

  // Library: a clear failure at once, not a timeout.
  const PlanningContext context{f.sim, &f.view, &f.index};
  SimulatorWorkspace ws(f.sim);
  for (const std::string planner : {"lazyboe", "boe"}) {
    for (bool start_is_far : {true, false}) {
      SCOPED_TRACE(planner + std::string(start_is_far ? ", far start" : ", far goal"));
      const auto t0 = Clock::now();
      const PlanResult r = plan(context, ws,
                                library_problem(f, start_is_far ? far_start : f.a,
                                                start_is_far ? f.b : far_goal, planner, 5));
      const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      EXPECT_FALSE(r.success);
      EXPECT_LT(seconds, 1.0) << "ran into its 5 s budget instead of failing at once";
      EXPECT_TRUE(contains(r.failure, "theta")) << "failure: " << r.failure;
      EXPECT_TRUE(contains(r.failure, "bundle")) << "failure: " << r.failure;
      EXPECT_TRUE(contains(r.failure, start_is_far ? "start" : "goal")) << "failure: " << r.failure;
      EXPECT_FALSE(contains(r.failure, "time budget")) << "failure: " << r.failure;
    }
  }
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

// An edge whose stored end lies at its own start can be taken lazily again and again from that
// end, with the heuristic unchanged. Such a chain must end (a tie counts as the heuristic
// rising), so every lazy edge costs a simulation; before, it grew for free until the budget.
TEST(Query, ALazyChainWithoutProgressEnds) {
  const Fixture& f = fixture();
  const int n = f.data.dof();
  const size_t k = 0;
  Bundle one;
  one.header = f.data.header;
  auto rows = [&](const std::vector<double>& v, size_t from, size_t to) {
    return std::vector<double>(v.begin() + from * n, v.begin() + to * n);
  };
  one.q0 = rows(f.data.q0, k, k + 1);
  one.qf = one.q0;  // the stored end is the start
  one.duration = {f.data.duration[k]};
  one.command_duration = {f.data.command_duration[k]};
  one.attempt = {f.data.attempt[k]};
  one.knot_offset = {0, f.data.knot_offset[k + 1] - f.data.knot_offset[k]};
  one.knots = rows(f.data.knots, f.data.knot_offset[k], f.data.knot_offset[k + 1]);
  one.sample_offset = {0, 0};
  one.header.valid = 1;
  one.header.target_edges = 1;
  Perturbation& p = one.perturbation;
  p = f.data.perturbation;
  p.done = {p.perturbations};
  p.valid = {p.perturbations};
  p.lazy = {p.perturbations};
  p.collision = {0};
  p.max_error = {0.0};
  p.p_lazy_prop = {1.0};  // always taken lazily
  p.p_collision = {0.0};
  const std::string path = fresh_dir("self-loop") + "/one.h5";
  write_bundle(path, one);
  const BundleView view = BundleView::open(path);
  const EdgeStartIndex index(view);
  const PlanningContext context{f.sim, &view, &index};

  const JointVector start = f.edge_start(k);
  JointVector goal = start;
  goal[n - 1] += 0.5;  // beyond the tolerance, within theta + tolerance of the stored end
  PlanningProblem problem = library_problem(f, start, goal, "lazyboe", 0.5);
  SimulatorWorkspace ws(f.sim);
  const PlanResult r = plan(context, ws, problem);
  EXPECT_GT(r.counters.lazy_edges, 0u);
  EXPECT_LE(r.counters.lazy_edges, r.counters.simulations + 2)
      << "lazy edges " << r.counters.lazy_edges << ", simulations " << r.counters.simulations
      << ": a lazy chain went on without simulating";
}

}  // namespace
}  // namespace lazyboe::test
