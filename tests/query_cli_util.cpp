// Helpers of the lazyboe-query command-line tests (test_query_cli, test_query_io_cli).
#include "query_cli_util.h"

#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "lazyboe/bundle/bundle_file.h"

namespace lazyboe::test {

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

const Fixture& fixture() { return shared_fixture<Fixture>(); }

// ------------------------------------------------------------------------------------------
// Queries and the tool
// ------------------------------------------------------------------------------------------

json query(const std::string& id, const JointVectorRef& start, const JointVectorRef& goal,
           const std::string& planner, double budget, bool stop_at_first, uint64_t seed) {
  json q;
  q["id"] = id;
  q["start"] = vec(start);
  q["goal"] = {{"q", vec(goal)}, {"tolerance", kTolerance}};
  q["planner"] = planner;
  q["budget"] = budget * time_scale();  // the sanitizers slow the planners
  q["seed"] = seed;
  if (stop_at_first) q["stop_at_first"] = true;
  // The searches are what these tests check: not the straight command tried first, nor
  // lazysp's direct command to the goal from a state near it, nor its shortcut of a candidate.
  const ParameterValues only_search = searching(planner);
  if (only_search.has("direct")) q["direct"] = false;
  if (only_search.has("connect_radius")) q["connect_radius"] = 0;
  if (only_search.has("candidate_shortcut")) q["candidate_shortcut"] = false;
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
                  std::vector<std::string> extra) {
  const std::string file = write_temp_file(name + ".jsonl", jsonl(queries));
  std::vector<std::string> args = {"--bundle", fixture().path, "--queries", file};
  args.insert(args.end(), extra.begin(), extra.end());
  return query_tool(args);
}

// A result without the fields that depend on the wall clock.
json timeless(json r) {
  r.erase("time_to_first_solution");
  r.erase("planning_seconds");
  r.erase("time_to_executable");
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

}  // namespace lazyboe::test
