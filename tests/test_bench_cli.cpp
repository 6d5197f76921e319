// lazyboe-bench end to end on one small bundle built here with the real tools: a tiny study
// (2 problems, 1 s budget) produces every file, with consistent rows; OMPL rows are run or
// reported as skipped, never silently missing; the problems file repeats a study exactly; an
// interrupted study (partial rows, a torn last line, or SIGINT) resumes without redoing runs;
// bad input is a one-line error that leaves earlier results untouched.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "cli_util.h"
#include "lazyboe/bench/report.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/ompl/ompl_planners.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRegion = "-0.3:0.3,0.0:0.5,-0.3:0.3,-2.3:-1.7,-0.3:0.3,1.6:2.2,0.5:1.1";

// A 1500-edge bundle in a small region with a p = 2 perturbation analysis, once per process.
const std::string& bundle() {
  static const std::string path = [] {
    const std::string dir = fresh_dir("bench-bundle"), out = dir + "/bundle.h5";
    const CommandResult b =
        run(watchdog(300) + quote(tool_path("lazyboe-build")) + " --out " + quote(out) +
            " --edges 1500 --region=" + kRegion + " --theta 0.45 --quiet");
    if (b.exit_code != 0) throw std::runtime_error("lazyboe-build failed: " + describe(b));
    const CommandResult p = run(watchdog(300) + quote(tool_path("lazyboe-perturb")) + " --bundle " +
                                quote(out) + " --perturbations 2 --quiet");
    if (p.exit_code != 0) throw std::runtime_error("lazyboe-perturb failed: " + describe(p));
    return out;
  }();
  return path;
}

// "--budget S" with S scaled by time_scale(): the sanitizers slow the planners.
std::string budget(double seconds) { return "--budget " + std::to_string(seconds * time_scale()); }

