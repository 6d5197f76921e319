// Helpers of the lazyboe-query command-line tests (test_query_cli, test_query_io_cli): the
// small dense bundle built once per process with the real tools, queries, running the tool, and
// the batches several tests share.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "planning_fixture.h"
#include "test_util.h"

namespace lazyboe::test {

// Builds <temp>/bundle/unperturbed.h5 (lazyboe-build) and <temp>/bundle/bundle.h5 (a copy,
// then lazyboe-perturb with p = 4). Returns the perturbed bundle's path.
std::string make_bundles();

struct Fixture : PlanningFixture {
  Fixture() : Fixture(make_bundles()) {}
  explicit Fixture(const std::string& bundle_path)
      : PlanningFixture(std::make_shared<const Bundle>(read_bundle(bundle_path)),
                        BundleView::open(bundle_path)),
        path(bundle_path) {}
  std::string path;
  std::string unperturbed = (std::filesystem::path(path).parent_path() / "unperturbed.h5").string();
};

const Fixture& fixture();

nlohmann::json query(const std::string& id, const JointVectorRef& start, const JointVectorRef& goal,
                     const std::string& planner, double budget, bool stop_at_first,
                     uint64_t seed = 1);
std::string jsonl(const std::vector<nlohmann::json>& queries);
std::string query_command(const std::vector<std::string>& args);

struct ToolRun {
  CommandResult r;
  std::vector<nlohmann::json> results;
  std::string problems;  // lines of stdout that are not JSON
};

std::vector<nlohmann::json> parse_lines(const std::string& out, std::string& problems);
ToolRun query_tool(const std::vector<std::string>& args);
// Runs a batch (written to <temp>/<name>.jsonl) on the fixture's bundle.
ToolRun run_batch(const std::string& name, const std::vector<nlohmann::json>& queries,
                  std::vector<std::string> extra = {});
// A result without the fields that depend on the wall clock.
nlohmann::json timeless(nlohmann::json r);

// Shared runs (computed once per process, used by several tests): the same problem with every
// planner, trajectories inline; a deterministic batch (stop at the first solution) and its quick
// part (all but the a -> c queries).
const ToolRun& tool_easy_run();
std::vector<nlohmann::json> deterministic_queries();
std::vector<nlohmann::json> quick_queries();
const ToolRun& deterministic_run();
// Checks a run of the deterministic batch worked at all: exit 0, one result per query.
void expect_batch_ran(const ToolRun& t, size_t queries);
// A result that solved its query with an inline trajectory.
void expect_solved(const nlohmann::json& r, const std::string& what);

}  // namespace lazyboe::test
