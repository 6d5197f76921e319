// lazyboe-view through the real tool: what goes into the page (read back from the JSON it
// inlines), a self-contained file, and bad input as one-line errors. What the page shows in a
// browser is tested by tests/viewer/test_viewer.py (headless Chromium).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/robot/kinematics.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

using nlohmann::json;

CommandResult view_tool(const std::vector<std::string>& args) {
  std::string cmd = quote(tool_path("lazyboe-view"));
  for (const std::string& a : args) cmd += " " + quote(a);
  return run(cmd);
}

// The scene data the page carries (<script id="lazyboe-data" type="application/json">).
json page_data(const std::string& html_path) {
  const std::string page = read_file(html_path);
  const std::string open = "<script id=\"lazyboe-data\" type=\"application/json\">";
  const size_t begin = page.find(open);
  EXPECT_NE(begin, std::string::npos) << html_path << " has no data element";
  if (begin == std::string::npos) return json();
  const size_t end = page.find("</script>", begin);
  std::string text = page.substr(begin + open.size(), end - begin - open.size());
  return json::parse(text);
}

const std::vector<double> kReady = {0, -0.785, 0, -2.356, 0, 1.571, 0.785};
const std::vector<double> kOther = {0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.4};

// A result line with an inline trajectory from `a` to `b` (linear, `samples` samples over 1 s).
json trajectory_result(const std::string& id, int line, const std::vector<double>& a,
                       const std::vector<double>& b, int samples) {
  json t = json::array(), q = json::array(), dq = json::array();
  for (int i = 0; i < samples; ++i) {
    const double s = samples > 1 ? double(i) / (samples - 1) : 0;
    t.push_back(s);
    json row = json::array();
    for (size_t k = 0; k < a.size(); ++k) row.push_back(a[k] + s * (b[k] - a[k]));
    q.push_back(row);
    dq.push_back(std::vector<double>(a.size(), 0.0));
  }
  return {{"id", id},
          {"line", line},
          {"planner", "lazysp"},
          {"success", true},
          {"time_to_first_solution", 0.01},
          {"n_solutions", 1},
          {"best_cost", 1.5},
          {"duration", 1.0},
          {"edges", {4, -1, 7}},
          {"trajectory", {{"t", t}, {"q", q}, {"dq", dq}}}};
}

json failed_result(const std::string& id, int line, const std::string& failure) {
  return {{"id", id},         {"line", line},        {"planner", "lazyboe"},
          {"success", false}, {"failure", failure},  {"time_to_first_solution", nullptr},
          {"n_solutions", 0}, {"best_cost", nullptr}};
}

std::string lines(const std::vector<json>& rows) {
  std::string s;
  for (const json& r : rows) s += r.dump() + "\n";
  return s;
}

json query_line(const std::string& id, const std::vector<double>& start,
                const std::vector<double>& goal) {
  return {{"id", id}, {"start", start}, {"goal", {{"q", goal}, {"tolerance", 0.1}}}};
}

// A small bundle built and perturbed by the real tools, once per process.
const std::string& small_bundle() {
  static const std::string path = [] {
    const std::string p = temp_dir() + "/view-bundle.h5";
    const CommandResult b = run(quote(tool_path("lazyboe-build")) + " --out " + quote(p) +
                                " --edges 200 --seed 3 --quiet");
    EXPECT_EQ(b.exit_code, 0) << describe(b);
    const CommandResult pt = run(quote(tool_path("lazyboe-perturb")) + " --bundle " + quote(p) +
                                 " --perturbations 2 --quiet");
    EXPECT_EQ(pt.exit_code, 0) << describe(pt);
    return p;
  }();
  return path;
}

