// lazyboe-perturb: the perturbation analysis of an edge bundle. For every edge, p perturbations
// of its start state are re-simulated with the edge's command; P_lazy_prop and P_collision (and
// the counts behind them, and the transfer statistics) are written into the same bundle file.
#include <cstdio>

#include "lazyboe/bundle/builder.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/bundle/inspect.h"
#include "lazyboe/bundle/perturbation.h"
#include "mpi_offline.h"
#include "mpi_perturb.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;

bool g_job_sent = false;  // MPI: rank 0 has sent the other ranks their job

// What the checkpoint journal beside the bundle gave.
void report_replay(const JournalReplay& replay, const std::string& path) {
  if (!replay.note.empty()) std::fprintf(stderr, "lazyboe-perturb: %s\n", replay.note.c_str());
  if (replay.applied)
    std::fprintf(stderr, "lazyboe-perturb: %s: %llu checkpoints from its journal applied%s\n",
                 path.c_str(), static_cast<unsigned long long>(replay.records),
                 replay.ignored_bytes ? "; a torn last checkpoint was dropped" : "");
}

// The command line, parsed.
struct PerturbOptions {
  std::string bundle_path, robot_path, env_path;
  PerturbSettings settings;
  PerturbControl control;
  bool replace = false, use_mpi = false, theta_given = false;
};

void add_options(CLI::App& app, PerturbOptions& o) {
  PerturbSettings& s = o.settings;
  app.add_option("--bundle", o.bundle_path, "Bundle file (HDF5), updated in place")->required();
  app.add_option("--theta", s.theta,
                 "Perturbation radius, rad (default: the bundle's design theta)")
      ->check(real_in({0, 1e3, true}, " rad"));
  app.add_option("--perturbations", s.perturbations, "Perturbations per edge (p)")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--seed", s.seed, "Random seed")->capture_default_str()->check(whole_number(true));
  app.add_option("--threads", o.control.threads, "Threads (0: all cores)")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option("--robot", o.robot_path,
                 "Robot config (default: the one the bundle was built with)");
  app.add_option("--env", o.env_path, "Environment (default: the one the bundle was built with)");
  app.add_flag("--replace", o.replace, "Discard an existing analysis with other settings");
  app.add_option("--checkpoint-seconds", o.control.checkpoint_seconds,
                 "Least time between checkpoints (0: after every round)")
      ->capture_default_str()
      ->check(number_at_least_zero());
  app.add_flag("--quiet", o.control.quiet, "No progress or summary output");
  app.add_flag("--mpi", o.use_mpi,
               "Require MPI (run under mpirun or srun; without this flag MPI is used whenever "
               "the tool is launched by one)");
}

int report_interrupted(const PerturbOptions& o) {
  const PerturbSettings& s = o.settings;
  std::fprintf(stderr,
               "lazyboe-perturb: interrupted; the completed edges are saved in %s. Continue with: "
               "lazyboe-perturb --bundle %s --theta %.17g --perturbations %llu --seed %llu\n",
               o.bundle_path.c_str(), o.bundle_path.c_str(), s.theta,
               static_cast<unsigned long long>(s.perturbations),
               static_cast<unsigned long long>(s.seed));
  return 130;
}

// The analysis on rank 0 (or the only process): resumes from the journal, runs, saves.
int perturb(PerturbOptions& o) {
  PerturbSettings& s = o.settings;
  PerturbControl& control = o.control;
  const std::string& bundle_path = o.bundle_path;
  Bundle bundle = read_bundle(bundle_path);
  const BundleHeader& h = bundle.header;
  require_complete(h, bundle_path);
  if (!o.theta_given) s.theta = h.design_theta;
  if (!(s.theta > 0)) fail("--theta", "must be > 0");
  if (s.perturbations >= (1ULL << 24)) fail("--perturbations", "must be below 16777216");

  const BundleScene scene = load_bundle_scene(h, o.robot_path, o.env_path);
  const CollisionModel collision = build_collision_model(scene.robot, scene.env);
  SimulationOptions options = settings_from_header(h).simulation;
  options.sample_every = 0;
  const Simulator sim(scene.robot, collision, options);

  if (prepare_perturbation(bundle, s, o.replace, bundle_path) && !control.quiet) {
    std::fprintf(stderr,
                 "lazyboe-perturb: %s: its analysis has no transfer statistics (written by an "
                 "older lazyboe), which lazyboe's lazy_model transfer needs; --replace redoes "
                 "it with them\n",
                 bundle_path.c_str());
  }
  PerturbCheckpoints checkpoints(bundle_path);
  const JournalReplay replay = checkpoints.resume(bundle, s);
  if (!control.quiet) report_replay(replay, bundle_path);
  if (bundle.perturbation.complete && !replay.applied) {
    if (!control.quiet) {
      std::fprintf(stderr, "lazyboe-perturb: %s already holds this analysis (theta %g, p = %llu)\n",
                   bundle_path.c_str(), s.theta, static_cast<unsigned long long>(s.perturbations));
      print_perturbation_summary(bundle, stdout);
    }
    checkpoints.finish(bundle);  // p may have been raised to an equal value: keep in sync
    return 0;
  }
  install_stop_handlers();
  control.stop_requested = stop_requested;
  control.save_progress = [&](const Bundle& b, const std::vector<size_t>& edges, bool last) {
    if (last) {
      checkpoints.finish(b);
    } else {
      checkpoints.save(b, edges);
    }
  };
  CheckpointStats stats;
  control.stats = &stats;
#ifdef LAZYBOE_HAVE_MPI
  const auto ranks = mpi::start_perturb_ranks(scene, sim, bundle, s, options, control);
  g_job_sent = ranks != nullptr;
#endif
  const PerturbOutcome outcome = run_perturbation(sim, bundle, s, control);
#ifdef LAZYBOE_HAVE_MPI
  if (ranks) mpi::stop_perturb_ranks();
#endif
  if (!control.quiet) {
    print_perturbation_summary(bundle, stdout);
    print_checkpoint_stats(stats, bundle.perturbation.wall_seconds, stderr);
  }
  return outcome == PerturbOutcome::Interrupted ? report_interrupted(o) : 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Perturbation analysis: P_lazy_prop and P_collision for every edge of a bundle."};
  PerturbOptions o;
  add_options(app, o);
  one_line_cli_errors(app, "lazyboe-perturb");
  CLI11_PARSE(app, argc, argv);
  o.theta_given = app.count("--theta") > 0;
  return mpi::run_tool_on_ranks(
      "lazyboe-perturb", o.use_mpi, argc, argv, [&] { return perturb(o); },
      [&] { mpi::serve_perturb(o.control.threads); }, g_job_sent);
}