CommandResult bench(const std::string& args) {
  return run(watchdog(300) + quote(tool_path("lazyboe-bench")) + " --bundle " + quote(bundle()) +
             " " + args);
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

const std::string kHeader =
    "planner,problem,repeat,seed,success,time_to_first_solution,best_cost,n_solutions,nodes,"
    "simulations,lazy_edges,collision_checks,budget,failure,duration,stops,arc_length,"
    "raw_duration,raw_stops,post_seconds,junctions,blends_kept,shortcuts,found_by";

bool matplotlib_installed() {
  return std::system("/usr/bin/python3 -c 'import matplotlib' > /dev/null 2>&1") == 0;
}

// Every row is self-consistent: a success has a time within the budget, a positive cost and at
// least one solution, and an executed trajectory no longer than its raw chain with no more
// stops (the raw chain stops after every step); a failure has a reason and no time or cost.
void expect_consistent_rows(const std::vector<std::string>& rows, double budget) {
  for (size_t k = 1; k < rows.size(); ++k) {
    const std::vector<std::string> f = fields_of(rows[k]);
    ASSERT_EQ(f.size(), 24u) << rows[k];
    EXPECT_GT(std::stoull(f[9]), 0u) << "a run that simulated nothing: " << rows[k];
    if (f[4] == "1") {
      EXPECT_LE(std::stod(f[5]), budget + 0.5 * time_scale()) << rows[k];
      EXPECT_GT(std::stod(f[6]), 0) << rows[k];
      EXPECT_GE(std::stoi(f[7]), 1) << rows[k];
      EXPECT_LE(std::stod(f[14]), std::stod(f[17]) + 1e-3) << rows[k];  // duration <= raw
      EXPECT_LE(std::stoi(f[15]), std::stoi(f[18])) << rows[k];         // stops <= raw
      EXPECT_LE(std::stod(f[16]), std::stod(f[6]) + 1e-6) << rows[k];   // arc length <= raw
    } else {
      ASSERT_EQ(f[4], "0") << rows[k];
      EXPECT_TRUE(f[5].empty() && f[6].empty()) << rows[k];
      EXPECT_FALSE(f[13].empty()) << "a failure without a reason: " << rows[k];
    }
  }
}

TEST(BenchCli, TinyStudyWritesEveryFileWithConsistentRows) {
  const std::string dir = fresh_dir("study");
  const CommandResult r =
      bench("--problems 2 " + budget(1) + " --jobs 2 --seed 3 --no-direct --out " + quote(dir));
  ASSERT_EQ(r.exit_code, 0) << describe(r);

  const std::vector<std::string> problems = lines_of(read_file(dir + "/problems.jsonl"));
  ASSERT_EQ(problems.size(), 2u);
  for (const std::string& line : problems) {
    const nlohmann::json q = nlohmann::json::parse(line);
    EXPECT_EQ(q["start"].size(), 7u);
    EXPECT_EQ(q["goal"]["q"].size(), 7u);
    EXPECT_DOUBLE_EQ(q["goal"]["tolerance"].get<double>(), 0.45);  // the bundle's theta
  }

  const std::vector<std::string> rows = lines_of(read_file(dir + "/runs.csv"));
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows[0], kHeader);
  const std::vector<std::string> ours = {"lazyboe",  "lazyboe-transfer", "boe",    "rrt",
                                         "sst-0.5x", "sst-1x",           "sst-2x", "lazysp"};
  const std::vector<std::string> ompl = {"ompl-rrt", "ompl-sst", "ompl-kpiece"};
  const size_t planners = ours.size() + (ompl_available() ? ompl.size() : 0);
  ASSERT_EQ(rows.size(), 1 + 2 * planners) << read_file(dir + "/runs.csv");
  expect_consistent_rows(rows, 1.0 * time_scale());
  size_t lazy_edges = 0;
  for (size_t k = 1; k < rows.size(); ++k) {
    const std::vector<std::string> f = fields_of(rows[k]);
    if (f[0] == "lazyboe") lazy_edges += std::stoull(f[10]);
    EXPECT_NE(f[23], "direct") << "--no-direct, and yet: " << rows[k];
    const bool lazy_planner = f[0] == "lazyboe" || f[0] == "lazyboe-transfer" || f[0] == "lazysp";
    if (!lazy_planner) {  // lazysp's: the predicted states it kept
      EXPECT_EQ(f[10], "0") << "only LazyBoE and lazysp take lazy edges: " << rows[k];
    }
  }
  EXPECT_GT(lazy_edges, 0u);

  const std::string summary = read_file(dir + "/summary.md");
  for (const std::string& name : ours) EXPECT_TRUE(contains(summary, "| " + name + " |")) << name;
  for (const std::string& name : ompl) {
    EXPECT_TRUE(contains(summary, "| " + name + " |")) << name;
    if (!ompl_available()) {
      EXPECT_TRUE(contains(summary, "- " + name + ": built without OMPL")) << summary;
      EXPECT_TRUE(contains(r.err, "skipping " + name)) << r.err;
    }
  }
  EXPECT_TRUE(contains(summary, "Mann-Whitney U")) << summary;
  EXPECT_TRUE(contains(summary, "## Targets")) << summary;
  EXPECT_TRUE(contains(summary, "## Execution")) << summary;
  EXPECT_TRUE(contains(summary, "- A single straight command (start to goal")) << summary;
  EXPECT_TRUE(contains(summary, " of 2 problems: those need no planning")) << summary;
  EXPECT_TRUE(fs::exists(dir + "/study.json"));
  EXPECT_FALSE(fs::exists(dir + "/runs.partial.csv"));
  for (const char* figure :
       {"time_to_first_solution.png", "final_cost.png", "n_solutions.png", "success_rate.png"}) {
    if (matplotlib_installed()) {
      EXPECT_GT(fs::file_size(dir + "/" + figure), 1000u) << figure;
    } else {
      EXPECT_TRUE(contains(r.err, "figures skipped")) << r.err;
    }
  }

  // The problems file repeats the study's problems exactly; boe now tries the straight command
  // first (no --no-direct), and answers with it exactly the problems it solves.
  const std::string again = fresh_dir("study-again");
  const CommandResult r2 = bench("--problems-file " + quote(dir + "/problems.jsonl") +
                                 " --planners rrt,boe --repeats 2 " + budget(0.3) +
                                 " --no-figures --quiet --seed 3 "
                                 "--out " +
                                 quote(again));
  ASSERT_EQ(r2.exit_code, 0) << describe(r2);
  EXPECT_EQ(read_file(again + "/problems.jsonl"), read_file(dir + "/problems.jsonl"));
  // 2 planners x 2 problems x 2 repeats; a (problem, repeat) has one seed for every planner,
  // repeats have their own, and the seeds are the first study's for the same study seed.
  const std::vector<std::string> repeated = lines_of(read_file(again + "/runs.csv"));
  ASSERT_EQ(repeated.size(), 9u);
  std::map<std::pair<std::string, std::string>, std::set<std::string>> seeds;
  std::set<std::string> all_seeds;
  for (size_t k = 1; k < repeated.size(); ++k) {
    const std::vector<std::string> f = fields_of(repeated[k]);
    seeds[std::make_pair(f[1], f[2])].insert(f[3]);
    all_seeds.insert(f[3]);
  }
  EXPECT_EQ(seeds.size(), 4u);
  for (const auto& [key, s] : seeds) EXPECT_EQ(s.size(), 1u) << key.first << " " << key.second;
  int direct_rows = 0;
  for (size_t k = 1; k < repeated.size(); ++k) {
    const std::vector<std::string> f = fields_of(repeated[k]);
    if (f[23] != "direct") continue;
    EXPECT_EQ(f[0], "boe") << "only the bundle planners try the straight command: " << repeated[k];
    EXPECT_EQ(f[9], "1") << "one simulation: " << repeated[k];
    ++direct_rows;
  }
  const std::string summary2 = read_file(again + "/summary.md");
  const size_t at = summary2.find(") solves ");
  ASSERT_NE(at, std::string::npos) << summary2;
  EXPECT_EQ(direct_rows, 2 * std::stoi(summary2.substr(at + 9))) << summary2;  // 2 repeats
  EXPECT_EQ(all_seeds.size(), 4u);
  for (size_t k = 1; k < rows.size(); ++k) {
    const std::vector<std::string> f = fields_of(rows[k]);
    const std::set<std::string>& same = seeds[std::make_pair(f[1], f[2])];
    EXPECT_EQ(same.count(f[3]), 1u) << rows[k];
  }

  // An earlier study is not overwritten without --force.
  const auto before = snapshot(dir);
  expect_one_line_error(bench("--problems 2 " + budget(1) + " --out " + quote(dir)),
                        {dir, "--resume", "--force"});
  EXPECT_EQ(snapshot(dir), before);
}