TEST(ViewCli, PageCarriesTrajectoriesFailuresAndTheirQueries) {
  const std::string dir = fresh_dir("view_main");
  write_temp_file("view_main/results.jsonl",
                  lines({trajectory_result("a", 1, kReady, kOther, 11),
                         failed_result("b", 2, "no bundle coverage of the goal"),
                         {{"id", "c"},
                          {"line", 3},
                          {"planner", nullptr},
                          {"success", false},
                          {"error", "line 3: start: in collision"},
                          {"time_to_first_solution", nullptr},
                          {"n_solutions", 0},
                          {"best_cost", nullptr}}}));
  write_temp_file("view_main/queries.jsonl",
                  lines({query_line("a", kReady, kOther), query_line("b", kOther, kReady),
                         query_line("c", kReady, kReady)}));
  const std::string out = dir + "/view.html";
  const CommandResult r = view_tool(
      {"--results", dir + "/results.jsonl", "--queries", dir + "/queries.jsonl", "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(count_lines(r.out), 1) << describe(r);
  EXPECT_TRUE(contains(r.out, "1 trajectories, 2 failed queries")) << describe(r);
  const json d = page_data(out);
  const json& res = d["results"];
  ASSERT_EQ(res["trajectories"].size(), 1u);
  const json& tr = res["trajectories"][0];
  EXPECT_EQ(tr["id"], "a");
  EXPECT_EQ(tr["edges"], json({4, -1, 7}));
  EXPECT_EQ(tr["samples"]["q"].size(), 11u);  // 0.1 s apart: all kept
  EXPECT_EQ(tr["start"], json(kReady));
  ASSERT_EQ(res["failures"].size(), 2u);
  EXPECT_EQ(res["failures"][0]["reason"], "no bundle coverage of the goal");
  EXPECT_EQ(res["failures"][0]["kind"], "failure");
  EXPECT_EQ(res["failures"][0]["start"], json(kOther));
  EXPECT_EQ(res["failures"][0]["goal"]["q"], json(kReady));
  EXPECT_EQ(res["failures"][1]["reason"], "line 3: start: in collision");
  EXPECT_EQ(res["failures"][1]["kind"], "error");
  // The robot's chain as the library has it, and the bundled table's obstacles.
  EXPECT_EQ(d["robot"]["joints"].size(), 7u);
  EXPECT_EQ(d["robot"]["shapes"].size(), panda().geometry.bodies.size());
  EXPECT_GT(d["environment"]["obstacles"].size(), 0u);
}

// One file with everything inlined: nothing for the browser to fetch.
TEST(ViewCli, PageIsSelfContained) {
  const std::string dir = fresh_dir("view_self");
  const std::string out = dir + "/view.html";
  const CommandResult r = view_tool({"--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::string page = read_file(out);
  for (const char* external : {"<script src", "<link", "@import", "src=\"http", "href=\"http"})
    EXPECT_FALSE(contains(page, external)) << "page refers to something outside: " << external;
  EXPECT_TRUE(contains(page, "OrbitControls"));
  EXPECT_TRUE(contains(page, "lazyboeView"));
  EXPECT_TRUE(page_data(out)["results"].is_null());
  EXPECT_TRUE(files_in(dir) == std::vector<std::string>{"view.html"}) << join(files_in(dir));
}

TEST(ViewCli, TrajectoriesFromCsvFilesNextToTheResults) {
  const std::string dir = fresh_dir("view_csv");
  std::filesystem::create_directories(dir + "/trajectories");
  write_temp_file("view_csv/trajectories/a.csv",
                  "t,q1,q2,q3,q4,q5,q6,q7,dq1,dq2,dq3,dq4,dq5,dq6,dq7\n"
                  "0,0,-0.785,0,-2.356,0,1.571,0.785,0,0,0,0,0,0,0\n"
                  "0.5,0.1,-0.785,0,-2.356,0,1.571,0.785,0,0,0,0,0,0,0\n");
  json result = trajectory_result("a", 1, kReady, kOther, 2);
  result.erase("trajectory");
  result["trajectory_file"] = "somewhere/else/trajectories/a.csv";  // as lazyboe-query ran
  write_temp_file("view_csv/results.jsonl", lines({result}));
  const std::string out = dir + "/view.html";
  // Found by its name next to the results when the path as written does not exist.
  std::filesystem::copy_file(dir + "/trajectories/a.csv", dir + "/a.csv");
  const CommandResult r = view_tool({"--results", dir + "/results.jsonl", "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const json samples = page_data(out)["results"]["trajectories"][0]["samples"];
  EXPECT_EQ(samples["t"], json({0.0, 0.5}));
  EXPECT_DOUBLE_EQ(samples["q"][1][0].get<double>(), 0.1);
}

// A 1 kHz trajectory is thinned to the page's sample interval, its ends kept.
TEST(ViewCli, ThinsDenseTrajectories) {
  const std::string dir = fresh_dir("view_thin");
  write_temp_file("view_thin/results.jsonl",
                  lines({trajectory_result("a", 1, kReady, kOther, 1001)}));
  const std::string out = dir + "/view.html";
  const CommandResult r = view_tool({"--results", dir + "/results.jsonl", "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const json samples = page_data(out)["results"]["trajectories"][0]["samples"];
  EXPECT_EQ(samples["t"].size(), 51u);  // 0, 0.02, ..., 1.0
  EXPECT_EQ(samples["t"].front(), 0.0);
  EXPECT_EQ(samples["t"].back(), 1.0);
  EXPECT_EQ(samples["q"].back(), json(kOther));
}

TEST(ViewCli, ResultsWithoutTrajectoriesGiveAPageThatSaysSo) {
  const std::string dir = fresh_dir("view_none");
  json result = trajectory_result("a", 1, kReady, kOther, 2);
  result.erase("trajectory");
  write_temp_file("view_none/results.jsonl", lines({result}));
  write_temp_file("view_none/empty.jsonl", "");
  for (const std::string name : {"results", "empty"}) {
    const std::string out = dir + "/" + name + ".html";
    const CommandResult r = view_tool({"--results", dir + "/" + name + ".jsonl", "--out", out});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_TRUE(contains(r.out, "0 trajectories")) << describe(r);
    const json res = page_data(out)["results"];
    EXPECT_EQ(res["trajectories"].size(), 0u);
    EXPECT_EQ(res["without_trajectory"].size(), name == "results" ? 1u : 0u);
  }
}

TEST(ViewCli, BundleSampleIsSeededAndMatchesTheKinematics) {
  const std::string dir = fresh_dir("view_bundle");
  const auto page = [&](const std::string& name, const std::string& seed) {
    const std::string out = dir + "/" + name;
    const CommandResult r = view_tool(
        {"--bundle", small_bundle(), "--bundle-points", "100", "--seed", seed, "--out", out});
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return out;
  };
  const std::string a = page("a.html", "5"), b = page("b.html", "5"), c = page("c.html", "6");
  EXPECT_EQ(read_file(a), read_file(b));
  const json d = page_data(a)["bundle"];
  EXPECT_NE(d["edge_ids"], page_data(c)["bundle"]["edge_ids"]);
  ASSERT_EQ(d["edge_ids"].size(), 50u);
  ASSERT_EQ(d["points"].size(), 300u);
  ASSERT_EQ(d["density"].size(), 100u);
  ASSERT_EQ(d["p_lazy_prop"].size(), 100u);
  ASSERT_EQ(d["p_collision"].size(), 100u);
  for (size_t i = 0; i < 100; ++i) {
    if (i % 2 == 0) {
      EXPECT_GE(d["density"][i].get<int>(), 1);  // an edge's own start
    }
    EXPECT_GE(d["p_lazy_prop"][i].get<double>(), 0.0);
    EXPECT_LE(d["p_lazy_prop"][i].get<double>(), 1.0);
  }
  // The first point is the flange at the first sampled edge's start.
  const BundleView bundle = BundleView::open(small_bundle());
  RobotData data(panda());
  const size_t e = d["edge_ids"][0];
  forward_kinematics(panda(), data, Eigen::Map<const Eigen::VectorXd>(bundle.q0(e), 7));
  const Eigen::Vector3d p = link_pose(panda(), data, panda().tip_link()).p;
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(d["points"][k].get<double>(), p[k], 0.5e-4);
}

// A bundle without a perturbation analysis: density only, and the page is told so.
TEST(ViewCli, BundleWithoutPerturbationHasDensityOnly) {
  const std::string dir = fresh_dir("view_unperturbed");
  const std::string bundle = dir + "/b.h5";
  const CommandResult b = run(quote(tool_path("lazyboe-build")) + " --out " + quote(bundle) +
                              " --edges 30 --seed 4 --quiet");
  ASSERT_EQ(b.exit_code, 0) << describe(b);
  const std::string out = dir + "/view.html";
  const CommandResult r = view_tool({"--bundle", bundle, "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const json d = page_data(out)["bundle"];
  EXPECT_FALSE(d["has_perturbation"].get<bool>());
  EXPECT_FALSE(d.contains("p_lazy_prop"));
  EXPECT_EQ(d["density"].size(), 60u);  // every edge: fewer than the points asked for
}

// ---- Bad input: one line naming what is wrong, no page -----------------------------------

void expect_no_page(const std::string& dir) {
  EXPECT_TRUE(files_in(dir).empty() || !contains(join(files_in(dir)), "view.html"))
      << join(files_in(dir));
  EXPECT_TRUE(tmp_files_in(dir).empty()) << join(tmp_files_in(dir));
}

TEST(ViewCli, MissingResultsFile) {
  const std::string dir = fresh_dir("view_missing");
  expect_one_line_error(view_tool({"--results", dir + "/none.jsonl", "--out", dir + "/view.html"}),
                        {"none.jsonl", "results"});
  expect_no_page(dir);
}

TEST(ViewCli, ResultLineThatIsNotJsonNamesItsLine) {
  const std::string dir = fresh_dir("view_syntax");
  write_temp_file("view_syntax/results.jsonl",
                  lines({trajectory_result("a", 1, kReady, kOther, 2)}) + "{not json\n");
  expect_one_line_error(
      view_tool({"--results", dir + "/results.jsonl", "--out", dir + "/view.html"}),
      {"results.jsonl:2"});
  expect_no_page(dir);
}

TEST(ViewCli, TrajectoryRowOfTheWrongWidthNamesTheField) {
  const std::string dir = fresh_dir("view_width");
  json result = trajectory_result("a", 1, kReady, kOther, 3);
  result["trajectory"]["q"][1].erase(6);
  write_temp_file("view_width/results.jsonl", lines({result}));
  expect_one_line_error(
      view_tool({"--results", dir + "/results.jsonl", "--out", dir + "/view.html"}),
      {"results.jsonl:1", "trajectory.q[1]", "7 numbers"});
  expect_no_page(dir);
}

TEST(ViewCli, ResultsThatDoNotMatchTheQueries) {
  const std::string dir = fresh_dir("view_mismatch");
  write_temp_file("view_mismatch/results.jsonl", lines({failed_result("b", 1, "time budget")}));
  write_temp_file("view_mismatch/queries.jsonl", lines({query_line("a", kReady, kOther)}));
  expect_one_line_error(view_tool({"--results", dir + "/results.jsonl", "--queries",
                                   dir + "/queries.jsonl", "--out", dir + "/view.html"}),
                        {"results.jsonl:1", "'b'", "'a'"});
  expect_no_page(dir);
}

TEST(ViewCli, QueryGoalOfTheWrongSizeNamesTheField) {
  const std::string dir = fresh_dir("view_goal");
  write_temp_file("view_goal/results.jsonl", lines({failed_result("a", 1, "time budget")}));
  json query = query_line("a", kReady, kOther);
  query["goal"]["q"].erase(0);
  write_temp_file("view_goal/queries.jsonl", lines({query}));
  expect_one_line_error(view_tool({"--results", dir + "/results.jsonl", "--queries",
                                   dir + "/queries.jsonl", "--out", dir + "/view.html"}),
                        {"queries.jsonl:1", "goal.q", "7 numbers"});
  expect_no_page(dir);
}

TEST(ViewCli, MissingThreeJsIsOneClearLine) {
  const std::string dir = fresh_dir("view_three");
  expect_one_line_error(view_tool({"--three-dir", dir + "/nothing", "--out", dir + "/view.html"}),
                        {"three.js not found", "three.min.js", "libjs-three"});
  expect_no_page(dir);
}

// The collision model has primitives only: a robot whose URDF has a mesh collision is refused
// by the robot loader, naming the link and the mesh, before any page is written.
TEST(ViewCli, RobotWithMeshesIsRefused) {
  const std::string dir = fresh_dir("view_mesh");
  std::string urdf = read_file(source_path("data/robots/panda.urdf"));
  const std::string sphere = "<geometry><sphere radius=\"0.06\"/></geometry>";
  const size_t at = urdf.find(sphere);
  ASSERT_NE(at, std::string::npos);
  urdf.replace(at, sphere.size(),
               "<geometry><mesh filename=\"package://panda/meshes/link0.stl\"/></geometry>");
  write_temp_file("view_mesh/panda.urdf", urdf);
  const std::string config =
      write_temp_file("view_mesh/panda.json", read_file(source_path("data/robots/panda.json")));
  expect_one_line_error(view_tool({"--robot", config, "--out", dir + "/view.html"}),
                        {"view_mesh/panda.urdf", "panda_link0", "mesh"});
  EXPECT_FALSE(std::filesystem::exists(dir + "/view.html"));
}

TEST(ViewCli, OutputIsNeverAnInput) {
  const std::string dir = fresh_dir("view_out");
  const std::string results =
      write_temp_file("view_out/results.jsonl", lines({failed_result("b", 1, "time budget")}));
  const std::string before = read_file(results);
  expect_one_line_error(view_tool({"--results", results, "--out", results}),
                        {"--out", "--results"});
  EXPECT_EQ(read_file(results), before);
}

TEST(ViewCli, UnknownColouringIsRefused) {
  const std::string dir = fresh_dir("view_colour");
  const CommandResult r = view_tool({"--colour-by", "speed", "--out", dir + "/view.html"});
  expect_one_line_error(r, {"--colour-by"});
}

}  // namespace
}  // namespace lazyboe::test
