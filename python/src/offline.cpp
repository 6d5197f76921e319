// lazyboe.build_bundle, lazyboe.perturb_bundle: the offline stages with lazyboe-build's and
// lazyboe-perturb's settings and defaults, a progress callback, and Ctrl-C (or an exception in
// the callback) stopping them cleanly at the next round, with a checkpoint written: the file is
// resumable as after the tools.
#include <pybind11/stl.h>

#include <exception>
#include <filesystem>
#include <type_traits>

#include "convert.h"
#include "lazyboe/bundle/builder.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/bundle/perturbation.h"
#include "lazyboe/bundle/scene.h"
#include "lazyboe/bundle/settings.h"
#include "lazyboe/common/version.h"
#include "lazyboe/planning/edge_index_file.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe::python {
namespace {

// The Python side of a long job: the progress callback, and the first Python exception (a
// KeyboardInterrupt from Ctrl-C, or one raised by the callback), which stops the job.
struct PythonControl {
  py::object progress;
  std::exception_ptr error;  // released with the GIL held (it is rethrown under it)

  bool stop_requested() {
    py::gil_scoped_acquire gil;
    if (!error && PyErr_CheckSignals() != 0)
      error = std::make_exception_ptr(py::error_already_set());
    return static_cast<bool>(error);
  }
  void report(uint64_t done, uint64_t total) {
    if (progress.is_none()) return;
    py::gil_scoped_acquire gil;
    if (error) return;
    try {
      progress(done, total);
    } catch (py::error_already_set&) {
      error = std::current_exception();
    }
  }
};

std::string path_text(const py::object& p) { return py::str(p).cast<std::string>(); }

// A keyword's value, when given; InputError naming it for a value of the wrong kind.
template <typename T>
void take(const py::object& value, T& into, const std::string& name) {
  if (value.is_none()) return;
  try {
    into = value.cast<T>();
  } catch (const py::cast_error&) {
    throw InputError(name + ": expected " +
                     (std::is_floating_point_v<T> ? "a number" : "a whole number >= 0"));
  }
}

// The build settings from the keywords: lazyboe-build's checks, under the keywords' names.
struct BuildArgs {
  py::object edges, seed, region, theta, min_duration, max_duration, knot_interval, velocity_scale,
      limit_scale, integrator, substeps, sample_interval;
};

void check_settings(const BuildSettings& s) {
  if (s.edges == 0) throw InputError("edges: must be > 0");
  if (!(s.command.min_duration > 0)) throw InputError("min_duration: must be > 0");
  if (!(s.command.max_duration >= s.command.min_duration))
    throw InputError("max_duration: must be >= min_duration");
  if (!(s.command.knot_interval > 0)) throw InputError("knot_interval: must be > 0");
  if (!(s.command.velocity_scale > 0 && s.command.velocity_scale <= 1))
    throw InputError("velocity_scale: must be in (0, 1]");
  if (!(s.command.limit_scale > 0 && s.command.limit_scale <= 1))
    throw InputError("limit_scale: must be in (0, 1]");
  if (s.simulation.substeps < 1) throw InputError("substeps: must be >= 1");
  if (!(s.design_theta > 0)) throw InputError("theta: must be > 0");
}

void apply_region(const py::object& region, const RobotModel& robot, BuildSettings& s) {
  if (region.is_none() ||
      (py::isinstance<py::str>(region) && region.cast<std::string>() == "default")) {
    s.region_lower = robot.region.lower;
    s.region_upper = robot.region.upper;
  } else if (py::isinstance<py::str>(region) && region.cast<std::string>() == "limits") {
    s.region_lower = robot.q_min;
    s.region_upper = robot.q_max;
  } else {
    if (py::isinstance<py::str>(region) || !py::isinstance<py::sequence>(region) ||
        py::len(region) != 2)
      throw InputError("region: expected 'default', 'limits' or (lower, upper)");
    const py::sequence pair = region.cast<py::sequence>();
    const JointRows lo = joint_rows(pair[0], robot.dof, "region lower");
    const JointRows hi = joint_rows(pair[1], robot.dof, "region upper");
    if (lo.batch || hi.batch) throw InputError("region: expected two rows of joint values");
    s.region_lower = Eigen::Map<const Eigen::VectorXd>(lo.data, robot.dof);
    s.region_upper = Eigen::Map<const Eigen::VectorXd>(hi.data, robot.dof);
  }
}

// Settings for a new build (defaults: lazyboe-build's), or those of the file being resumed
// with the keywords given now applied, as `lazyboe-build --resume` does.
BuildSettings build_settings(const BuildArgs& a, const BundleHeader* resumed) {
  BuildSettings s;
  s.simulation.integrator = Integrator::SemiImplicitEuler;  // lazyboe-build --integrator euler
  if (resumed) s = input_errors([&] { return settings_from_header(*resumed); });
  take(a.edges, s.edges, "edges");
  take(a.seed, s.seed, "seed");
  take(a.theta, s.design_theta, "theta");
  take(a.min_duration, s.command.min_duration, "min_duration");
  take(a.max_duration, s.command.max_duration, "max_duration");
  take(a.knot_interval, s.command.knot_interval, "knot_interval");
  take(a.velocity_scale, s.command.velocity_scale, "velocity_scale");
  take(a.limit_scale, s.command.limit_scale, "limit_scale");
  take(a.substeps, s.simulation.substeps, "substeps");
  if (!a.integrator.is_none())
    s.simulation.integrator = input_errors(
        [&] { return parse_integrator(a.integrator.cast<std::string>(), "integrator"); });
  check_settings(s);
  return s;
}

// As lazyboe-build: the finished bundle gets its k-d tree index; failing that is a warning.
void write_index_or_warn(const std::string& path) {
  try {
    write_bundle_index(BundleView::open(path));
  } catch (const std::exception& e) {  // Error, or the file system's own
    const std::string message =
        std::string(e.what()) + "; planning will build the k-d trees at load";
    if (PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1) < 0) throw py::error_already_set();
  }
}