TEST(BenchCli, ResumeRunsOnlyWhatIsMissingAndIgnoresATornLine) {
  const std::string dir = fresh_dir("resume");
  const std::string args =
      "--problems 2 --planners rrt,boe " + budget(0.5) + " --no-figures --out " + quote(dir);
  const CommandResult first = bench(args + " --quiet");
  ASSERT_EQ(first.exit_code, 0) << describe(first);
  const std::vector<std::string> rows = lines_of(read_file(dir + "/runs.csv"));
  ASSERT_EQ(rows.size(), 5u);

  // As if interrupted after two runs, in the middle of writing the third.
  fs::remove(dir + "/runs.csv");
  write_bytes(dir + "/runs.partial.csv", rows[0] + "\n" + rows[1] + "\n" + rows[3] + "\n" +
                                             rows[2].substr(0, rows[2].size() / 2));
  const CommandResult resumed = bench(args + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_TRUE(contains(resumed.err, "2 runs to do (2 done)")) << resumed.err;
  const std::vector<std::string> after = lines_of(read_file(dir + "/runs.csv"));
  ASSERT_EQ(after.size(), 5u);
  EXPECT_EQ(after[1], rows[1]);  // kept as saved, not run again
  EXPECT_EQ(after[3], rows[3]);
  EXPECT_EQ(fields_of(after[2])[0], fields_of(rows[2])[0]);
  expect_consistent_rows(after, 0.5 * time_scale());

  // Resuming with other parameters is refused, and changes nothing.
  const auto before = snapshot(dir);
  expect_one_line_error(
      bench("--problems 2 --planners rrt,boe " + budget(2) + " --out " + quote(dir) + " --resume"),
      {"study.json", "other parameters"});
  EXPECT_EQ(snapshot(dir), before);
}

TEST(BenchCli, InterruptKeepsFinishedRunsForResume) {
  const std::string dir = fresh_dir("interrupt");
  const std::string command = quote(tool_path("lazyboe-bench")) + " --bundle " + quote(bundle()) +
                              " --problems 3 --planners boe,rrt " + budget(2) +
                              " --no-figures --quiet "
                              "--out " +
                              quote(dir);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until the first run has finished (its row is in the partial file), then interrupt.
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(60 * time_scale());
  while (std::chrono::steady_clock::now() < deadline &&
         lines_of(fs::exists(dir + "/runs.partial.csv") ? read_file(dir + "/runs.partial.csv") : "")
                 .size() < 2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_FALSE(fs::exists(dir + "/runs.csv"));
  const size_t saved = lines_of(read_file(dir + "/runs.partial.csv")).size() - 1;
  EXPECT_GE(saved, 1u);
  EXPECT_LT(saved, 6u);

  const CommandResult resumed = run(command + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << describe(resumed);
  EXPECT_EQ(lines_of(read_file(dir + "/runs.csv")).size(), 7u);
  EXPECT_FALSE(fs::exists(dir + "/runs.partial.csv"));
}

// A study of pose goals with a task: problems.jsonl holds the pose goals, summary.md the task,
// and the task reaches every run (a speed limit no motion meets fails them all; the same study
// without it succeeds).
TEST(BenchCli, PoseGoalsAndATaskReachEveryRun) {
  const std::string dir = fresh_dir("task");
  const std::string study = "--problems 2 " + budget(5) +
                            " --planners lazysp --goals pose --no-figures --quiet --payload "
                            "'{\"mass\": 2.0, \"com\": [0, 0, 0.05]}' ";
  const CommandResult r = bench(study + "--out " + quote(dir + "/carried"));
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  for (const std::string& line : lines_of(read_file(dir + "/carried/problems.jsonl"))) {
    const nlohmann::json q = nlohmann::json::parse(line);
    ASSERT_TRUE(q["goal"].contains("pose")) << line;
    EXPECT_EQ(q["goal"]["position_tolerance"].get<double>(), 0.01);
  }
  EXPECT_NE(read_file(dir + "/carried/summary.md").find("Task of every run: payload"),
            std::string::npos);
  const auto successes = [&](const std::string& out) {
    int n = 0;
    for (const std::string& row : lines_of(read_file(out + "/runs.csv")))
      n += fields_of(row).size() > 4 && fields_of(row)[4] == "1";
    return n;
  };
  EXPECT_EQ(successes(dir + "/carried"), 2) << read_file(dir + "/carried/runs.csv");
  const CommandResult slow = bench(study + "--end-effector-limits '{\"max_linear_speed\": 1e-4}' " +
                                   "--out " + quote(dir + "/slow"));
  ASSERT_EQ(slow.exit_code, 0) << describe(slow);
  EXPECT_EQ(successes(dir + "/slow"), 0);
}

TEST(BenchCli, BadInputIsOneLineError) {
  const std::string dir = fresh_dir("bad");
  expect_one_line_error(bench("--planners lazyboe,foo --out " + quote(dir)), {"--planners", "foo"});
  expect_one_line_error(bench("--planners rrt,rrt --out " + quote(dir)), {"--planners", "twice"});
  expect_one_line_error(bench("--budget 0 --out " + quote(dir)), {"--budget"});
  expect_one_line_error(bench("--out " + quote(dir) + " --resume"), {"study.json", "no study"});
  expect_one_line_error(bench("--payload '{\"mass\": -1}' --out " + quote(dir)),
                        {"--payload", "mass"});
  expect_one_line_error(bench("--end-effector-limits '{\"max_tilt\": 0.2}' --out " + quote(dir)),
                        {"--end-effector-limits", "axis"});
  expect_one_line_error(bench("--goals poses --out " + quote(dir)), {"--goals"});
  expect_one_line_error(bench("--goals pose --problems-file " + quote(dir + "/bad.jsonl") +
                              " --out " + quote(dir)),
                        {"--problems-file excludes --goals"});
  write_bytes(dir + "/bad.jsonl", "{\"id\": \"a\", \"start\": [0, 0]}\n");
  expect_one_line_error(bench("--problems-file " + quote(dir + "/bad.jsonl") +
                              " --planners rrt --quiet --out " + quote(dir + "/out")),
                        {"bad.jsonl", "line 1"});
  expect_one_line_error(run(quote(tool_path("lazyboe-bench")) + " --bundle " +
                            quote(dir + "/missing.h5") + " --out " + quote(dir + "/out")),
                        {"missing.h5"});
}

// The partial file's reader skips a row an interruption cut short, and the writer drops it
// before appending, so a study interrupted twice still resumes. Fields are parsed strictly.
TEST(BenchRuns, PartialFileSurvivesATornRowAndRejectsBadFields) {
  const std::string dir = fresh_dir("partial");
  const std::string path = dir + "/runs.partial.csv";
  RunRecord a;
  a.planner = "rrt";
  a.problem = 0;
  a.seed = 42;
  a.success = true;
  a.time_to_first_solution = 0.5;
  a.best_cost = 1.25;
  a.n_solutions = 1;
  a.counters.simulations = 7;
  a.budget = 1;
  a.duration = 0.75;
  a.stops = 1;
  a.raw_duration = 2.5;
  a.raw_stops = 3;
  a.found_by = "direct";
  RunRecord b = a;
  b.found_by.clear();
  b.problem = 1;
  b.success = false;
  b.time_to_first_solution = b.best_cost = std::numeric_limits<double>::quiet_NaN();
  b.n_solutions = 0;
  b.failure = "no solution, \"quoted\"";
  const std::vector<std::string> ids = {"p0", "p1"};
  {
    PartialRunsFile f(path);
    f.append(a, "p0");
  }
  const std::string whole = read_file(path);
  write_bytes(path, whole + runs_csv_row(b, "p1").substr(0, 20));  // torn
  ASSERT_EQ(read_runs_csv(path, ids).size(), 1u);
  {
    PartialRunsFile f(path);  // drops the torn row
    f.append(b, "p1");
  }
  const std::vector<RunRecord> runs = read_runs_csv(path, ids);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].seed, 42u);
  EXPECT_DOUBLE_EQ(runs[0].best_cost, 1.25);
  EXPECT_DOUBLE_EQ(runs[0].duration, 0.75);
  EXPECT_EQ(runs[0].stops, 1);
  EXPECT_DOUBLE_EQ(runs[0].raw_duration, 2.5);
  EXPECT_EQ(runs[0].raw_stops, 3);
  EXPECT_EQ(runs[0].junctions, -1);
  EXPECT_EQ(runs[0].found_by, "direct");
  EXPECT_FALSE(runs[1].success);
  EXPECT_EQ(runs[1].found_by, "");
  EXPECT_EQ(runs[1].failure, b.failure);
  EXPECT_TRUE(std::isnan(runs[1].time_to_first_solution));

  const std::string header = lines_of(whole)[0];
  for (const auto& [row, field] : std::vector<std::pair<std::string, std::string>>{
           {"rrt,p0,0,-5,1,0.5,1.25,1,0,7,0,0,1,,,,,,,,,,,", "seed"},
           {"rrt,p0,0,42,yes,0.5,1.25,1,0,7,0,0,1,,,,,,,,,,,", "success"},
           {"rrt,p0,0,42,1,0.5,1.25,1.7,0,7,0,0,1,,,,,,,,,,,", "n_solutions"},
           {"rrt,p0,0,42,1,0.5,1.25,1,0,,0,0,1,,,,,,,,,,,", "simulations"},
           {"rrt,p9,0,42,1,0.5,1.25,1,0,7,0,0,1,,,,,,,,,,,", "problem"},
           {"rrt,p0,0,42,1,0.5,1.25,1,0,7,0,0,1,,fast,,,,,,,,,", "duration"},
           {"rrt,p0,0,42,1,0.5,1.25,1,0,7,0,0,1,,1.0,-1,,,,,,,,", "stops"},
           // Found by fuzzing: counts past the int range wrapped (4294967297 read as 1).
           {"rrt,p0,4294967297,42,1,0.5,1.25,1,0,7,0,0,1,,,,,,,,,,,", "repeat"},
           {"rrt,p0,0,42,1,0.5,1.25,2147483648,0,7,0,0,1,,,,,,,,,,,", "n_solutions"},
           {"rrt,p0,0,42,1,0.5,1.25,1,0,7,0,0,1,,1.0,4294967296,,,,,,,,", "stops"}}) {
    write_bytes(path, header + "\n" + row + "\n");
    try {
      read_runs_csv(path, ids);
      ADD_FAILURE() << "accepted: " << row;
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "line 2") && contains(e.what(), field)) << e.what();
    }
  }
}

