// lazyboe-query's bundles, streams and outputs, through the real tool on the small dense bundle
// of test_query_cli (helpers: query_cli_util.h): memory-mapped and read-into-memory bundles give
// identical answers, incomplete, missing and unperturbed bundles are refused; streaming from
// standard input; the robot and environment checked; CSV and inline trajectories, raw chains and
// the result schema; starts and goals outside the coverage.
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
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/sim/simulator.h"
#include "planning_fixture.h"
#include "query_cli_util.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

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

// A JSON array, as pretty-printed JSON tools write one, or a pretty-printed object, is one clear
// error for the file (not one "not valid JSON" result per line), and nothing is written.
TEST(QueryCli, AJsonArrayIsOneErrorNamingTheFormat) {
  const Fixture& f = fixture();
  const nlohmann::json batch = {query("a", f.a, f.b, "boe", 1, true),
                                query("b", f.b, f.a, "boe", 1, true)};
  const std::string dir = fresh_dir("array");
  const std::string file = write_temp_file("array/batch.json", batch.dump(2) + "\n");
  const ToolRun t =
      query_tool({"--bundle", f.path, "--queries", file, "--out", dir + "/r.jsonl", "--quiet"});
  expect_one_line_error(t.r, {file, "line 1: a JSON array", "JSON Lines", "jq -c"});
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"batch.json"});
  // One query pretty-printed over several lines, likewise.
  const std::string pretty = write_temp_file("array/one.json", batch[0].dump(2) + "\n");
  const ToolRun p =
      query_tool({"--bundle", f.path, "--queries", pretty, "--out", dir + "/r.jsonl", "--quiet"});
  expect_one_line_error(p.r,
                        {pretty, "line 1: a JSON object over lines 1-", "JSON Lines", "jq -c ."});
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"batch.json", "one.json"}));
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
  ASSERT_EQ(t3.r.exit_code, 3) << describe(t3.r);  // some lines had errors, the others ran
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
  EXPECT_EQ(t.r.exit_code, 3) << describe(t.r);  // some lines had errors
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
  EXPECT_EQ(timeless(a), timeless(b));
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
    EXPECT_TRUE(contains(failure, "try lazysp")) << "says what to do: " << failure;
  }
  std::cout << "[ reason  ] far start: "
            << (t.results.empty() ? "" : t.results[0].value("failure", "")) << "\n"
            << "[ reason  ] far goal:  "
            << (t.results.size() < 2 ? "" : t.results[1].value("failure", "")) << "\n";
}

// The summary on stderr counts what was solved, never rounds a failure up to 100%, shows a
// planner that solved nothing with dashes, and names the leading failure reason.
TEST(QueryCli, TheSummaryCountsTheSolvedQueries) {
  const Fixture& f = fixture();
  const JointVector far_start = far_start_state(f);
  ASSERT_EQ(far_start.size(), 7) << "no collision-free state far from the bundle's starts";
  const ToolRun t =
      run_batch("summary",
                {query("ok-1", f.a, f.b, "boe", 5, true), query("ok-2", f.b, f.a, "boe", 5, true),
                 query("far", far_start, f.b, "boe", 3, false),
                 query("far-lazy", far_start, f.b, "lazyboe", 3, false)},
                {});
  ASSERT_EQ(t.r.exit_code, 0) << describe(t.r);
  EXPECT_TRUE(contains(t.r.err, "1 failed, most often: ")) << t.r.err;
  // By kind: the reason without the query's own figures in parentheses.
  const std::string failure = t.results.size() > 2 ? t.results[2].value("failure", "?") : "?";
  EXPECT_TRUE(contains(failure, " (")) << failure;
  EXPECT_TRUE(contains(t.r.err, "most often: " + failure.substr(0, failure.find(" (")) + "\n"))
      << t.r.err;
  EXPECT_TRUE(contains(t.r.err, "solved")) << t.r.err;
  std::istringstream lines(t.r.err);
  bool found = false;
  for (std::string line; std::getline(lines, line);) {
    std::istringstream row(line);
    std::string planner, percent;
    size_t queries = 0, solved = 0;
    if (!(row >> planner >> queries >> solved >> percent) || planner != "boe") continue;
    found = true;
    EXPECT_EQ(queries, 3u) << line;
    EXPECT_EQ(solved, 2u) << line;
    EXPECT_EQ(percent, "66.6%") << line;  // rounded down
  }
  EXPECT_TRUE(found) << t.r.err;
  // lazyboe solved nothing: dashes where its figures would be.
  const auto dashed = [&] {
    std::istringstream rows(t.r.err);
    for (std::string line; std::getline(rows, line);) {
      std::istringstream row(line);
      std::string planner, queries, solved, percent, median, mean, cost;
      if (row >> planner >> queries >> solved >> percent >> median >> mean >> cost &&
          planner == "lazyboe")
        return solved == "0" && percent == "0.0%" && median == "-" && mean == "-" && cost == "-";
    }
    return false;
  };
  EXPECT_TRUE(dashed()) << t.r.err;
}

}  // namespace
}  // namespace lazyboe::test
