// lazyboe-build: generate the edge bundle (valid random rollouts of the robot's dynamics) in
// parallel and store it in HDF5; or --inspect an existing bundle.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "lazyboe/bundle/builder.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/bundle/inspect.h"
#include "lazyboe/bundle/scene.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/common/progress.h"
#include "lazyboe/common/version.h"
#include "lazyboe/io/bundle_report.h"
#include "lazyboe/planning/edge_index_file.h"
#include "lazyboe/planning/workspace_index.h"
#include "lazyboe/robot/robot_config.h"
#include "mpi_build.h"
#include "mpi_offline.h"
#include "tool_main.h"

namespace {

using namespace lazyboe;

// --region: "default" (the robot config's sampling_region), "limits" (the joint limits), a JSON
// file {"lower": [...], "upper": [...]}, or inline "lo1:hi1,lo2:hi2,...".
void parse_region(const std::string& text, const RobotModel& robot, JointVector& lower,
                  JointVector& upper) {
  const int n = robot.dof;
  if (text == "default") {
    lower = robot.region.lower;
    upper = robot.region.upper;
    return;
  }
  if (text == "limits") {
    lower = robot.q_min;
    upper = robot.q_max;
    return;
  }
  lower.resize(n);
  upper.resize(n);
  if (std::filesystem::exists(text)) {
    const nlohmann::json doc = load_json_file(text);
    const JsonField root(doc, text, "");
    root.allow_only({"description", "lower", "upper"});
    const std::vector<double> lo = root.at("lower").numbers(), hi = root.at("upper").numbers();
    if (static_cast<int>(lo.size()) != n)
      root.at("lower").fail("expected " + std::to_string(n) + " values");
    if (static_cast<int>(hi.size()) != n)
      root.at("upper").fail("expected " + std::to_string(n) + " values");
    for (int i = 0; i < n; ++i) {
      lower[i] = lo[i];
      upper[i] = hi[i];
    }
    return;
  }
  std::stringstream ss(text);
  std::string item;
  int i = 0;
  while (std::getline(ss, item, ',')) {
    double lo = 0, hi = 0;
    char colon = 0, extra = 0;
    std::istringstream is(item);
    if (!(is >> lo >> colon >> hi) || colon != ':' || (is >> extra) || !std::isfinite(lo) ||
        !std::isfinite(hi)) {
      fail("--region", "'" + text +
                           "' is not a file, 'default', 'limits', or lo:hi pairs (bad item '" +
                           item + "')");
    }
    if (i >= n) fail("--region", "more than " + std::to_string(n) + " lo:hi pairs");
    lower[i] = lo;
    upper[i] = hi;
    ++i;
  }
  if (i != n)
    fail("--region", "expected " + std::to_string(n) + " lo:hi pairs, got " + std::to_string(i));
}

void print_summary(const Bundle& b) {
  std::fprintf(stderr, "lazyboe-build: %zu edges (%s)\n", b.size(),
               b.header.complete ? "complete" : "incomplete");
  print_build_summary(b.header, stderr);
}

// The command line. Settings go straight into `settings`, except those that need the robot.
struct BuildOptions {
  std::string robot_path = default_robot_path(), env_path = default_environment_path();
  std::string out_path, inspect_path, verify_path, index_path, region = "default",
                                                               integrator = "euler";
  BuildSettings settings;
  BuildControl control;
  double sample_interval = 0.05;
  double workspace_cell = WorkspaceIndexOptions().cell;
  bool resume = false, force = false, mpi = false, keep_going = false;
};

bool g_job_sent = false;  // MPI: rank 0 has sent the other ranks their job

void add_options(CLI::App& app, BuildOptions& o) {
  BuildSettings& s = o.settings;
  app.add_option("--robot", o.robot_path, "Robot config (JSON)")->capture_default_str();
  app.add_option("--env", o.env_path, "Environment (JSON)")->capture_default_str();
  app.add_option("--out", o.out_path, "Bundle file to write (HDF5)");
  app.add_option("--edges", s.edges, "Valid edges to generate")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--seed", s.seed, "Random seed")->capture_default_str()->check(whole_number(true));
  app.add_option("--threads", o.control.threads, "Threads (0: all cores)")
      ->capture_default_str()
      ->check(whole_number(true));
  app.add_option(
         "--region", o.region,
         "Start-state box: default (robot config), limits, a JSON file, or lo:hi,... per joint")
      ->capture_default_str();
  const RealRange seconds{0, 1e3, true}, fraction{0, 1, true};
  app.add_option("--min-duration", s.command.min_duration, "Shortest velocity command, s")
      ->capture_default_str()
      ->check(real_in(seconds, " s"));
  app.add_option("--max-duration", s.command.max_duration, "Longest velocity command, s")
      ->capture_default_str()
      ->check(real_in(seconds, " s"));
  app.add_option("--knot-interval", s.command.knot_interval, "Nominal spacing of velocity knots, s")
      ->capture_default_str()
      ->check(real_in(seconds, " s"));
  app.add_option("--velocity-scale", s.command.velocity_scale,
                 "Knot speeds up to this fraction of the velocity limits")
      ->capture_default_str()
      ->check(real_in(fraction));
  app.add_option("--limit-scale", s.command.limit_scale,
                 "Commanded acceleration and jerk up to this fraction of the limits")
      ->capture_default_str()
      ->check(real_in(fraction));
  app.add_option("--integrator", o.integrator, "euler (semi-implicit) or rk4")
      ->capture_default_str();
  app.add_option("--substeps", s.simulation.substeps, "Integration steps per control period")
      ->capture_default_str()
      ->check(whole_number(false));
  app.add_option("--sample-interval", o.sample_interval, "Stored trajectory spacing, s (0: none)")
      ->capture_default_str()
      ->check(real_in({0, 1e3}, " s"));
  app.add_option("--theta", s.design_theta, "Neighbourhood radius the bundle is designed for (rad)")
      ->capture_default_str()
      ->check(real_in({0, 1e3, true}, " rad"));
  app.add_option("--checkpoint-seconds", o.control.checkpoint_seconds,
                 "Least time between checkpoints (0: after every round)")
      ->capture_default_str()
      ->check(number_at_least_zero());
  app.add_flag("--resume", o.resume, "Continue an interrupted build in --out (to --edges)");
  app.add_flag("--force", o.force, "Overwrite an existing --out");
  app.add_flag("--quiet", o.control.quiet, "No progress output");
  app.add_flag("--keep-going", o.keep_going,
               "Build even when almost every attempt is rejected (by default a build stops when "
               "fewer than 2% of its first 2000 attempts are valid, saying why)");
  app.add_flag("--mpi", o.mpi,
               "Require MPI (run under mpirun or srun; without this flag MPI is used whenever "
               "the tool is launched by one)");
  app.add_option("--inspect", o.inspect_path,
                 "Print the header and statistics of a bundle, then exit");
  app.add_option("--verify", o.verify_path,
                 "Check every dataset's checksum and the bundle's validity, then exit");
  app.add_option("--index", o.index_path,
                 "Write the k-d tree index and the workspace index beside a finished bundle "
                 "(FILE.kd-index, FILE.ws-index; every build writes them), then exit");
  app.add_option("--workspace-cell", o.workspace_cell,
                 "Cell side of the workspace index, m (docs/bundle.md)")
      ->check(CLI::Range(0.005, 1.0));
}

// Checks the options that need no file, in the order of their messages' precedence.
void check_options(const BuildOptions& o) {
  const BuildSettings& s = o.settings;
  if (o.out_path.empty()) fail("--out", "required (the bundle file to write)");
  if (std::filesystem::is_directory(o.out_path))
    fail(o.out_path, "cannot write: is a directory, not a file");
  if (o.resume && o.force) fail("--resume", "cannot be combined with --force");
  if (s.edges == 0) fail("--edges", "must be > 0");
  if (!(s.command.min_duration > 0)) fail("--min-duration", "must be > 0");
  if (!(s.command.max_duration >= s.command.min_duration)) {
    fail("--max-duration", "must be >= --min-duration");
  }
  if (!(s.command.knot_interval > 0)) fail("--knot-interval", "must be > 0");
  if (!(s.command.velocity_scale > 0 && s.command.velocity_scale <= 1))
    fail("--velocity-scale", "must be in (0, 1]");
  if (!(s.command.limit_scale > 0 && s.command.limit_scale <= 1))
    fail("--limit-scale", "must be in (0, 1]");
  if (s.simulation.substeps < 1) fail("--substeps", "must be >= 1");
  if (!(s.design_theta > 0)) fail("--theta", "must be > 0");
  if (o.control.threads < 0) fail("--threads", "must be >= 0");
  if (!(o.sample_interval >= 0)) fail("--sample-interval", "must be >= 0");
}

// A resumed build takes every setting from the file; options given now must agree with it.
void take_settings_from(const CLI::App& app, const BundleHeader& h, BuildOptions& o) {
  BuildSettings& s = o.settings;
  if (!app.count("--robot")) o.robot_path = h.robot_config;
  if (!app.count("--env")) o.env_path = h.env_file;
  const BuildSettings from = settings_from_header(h);
  if (!app.count("--edges")) s.edges = from.edges;
  if (!app.count("--seed")) s.seed = from.seed;
  if (!app.count("--min-duration")) s.command.min_duration = from.command.min_duration;
  if (!app.count("--max-duration")) s.command.max_duration = from.command.max_duration;
  if (!app.count("--knot-interval")) s.command.knot_interval = from.command.knot_interval;
  if (!app.count("--velocity-scale")) s.command.velocity_scale = from.command.velocity_scale;
  if (!app.count("--limit-scale")) s.command.limit_scale = from.command.limit_scale;
  if (!app.count("--integrator")) s.simulation.integrator = from.simulation.integrator;
  if (!app.count("--substeps")) s.simulation.substeps = from.simulation.substeps;
  if (!app.count("--sample-interval")) o.sample_interval = h.sample_interval;
  if (!app.count("--theta")) s.design_theta = from.design_theta;
  if (!app.count("--region")) {
    s.region_lower = from.region_lower;
    s.region_upper = from.region_upper;
  }
}

// Prepares `existing` to grow to the new target after check_resume_compatible. False when it
// is complete at that target already (nothing to do).
bool prepare_resume(Bundle& existing, const BuildOptions& o) {
  const BuildSettings& s = o.settings;
  if (existing.size() > s.edges) {
    fail("--edges", "the file already holds " + std::to_string(existing.size()) + " edges");
  }
  if (existing.size() == s.edges && existing.header.complete) {
    if (!o.control.quiet) {
      std::fprintf(stderr, "lazyboe-build: %s is already complete with %zu edges\n",
                   o.out_path.c_str(), existing.size());
    }
    return false;
  }
  existing.header.target_edges = s.edges;
  existing.header.complete = false;
  existing.header.tool_version = version();
  if (existing.perturbation.present) {
    // New edges have no perturbation counts: the analysis has to be run again.
    existing.perturbation = Perturbation{};
    if (!o.control.quiet) {
      std::fprintf(stderr,
                   "lazyboe-build: the perturbation analysis in %s is dropped; run "
                   "lazyboe-perturb again\n",
                   o.out_path.c_str());
    }
  }
  if (!o.control.quiet) {
    std::fprintf(stderr, "lazyboe-build: resuming %s at %zu of %llu edges\n", o.out_path.c_str(),
                 existing.size(), static_cast<unsigned long long>(s.edges));
  }
  return true;
}

// What --resume found in the checkpoint journal beside the file.
void report_replay(const JournalReplay& r, const Bundle& b, const BuildOptions& o) {
  if (o.control.quiet) return;
  if (!r.note.empty()) std::fprintf(stderr, "lazyboe-build: %s\n", r.note.c_str());
  if (r.applied)
    std::fprintf(stderr,
                 "lazyboe-build: %s: %llu checkpoints from its journal applied (%zu edges)%s\n",
                 o.out_path.c_str(), static_cast<unsigned long long>(r.records), b.size(),
                 r.ignored_bytes ? "; a torn last checkpoint was dropped" : "");
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The workspace index beside a finished bundle (workspace_index.h), with progress.
void write_workspace(const BundleView& bundle, double cell, bool quiet) {
  const auto started = std::chrono::steady_clock::now();
  WorkspaceIndexOptions options;
  options.cell = cell;
  Progress progress("workspace index", bundle.size(), quiet);
  options.progress = [&](size_t done) { progress.update(done); };
  const RobotModel robot = load_bundle_robot(bundle.header(), "");
  const WorkspaceIndexSummary s = write_workspace_index(bundle, robot, options);
  progress.finish();
  if (quiet) return;
  std::fprintf(
      stderr, "lazyboe-build: workspace index written to %s (cell %.3f m, %.1f MB, %.2f s)\n",
      workspace_index_path(bundle.path()).c_str(), cell, s.bytes / 1e6, seconds_since(started));
}

// The indexes beside a finished bundle: the k-d trees, so that planning maps them instead of
// building them at load, and the workspace index, so that a new scene gets its collision prior.
void write_index(const std::string& path, double cell, bool quiet) {
  const auto started = std::chrono::steady_clock::now();
  const BundleView bundle = BundleView::open(path);
  write_bundle_index(bundle);
  if (!quiet)
    std::fprintf(stderr, "lazyboe-build: k-d tree index written to %s (%.2f s)\n",
                 edge_index_path(path).c_str(), seconds_since(started));
  write_workspace(bundle, cell, quiet);
}

// After a finished build the indexes are a convenience: failing to write them leaves a good
// bundle.
void try_write_index(const std::string& path, double cell, bool quiet) {
  try {
    write_index(path, cell, quiet);
  } catch (const std::exception& e) {  // Error, or the file system's own
    std::fprintf(stderr,
                 "lazyboe-build: warning: %s; planning will build the k-d trees at load and "
                 "plan in other scenes without a collision prior (write the indexes later with "
                 "lazyboe-build --index %s)\n",
                 e.what(), path.c_str());
  }
}

// Builds (or resumes) the bundle until complete or interrupted; returns the exit status.
int grow_bundle(const Simulator& sim, BuildOptions& o, Bundle& bundle,
                BuildCheckpoints& checkpoints) {
  install_stop_handlers();
  o.control.stop_requested = stop_requested;
  o.control.stop_when_hopeless = !o.keep_going;
  o.control.save_progress = [&](const Bundle& b, bool last) {
    if (last) {
      checkpoints.finish(b);
    } else {
      checkpoints.save(b);
    }
  };
  CheckpointStats stats;
  o.control.stats = &stats;
#ifdef LAZYBOE_HAVE_MPI
  std::unique_ptr<AttemptGenerator> own_share;
  if (mpi::world().active) {
    std::string job = mpi::build_job(o.robot_path, o.env_path, bundle.header, o.settings);
    mpi::broadcast(job);
    g_job_sent = true;
    own_share = std::make_unique<AttemptGenerator>(sim, o.settings, o.control.threads);
    mpi::distribute_build(o.control, *own_share);
  }
#endif
  const BuildOutcome outcome = build_bundle(sim, o.settings, bundle, o.control);
#ifdef LAZYBOE_HAVE_MPI
  if (mpi::world().active) mpi::stop_build_ranks();
#endif
  if (!o.control.quiet) {
    print_summary(bundle);
    print_checkpoint_stats(stats, bundle.header.wall_seconds, stderr);
  }
  if (outcome == BuildOutcome::Hopeless) {
    fail(o.out_path, "stopped after the first " + std::to_string(kHopelessAttempts) +
                         " attempts: " + rejection_diagnosis(bundle.header) +
                         " (the partial bundle is kept; --resume continues it as it is, "
                         "--keep-going builds anyway)");
  }
  if (outcome == BuildOutcome::Interrupted) {
    std::fprintf(stderr,
                 "lazyboe-build: interrupted; %s holds %zu edges. Continue with: lazyboe-build "
                 "--resume --out %s\n",
                 o.out_path.c_str(), bundle.size(), o.out_path.c_str());
    return 130;
  }
  try_write_index(o.out_path, o.workspace_cell, o.control.quiet);
  return 0;
}

// --verify: every checksum, then the validation every reader runs. Exit 0 only when both pass.
int verify(const std::string& path) {
  const std::vector<DatasetVerification> checks = verify_bundle_checksums(path);
  for (const DatasetVerification& v : checks) {
    if (v.status == DatasetVerification::Status::Mismatch)
      fail(path, v.dataset + ": checksum mismatch (stored " + v.stored + ", computed " +
                     v.computed + "): the file is damaged");
    if (v.status == DatasetVerification::Status::NoChecksum)
      fail(path, v.dataset +
                     ": no checksum (written before checksums existed; any rewrite, e.g. "
                     "lazyboe-perturb --bundle FILE, adds them)");
  }
  read_bundle(path);
  for (const DatasetVerification& v : checks)
    std::printf("ok %s %s\n", v.dataset.c_str(), v.stored.c_str());
  std::printf("%s: verified (%s; the bundle is valid)\n", path.c_str(),
              checksum_summary(checks).c_str());
  return 0;
}

int run(const CLI::App& app, BuildOptions& o) {
  if (!o.verify_path.empty()) return verify(o.verify_path);
  if (!o.index_path.empty()) {
    write_index(o.index_path, o.workspace_cell, false);
    return 0;
  }
  if (!o.inspect_path.empty()) {
    print_inspection(o.inspect_path, stdout);
    print_files_beside(o.inspect_path, stdout);
    return 0;
  }
  check_options(o);
  BuildSettings& s = o.settings;
  s.simulation.integrator = parse_integrator(o.integrator, "--integrator");

  Bundle existing;
  BuildCheckpoints checkpoints(o.out_path);
  const bool exists = std::filesystem::exists(o.out_path);
  if (o.resume) {
    if (!exists) fail(o.out_path, "cannot resume: no such file");
    JournalReplay replay;
    existing = checkpoints.load(&replay);
    report_replay(replay, existing, o);
    take_settings_from(app, existing.header, o);
  } else if (exists && !o.force) {
    fail(o.out_path, "already exists (use --force to overwrite, or --resume to continue it)");
  }

  const RobotModel robot = load_robot(o.robot_path);
  const Environment env = load_environment(o.env_path);
  refuse_output_as_input({"--out", o.out_path}, {{"--robot", o.robot_path},
                                                 {"URDF", robot.files.urdf},
                                                 {"--env", o.env_path},
                                                 {"--region", o.region}});
  const CollisionModel collision = build_collision_model(robot, env);
  s.simulation.sample_every =
      exact_sample_every_ticks(o.sample_interval, robot.control_rate, "--sample-interval");
  if (!o.resume || app.count("--region"))
    parse_region(o.region, robot, s.region_lower, s.region_upper);
  const Simulator sim(robot, collision, s.simulation);
  check_region(sim, s);

  Bundle bundle = new_bundle(robot, env, s);
  if (o.resume) {
    check_resume_compatible(existing.header, bundle.header, o.out_path);
    if (!prepare_resume(existing, o)) {  // complete already: only its index may be missing
      std::error_code error;
      if (!std::filesystem::exists(edge_index_path(o.out_path), error) ||
          !std::filesystem::exists(workspace_index_path(o.out_path), error))
        try_write_index(o.out_path, o.workspace_cell, o.control.quiet);
      return 0;
    }
    bundle = std::move(existing);
  }
  return grow_bundle(sim, o, bundle, checkpoints);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Generate an edge bundle: valid random rollouts of the robot's dynamics, in HDF5."};
  BuildOptions options;
  add_options(app, options);
  one_line_cli_errors(app, "lazyboe-build");
  CLI11_PARSE(app, argc, argv);
  return mpi::run_tool_on_ranks(
      "lazyboe-build", options.mpi, argc, argv, [&]() -> int { return run(app, options); },
      [&] { mpi::serve_build(options.control.threads); }, g_job_sent);
}