// lazyboe-build --resume's preparation of the file; false when it is complete already.
bool prepare_resume(Bundle& existing, const BuildSettings& s) {
  if (existing.size() > s.edges)
    throw InputError("edges: the file already holds " + std::to_string(existing.size()) + " edges");
  if (existing.size() == s.edges && existing.header.complete) return false;
  existing.header.target_edges = s.edges;
  existing.header.complete = false;
  existing.header.tool_version = version();
  existing.perturbation = Perturbation{};  // new edges have none: lazyboe-perturb again
  return true;
}

template <typename Job>
void run_job(PythonControl& py_control, Job&& job) {
  {
    py::gil_scoped_release free;
    job();
  }
  if (py_control.error) std::rethrow_exception(py_control.error);
}

py::object open_bundle(const std::string& path) {
  return py::module_::import("lazyboe").attr("Bundle")(path);
}

py::object build(const py::object& out_arg, const py::object& robot_arg, const py::object& env_arg,
                 const BuildArgs& args, int threads, double checkpoint_seconds, bool resume,
                 bool force, const py::object& progress, bool quiet) {
  const std::string out = path_text(out_arg);
  if (resume && force) throw InputError("resume: cannot be combined with force");
  if (threads < 0) throw InputError("threads: must be >= 0");
  if (!(checkpoint_seconds >= 0)) throw InputError("checkpoint_seconds: must be >= 0");
  const bool exists = std::filesystem::exists(out);
  Bundle existing;
  BuildCheckpoints checkpoints(out);
  if (resume) {
    if (!exists) throw FileError(out + ": cannot resume: no such file");
    JournalReplay replay;
    existing = file_errors([&] { return checkpoints.load(&replay); });
    if (!quiet && !replay.note.empty()) std::fprintf(stderr, "lazyboe: %s\n", replay.note.c_str());
  } else if (exists && !force) {
    throw FileError(
        out + ": already exists (use force=True to overwrite, or resume=True to continue it)");
  }
  BuildSettings s = build_settings(args, resume ? &existing.header : nullptr);
  double sample_interval = resume ? existing.header.sample_interval : 0.05;
  take(args.sample_interval, sample_interval, "sample_interval");
  if (!(sample_interval >= 0)) throw InputError("sample_interval: must be >= 0");
  std::string robot_path = robot_arg.is_none()
                               ? (resume ? existing.header.robot_config : default_robot_path())
                               : path_text(robot_arg);
  std::string env_path = env_arg.is_none()
                             ? (resume ? existing.header.env_file : default_environment_path())
                             : path_text(env_arg);
  const RobotModel robot = file_errors([&] { return load_robot(robot_path); });
  const Environment env = file_errors([&] { return load_environment(env_path); });
  const CollisionModel collision = input_errors([&] { return build_collision_model(robot, env); });
  s.simulation.sample_every = input_errors([&] {
    return exact_sample_every_ticks(sample_interval, robot.control_rate, "sample_interval");
  });
  if (!resume || !args.region.is_none()) apply_region(args.region, robot, s);
  const Simulator sim(robot, collision, s.simulation);
  input_errors([&] { check_region(sim, s); });
  Bundle bundle = new_bundle(robot, env, s);
  if (resume) {
    input_errors([&] { check_resume_compatible(existing.header, bundle.header, out); });
    if (!prepare_resume(existing, s)) {  // complete already: only its index may be missing
      std::error_code error;
      if (!std::filesystem::exists(edge_index_path(out), error)) write_index_or_warn(out);
      return open_bundle(out);
    }
    bundle = std::move(existing);
  }
  PythonControl py_control{progress, nullptr};
  BuildControl control;
  control.threads = threads;
  control.checkpoint_seconds = checkpoint_seconds;
  control.quiet = quiet;
  control.stop_requested = [&] { return py_control.stop_requested(); };
  control.progress = [&](uint64_t done, uint64_t total) { py_control.report(done, total); };
  control.save_progress = [&](const Bundle& b, bool last) {
    last ? checkpoints.finish(b) : checkpoints.save(b);
  };
  BuildOutcome outcome = BuildOutcome::Complete;
  run_job(py_control, [&] { outcome = build_bundle(sim, s, bundle, control); });
  if (outcome == BuildOutcome::Hopeless) {
    throw std::runtime_error(out + ": stopped after the first " +
                             std::to_string(kHopelessAttempts) +
                             " attempts: " + rejection_diagnosis(bundle.header) +
                             " (the partial bundle is kept; resume=True continues it as it is)");
  }
  write_index_or_warn(out);
  return open_bundle(out);
}