TEST(BenchCli, ResumeOfAFinishedStudyRunsNothingAgain) {
  const std::string dir = fresh_dir("finished");
  const std::string args =
      "--problems 2 --planners rrt " + budget(0.3) + " --no-figures --out " + quote(dir);
  ASSERT_EQ(bench(args + " --quiet").exit_code, 0);
  const std::string runs = read_file(dir + "/runs.csv");
  const CommandResult again = bench(args + " --resume");
  ASSERT_EQ(again.exit_code, 0) << describe(again);
  EXPECT_TRUE(contains(again.err, "0 runs to do (2 done)")) << again.err;
  EXPECT_EQ(read_file(dir + "/runs.csv"), runs);
  expect_one_line_error(
      bench("--problems 3 --planners rrt " + budget(0.3) + " --out " + quote(dir) + " --resume"),
      {"study.json", "other parameters"});

  // Problem ids must be unique in a problems file.
  const std::vector<std::string> lines = lines_of(read_file(dir + "/problems.jsonl"));
  write_bytes(dir + "/twice.jsonl", lines[0] + "\n" + lines[0] + "\n");
  expect_one_line_error(bench("--problems-file " + quote(dir + "/twice.jsonl") +
                              " --planners rrt --quiet --out " + quote(dir + "/twice")),
                        {"twice.jsonl", "line 2", "repeated"});
}

}  // namespace
}  // namespace lazyboe::test
