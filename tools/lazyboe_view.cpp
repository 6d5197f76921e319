// lazyboe-view: one self-contained HTML page (no server, no network) showing the robot, the
// environment, planned trajectories from a results file and a sample of a bundle in 3-D.
#include <cstdio>
#include <optional>

#include "lazyboe/bundle/scene.h"
#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/view/view_data.h"
#include "lazyboe/view/view_page.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;

struct Options {
  std::string results_path, queries_path, bundle_path, robot_path, env_path, out_path;
  std::string three_dir = default_three_dir(), colour_by = "p_lazy_prop", title;
  size_t bundle_points = BundleSampleOptions{}.points;
  uint64_t seed = 1;
  double min_sample_interval = ResultsViewOptions{}.min_sample_interval;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--results", o.results_path, "Results of lazyboe-query (JSON Lines)");
  app.add_option("--queries", o.queries_path,
                 "The query batch of the results: start and goal of failed queries too");
  app.add_option("--bundle", o.bundle_path, "Edge bundle: a sample of its edge ends");
  app.add_option("--bundle-points", o.bundle_points, "Edge starts and ends to sample")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--seed", o.seed, "Seed of the bundle sample")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--colour-by", o.colour_by,
                 "Initial colouring of the bundle points: p_lazy_prop, p_collision or density")
      ->capture_default_str()
      ->check(CLI::IsMember({"p_lazy_prop", "p_collision", "density"}));
  app.add_option("--robot", o.robot_path, "Robot config (default: the bundle's, or the Panda)");
  app.add_option("--env", o.env_path, "Environment (default: the bundle's, or table.json)");
  app.add_option("--min-sample-interval", o.min_sample_interval,
                 "Trajectory samples kept at least this far apart, s")
      ->capture_default_str()
      ->check(real_in({0, 10, false}, " s"));
  app.add_option("--three-dir", o.three_dir, "three.js directory (Debian's libjs-three)")
      ->capture_default_str();
  app.add_option("--title", o.title, "Page title");
  app.add_option("--out", o.out_path, "HTML file to write")->required();
}

int run(const Options& o) {
  refuse_output_as_input({"--out", o.out_path}, {{"--results", o.results_path},
                                                 {"--queries", o.queries_path},
                                                 {"--bundle", o.bundle_path},
                                                 {"--robot", o.robot_path},
                                                 {"--env", o.env_path}});
  const ViewerScripts scripts = load_viewer_scripts(o.three_dir);
  std::optional<BundleView> bundle;
  if (!o.bundle_path.empty()) bundle = BundleView::open(o.bundle_path);
  const BundleScene scene =
      bundle ? load_bundle_scene(bundle->header(), o.robot_path, o.env_path)
             : BundleScene{
                   load_robot(o.robot_path.empty() ? default_robot_path() : o.robot_path),
                   load_environment(o.env_path.empty() ? default_environment_path() : o.env_path)};
  std::vector<std::string> warnings;
  nlohmann::json data = {{"title", o.title.empty() ? "LazyBoE viewer" : o.title},
                         {"robot", robot_view_json(scene.robot, warnings)},
                         {"environment", environment_view_json(scene.env)},
                         {"results", nullptr},
                         {"bundle", nullptr},
                         {"colour_by", o.colour_by}};
  if (!o.results_path.empty()) {
    ResultsViewOptions options;
    options.queries_path = o.queries_path;
    options.min_sample_interval = o.min_sample_interval;
    data["results"] = results_view_json(o.results_path, scene.robot, options);
  }
  if (bundle) data["bundle"] = bundle_sample_json(*bundle, scene.robot, {o.bundle_points, o.seed});

  for (const std::string& w : warnings)
    std::fprintf(stderr, "lazyboe-view: warning: %s\n", w.c_str());
  const std::string page = viewer_page(data, scripts);
  AtomicFile out(o.out_path);
  out.stream() << page;
  out.commit();
  const nlohmann::json& results = data["results"];
  std::printf(
      "%s: %.2f MB; robot %s (%zu visuals), %zu obstacles, %zu trajectories, %zu failed queries, "
      "%zu "
      "bundle points\n",
      o.out_path.c_str(), page.size() / 1e6, scene.robot.name.c_str(),
      data["robot"]["visuals"].size(), scene.env.obstacles.size(),
      results.is_null() ? 0 : results["trajectories"].size(),
      results.is_null() ? 0 : results["failures"].size(),
      bundle ? data["bundle"]["density"].size() : 0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Write one self-contained HTML page showing robot, environment, trajectories and "
      "bundle in 3-D."};
  Options options;
  add_options(app, options);
  one_line_cli_errors(app, "lazyboe-view");
  CLI11_PARSE(app, argc, argv);
  return lazyboe::run_tool("lazyboe-view", [&] { return run(options); });
}