py::object perturb(const py::object& path_arg, const py::object& theta_arg, uint64_t perturbations,
                   uint64_t seed, const py::object& robot_arg, const py::object& env_arg,
                   bool replace, int threads, double checkpoint_seconds, const py::object& progress,
                   bool quiet) {
  const std::string path = path_text(path_arg);
  if (threads < 0) throw InputError("threads: must be >= 0");
  if (!(checkpoint_seconds >= 0)) throw InputError("checkpoint_seconds: must be >= 0");
  if (perturbations == 0) throw InputError("perturbations: must be > 0");
  if (perturbations >= (1ULL << 24)) throw InputError("perturbations: must be below 16777216");
  Bundle bundle = file_errors([&] { return read_bundle(path); });
  file_errors([&] { require_complete(bundle.header, path); });
  PerturbSettings s;
  s.perturbations = perturbations;
  s.seed = seed;
  s.theta = bundle.header.design_theta;
  take(theta_arg, s.theta, "theta");
  if (!(s.theta > 0)) throw InputError("theta: must be > 0");
  const BundleScene scene = file_errors([&] {
    return load_bundle_scene(bundle.header, robot_arg.is_none() ? "" : path_text(robot_arg),
                             env_arg.is_none() ? "" : path_text(env_arg));
  });
  const CollisionModel collision = build_collision_model(scene.robot, scene.env);
  SimulationOptions options = settings_from_header(bundle.header).simulation;
  options.sample_every = 0;
  const Simulator sim(scene.robot, collision, options);
  input_errors([&] { prepare_perturbation(bundle, s, replace, path); });
  PerturbCheckpoints checkpoints(path);
  const JournalReplay replay = file_errors([&] { return checkpoints.resume(bundle, s); });
  if (!quiet && !replay.note.empty()) std::fprintf(stderr, "lazyboe: %s\n", replay.note.c_str());
  if (bundle.perturbation.complete && !replay.applied) {
    checkpoints.finish(bundle);  // p may have been raised to an equal value: keep in sync
    return open_bundle(path);
  }
  PythonControl py_control{progress, nullptr};
  PerturbControl control;
  control.threads = threads;
  control.checkpoint_seconds = checkpoint_seconds;
  control.quiet = quiet;
  control.stop_requested = [&] { return py_control.stop_requested(); };
  control.progress = [&](uint64_t done, uint64_t total) { py_control.report(done, total); };
  control.save_progress = [&](const Bundle& b, const std::vector<size_t>& edges, bool last) {
    last ? checkpoints.finish(b) : checkpoints.save(b, edges);
  };
  run_job(py_control, [&] { run_perturbation(sim, bundle, s, control); });
  return open_bundle(path);
}

}  // namespace

void bind_offline(py::module_& m) {
  m.def(
      "build_bundle",
      [](const py::object& out, const py::object& robot, const py::object& env,
         const py::object& edges, const py::object& seed, const py::object& region,
         const py::object& theta, const py::object& min_duration, const py::object& max_duration,
         const py::object& knot_interval, const py::object& velocity_scale,
         const py::object& limit_scale, const py::object& integrator, const py::object& substeps,
         const py::object& sample_interval, int threads, double checkpoint_seconds, bool resume,
         bool force, const py::object& progress, bool quiet) {
        const BuildArgs a{edges,        seed,         region,        theta,
                          min_duration, max_duration, knot_interval, velocity_scale,
                          limit_scale,  integrator,   substeps,      sample_interval};
        return build(out, robot, env, a, threads, checkpoint_seconds, resume, force, progress,
                     quiet);
      },
      py::arg("out"), py::kw_only(), py::arg("robot") = py::none(), py::arg("env") = py::none(),
      py::arg("edges") = py::none(), py::arg("seed") = py::none(), py::arg("region") = py::none(),
      py::arg("theta") = py::none(), py::arg("min_duration") = py::none(),
      py::arg("max_duration") = py::none(), py::arg("knot_interval") = py::none(),
      py::arg("velocity_scale") = py::none(), py::arg("limit_scale") = py::none(),
      py::arg("integrator") = py::none(), py::arg("substeps") = py::none(),
      py::arg("sample_interval") = py::none(), py::arg("threads") = 0,
      py::arg("checkpoint_seconds") = 10.0, py::arg("resume") = false, py::arg("force") = false,
      py::arg("progress") = py::none(), py::arg("quiet") = true,
      "Generates an edge bundle into `out`, as lazyboe-build does with the same options (None: "
      "the tool's default; with resume=True, the file's setting). region: 'default', 'limits' "
      "or (lower, upper). progress(done, total) is called after each round. Ctrl-C (or an "
      "exception in progress) stops the build at the next round with a checkpoint in `out`, "
      "and is raised; resume=True continues it. Returns the finished lazyboe.Bundle.");
  m.def("perturb_bundle", &perturb, py::arg("bundle"), py::kw_only(), py::arg("theta") = py::none(),
        py::arg("perturbations") = 16, py::arg("seed") = 1, py::arg("robot") = py::none(),
        py::arg("env") = py::none(), py::arg("replace") = false, py::arg("threads") = 0,
        py::arg("checkpoint_seconds") = 10.0, py::arg("progress") = py::none(),
        py::arg("quiet") = true,
        "The perturbation analysis of a bundle, written into the file, as lazyboe-perturb does "
        "(theta default: the bundle's design theta). progress(done, total) is called after each "
        "round; Ctrl-C stops it with the finished edges saved, and calling again with the same "
        "settings continues. Returns the lazyboe.Bundle.");
}

}  // namespace lazyboe::python
