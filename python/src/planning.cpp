// lazyboe.PlanningSession, lazyboe.planners(): queries in the query format's terms (read and
// validated by read_query, answered by answer_request, exactly as lazyboe-query does), with the
// GIL released while planning.
#include <omp.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <future>
#include <memory>

#include "convert.h"
#include "lazyboe/io/query_io.h"
#include "lazyboe/planning/execution.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/registry.h"

namespace lazyboe::python {
namespace {

struct PyTrajectory {
  py::array_t<double> t, q, dq, ddq, cmd;  // ddq, cmd: (0, dof) for a raw chain
  py::array_t<int64_t> edges;
  double cost = 0, duration = 0;
  int stops = 0;
};

// One answered query: what lazyboe-query's result line holds.
struct PyResult {
  Query query;
  PlanAnswer answer;
  WorldPtr world;     // the scene it was planned in
  std::string error;  // plan_many: why this query could not be planned (the others were)

  nlohmann::json json() const {
    if (!error.empty()) return error_json(query.id, 0, query.request.planner, error);
    return result_json(query, answer, *world, TrajectoryOutput::Inline, "");
  }
  const PlanResult& result() const { return answer.result; }
  const Trajectory& trajectory() const { return answer.trajectory; }
};

PyTrajectory trajectory_of(const Trajectory& tr, int dof) {
  PyTrajectory p;
  p.t = to_array(tr.t);
  p.q = rows_to_array(tr.q, dof);
  p.dq = rows_to_array(tr.dq, dof);
  p.ddq = rows_to_array(tr.ddq, dof);
  p.cmd = rows_to_array(tr.cmd, dof);
  p.stops = tr.stops;
  p.edges = py::array_t<int64_t>(static_cast<py::ssize_t>(tr.edges.size()));
  std::copy(tr.edges.begin(), tr.edges.end(), p.edges.mutable_data());
  p.cost = tr.cost;
  p.duration = tr.duration;
  return p;
}

struct Session {
  std::shared_ptr<const PlanningSession> session;
};

// A scene loaded once (PlanningSession.load_scene): its world, ready for any number of plans.
struct PyScene {
  WorldPtr world;
};

// What to return, as lazyboe-query's flags say it.
QueryDefaults query_defaults(double sample_interval, bool raw) {
  if (!(sample_interval > 0)) throw InputError("sample_interval: must be > 0");
  QueryDefaults d;
  d.output.sample_interval = sample_interval;
  d.output.raw = raw;
  return d;
}

// `where` starts the errors: "" (plan: the field alone) or "queries[2]".
// `world`: where the problem is checked when the query names no scene (default: the session's).
Query read(const Session& s, SimulatorWorkspace& ws, const nlohmann::json& doc,
           const std::string& where, const QueryDefaults& defaults,
           const WorldPtr& world = nullptr) {
  try {
    return read_query(doc, where, world ? world->sim : s.session->sim(), ws, defaults,
                      &s.session->scenes, world);
  } catch (const Error& e) {
    throw InputError(e.what());
  }
}

PyResult answer(const Session& s, SimulatorWorkspace& ws, RolloutPool& pool, const Query& q) {
  PyResult r{q, {}, q.world ? q.world : s.session->scenes.default_world(), ""};
  r.answer = answer_request(s.session->context(*r.world), q.request, ws, &pool);
  return r;
}

nlohmann::json query_doc(const py::object& start, const py::object& goal,
                         const std::string& planner, const py::object& budget,
                         const py::object& seed, const std::string& id, const py::object& scene,
                         const py::kwargs& params) {
  nlohmann::json doc = nlohmann::json::object();
  doc["id"] = id;
  doc["start"] = to_json(start, "start");
  doc["goal"] = to_json(goal, "goal");
  doc["planner"] = planner;
  if (!budget.is_none()) doc["budget"] = to_json(budget, "budget");
  if (!seed.is_none()) doc["seed"] = to_json(seed, "seed");
  if (py::isinstance<py::dict>(scene))
    doc["scene"] = to_json(scene, "scene");
  else if (!scene.is_none() && !py::isinstance<PyScene>(scene))
    doc["scene"] = py::str(scene).cast<std::string>();  // a path (str or os.PathLike)
  for (const auto& [k, v] : params) {
    const std::string name = k.cast<std::string>();
    doc[name] = to_json(v, name);
  }
  return doc;
}

// Runs `work` on a thread of its own while the calling thread, the interpreter's, looks for
// Ctrl-C every 20 ms; on one it sets `cancel` (the solve stops at its next check) and raises
// KeyboardInterrupt once the work has returned. Called with the GIL released.
template <typename Work>
auto interruptible(std::atomic<bool>& cancel, Work work) -> decltype(work()) {
  std::future<decltype(work())> done = std::async(std::launch::async, work);
  std::exception_ptr interrupt;
  while (done.wait_for(std::chrono::milliseconds(20)) != std::future_status::ready) {
    if (interrupt) continue;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      interrupt = std::make_exception_ptr(py::error_already_set());
      cancel = true;
    }
  }
  auto result = done.get();
  if (interrupt) std::rethrow_exception(interrupt);
  return result;
}

PyResult plan_one(const Session& s, const py::object& start, const py::object& goal,
                  const std::string& planner, const py::object& budget, const py::object& seed,
                  const std::string& id, const py::object& scene, double sample_interval,
                  int sim_threads, bool raw, const py::kwargs& params) {
  if (sim_threads < 1 || sim_threads > 1024) throw InputError("sim_threads: must be in [1, 1024]");
  const QueryDefaults defaults = query_defaults(sample_interval, raw);
  const nlohmann::json doc = query_doc(start, goal, planner, budget, seed, id, scene, params);
  // A loaded scene: the problem is checked in its world, and planned there.
  const WorldPtr loaded = py::isinstance<PyScene>(scene) ? scene.cast<PyScene>().world : nullptr;
  py::gil_scoped_release free;
  std::atomic<bool> cancel{false};
  SimulatorWorkspace ws(s.session->sim());
  Query q = read(s, ws, doc, "", defaults, loaded);
  if (loaded && !q.world) q.world = loaded;
  q.request.problem.termination.cancel = &cancel;
  return interruptible(cancel, [&] {
    RolloutPool pool(s.session->sim(), sim_threads);
    return answer(s, ws, pool, q);
  });
}

// Ctrl-C during a batch: the calling thread (OpenMP's thread 0) looks for a pending signal
// before each query it takes; once one is seen no query starts any more, and the
// KeyboardInterrupt is raised after the queries in flight.
struct BatchInterrupt {
  std::atomic<bool> seen{false};
  std::exception_ptr error;

  bool check() {
    if (seen || omp_get_thread_num() != 0) return seen;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      error = std::make_exception_ptr(py::error_already_set());
      seen = true;
    }
    return seen;
  }
};

// Every query parsed (checked) first, then planned on `jobs` threads; a query a planner could
// not plan (it threw) gets a result with its error, the others are planned. An interrupt
// cancels the queries in flight too.
std::vector<PyResult> plan_parsed(const Session& s, const std::vector<nlohmann::json>& docs,
                                  int jobs, const QueryDefaults& defaults,
                                  BatchInterrupt& interrupt) {
  std::vector<Query> parsed;
  {
    SimulatorWorkspace ws(s.session->sim());
    for (size_t k = 0; k < docs.size(); ++k) {
      parsed.push_back(read(s, ws, docs[k], "queries[" + std::to_string(k) + "]", defaults));
      parsed.back().request.problem.termination.cancel = &interrupt.seen;
    }
  }
  std::vector<PyResult> results(parsed.size());
#pragma omp parallel num_threads(jobs)
  {
    SimulatorWorkspace ws(s.session->sim());
    RolloutPool pool(s.session->sim(), 1);
#pragma omp for schedule(dynamic, 1)
    for (long k = 0; k < static_cast<long>(parsed.size()); ++k) {
      if (interrupt.check()) continue;
      try {
        results[k] = answer(s, ws, pool, parsed[k]);
      } catch (const std::exception& e) {
        results[k] = PyResult{parsed[k], {}, s.session->scenes.default_world(), e.what()};
      }
    }
  }
  return results;
}

std::vector<PyResult> plan_many(const Session& s, const py::iterable& queries, int jobs,
                                double sample_interval, bool raw) {
  if (jobs < 0 || jobs > 1024) throw InputError("jobs: must be in [0, 1024]");
  if (jobs == 0) jobs = omp_get_num_procs();
  const QueryDefaults defaults = query_defaults(sample_interval, raw);
  std::vector<nlohmann::json> docs;
  for (const py::handle& q : queries) {
    const std::string where = "queries[" + std::to_string(docs.size()) + "]";
    if (!py::isinstance<py::dict>(q)) throw InputError(where + ": expected a dict (a query)");
    nlohmann::json doc = to_json(q, where);
    if (!doc.contains("id")) doc["id"] = std::to_string(docs.size());
    docs.push_back(std::move(doc));
  }
  BatchInterrupt interrupt;
  std::vector<PyResult> results;
  {
    py::gil_scoped_release free;
    results = plan_parsed(s, docs, jobs, defaults, interrupt);
  }
  if (interrupt.error) std::rethrow_exception(interrupt.error);
  return results;
}

py::dict parameter_dict(const ParameterSpec& p) {
  static const char* types[] = {"real", "integer", "boolean", "choice"};
  py::dict d;
  d["type"] = types[static_cast<int>(p.type)];
  py::object def = py::none();
  if (p.has_fixed_default()) {
    if (p.type == ParameterType::Boolean)
      def = py::bool_(p.default_value != 0);
    else if (p.type == ParameterType::Integer)
      def = py::int_(static_cast<int64_t>(p.default_value));
    else if (p.type == ParameterType::Choice)
      def = py::str(p.choices.at(static_cast<size_t>(p.default_value)));
    else
      def = py::float_(p.default_value);
  }
  d["default"] = def;
  d["default_from"] = p.default_from.empty() ? py::object(py::none()) : py::str(p.default_from);
  d["range"] = p.range_text();
  d["choices"] = p.choices;
  d["description"] = p.description;
  return d;
}

py::list planners() {
  py::list out;
  for (const PlannerInfo& info : planner_registry()) {
    py::dict d, params, needs;
    d["name"] = info.name;
    d["description"] = info.description;
    needs["bundle"] = info.needs.bundle;
    needs["perturbation"] = info.needs.perturbation;
    needs["ompl"] = info.needs.ompl;
    d["needs"] = needs;
    d["available"] = info.available();
    for (const ParameterSpec& p : info.parameters) params[py::str(p.name)] = parameter_dict(p);
    d["parameters"] = params;
    out.append(d);
  }
  return out;
}

void bind_trajectory(py::module_& m) {
  py::class_<PyTrajectory>(m, "Trajectory",
                           "A realized trajectory: the path simulated again from the exact start "
                           "with every check.")
      .def_readonly("t", &PyTrajectory::t, "Sample times, s, (T,).")
      .def_readonly("q", &PyTrajectory::q, "Joint positions, (T, dof).")
      .def_readonly("dq", &PyTrajectory::dq, "Joint velocities, (T, dof).")
      .def_readonly("ddq", &PyTrajectory::ddq,
                    "Joint accelerations over the control tick from each sample, (T, dof); "
                    "(0, dof) for a raw chain (raw=True).")
      .def_readonly("cmd", &PyTrajectory::cmd,
                    "Commanded joint velocities, (T, dof); (0, dof) for a raw chain.")
      .def_readonly("stops", &PyTrajectory::stops,
                    "Stops at rest between the start and the end (a raw chain: steps - 1).")
      .def_readonly("edges", &PyTrajectory::edges,
                    "Bundle edge of each step (-1: not a bundle edge).")
      .def_readonly("cost", &PyTrajectory::cost, "Joint-space arc length, rad.")
      .def_readonly("duration", &PyTrajectory::duration, "s.")
      .def("__len__", [](const PyTrajectory& t) { return t.t.size(); });
}

// {'name', 'hash'}: a scene as results name it.
py::dict scene_dict(const Environment& env) {
  return py::dict(py::arg("name") = env.name, py::arg("hash") = env.identity);
}

// The PlanResult properties that say where and how it was answered (beside the result line's).
void bind_result_extras(py::class_<PyResult>& c) {
  c.def_property_readonly(
       "error",
       [](const PyResult& r) -> py::object {
         return r.error.empty() ? py::object(py::none()) : py::str(r.error);
       },
       "plan_many: why this query could not be planned (the planner failed: the others "
       "were planned); None otherwise.")
      .def_property_readonly(
          "scene", [](const PyResult& r) { return scene_dict(r.world->env); },
          "The scene it was planned in: {'name', 'hash'}.");
}

// The wall times beside time_to_first_solution.
void bind_result_timings(py::class_<PyResult>& c) {
  c.def_property_readonly(
       "planning_seconds", [](const PyResult& r) { return r.answer.planning_seconds; },
       "Wall time of planning, s (the whole budget unless stop_at_first).")
      .def_property_readonly(
          "time_to_executable",
          [](const PyResult& r) -> py::object {
            if (!r.result().success) return py::none();
            return py::float_(r.answer.seconds);
          },
          "Seconds from the start of planning to the returned trajectory (post-processing "
          "included); None without one.");
}

void bind_result(py::module_& m) {
  bind_trajectory(m);
  auto opt = [](bool present, double v) -> py::object {
    return present ? py::object(py::float_(v)) : py::object(py::none());
  };
  py::class_<PyResult> result(m, "PlanResult",
                              "The answer to one query, with the result line's names.");
  bind_result_extras(result);
  bind_result_timings(result);
  result
      .def_property_readonly(
          "id", [](const PyResult& r) { return r.query.id; }, "The query id.")
      .def_property_readonly(
          "planner", [](const PyResult& r) { return r.query.request.planner; },
          "The planner that answered.")
      .def_property_readonly(
          "success", [](const PyResult& r) { return r.result().success; },
          "A solution was found (and realized).")
      .def_property_readonly(
          "time_to_first_solution",
          [opt](const PyResult& r) {
            return opt(r.result().success, r.result().time_to_first_solution);
          },
          "Seconds to the first solution; None without one.")
      .def_property_readonly(
          "n_solutions", [](const PyResult& r) { return r.result().n_solutions; },
          "Solutions found within the budget.")
      .def_property_readonly(
          "best_cost",
          [opt](const PyResult& r) { return opt(r.result().success, r.trajectory().cost); },
          "Joint-space arc length of the realized best path, rad; None without one.")
      .def_property_readonly(
          "counters", [](const PyResult& r) { return from_json(r.json()["counters"]); },
          "{'nodes', 'simulations', 'lazy_edges', 'collision_checks'}.")
      .def_property_readonly(
          "failure",
          [](const PyResult& r) -> py::object {
            if (!r.error.empty()) return py::str("error: " + r.error);
            return r.result().success ? py::object(py::none()) : py::str(r.result().failure);
          },
          "Why there is no solution; None with one.")
      .def_property_readonly(
          "found_by",
          [](const PyResult& r) -> py::object {
            return r.result().found_by.empty() || !r.result().success
                       ? py::object(py::none())
                       : py::str(r.result().found_by);
          },
          "Which part of the planner found the best path (direct: the straight command the "
          "bundle planners try first; lazysp: waypoint, two_waypoints, bundle, growth, "
          "connection, approach or shortcut), or None.")
      .def_property_readonly(
          "duration",
          [opt](const PyResult& r) { return opt(r.result().success, r.trajectory().duration); },
          "Duration of the trajectory, s; None without one.")
      .def_property_readonly(
          "edges",
          [](const PyResult& r) -> py::object {
            if (!r.result().success) return py::none();
            return trajectory_of(r.trajectory(), 0).edges;
          },
          "Bundle edge of each step of the best path (-1: not a bundle edge); None without one.")
      .def_property_readonly(
          "trajectory",
          [](const PyResult& r) -> py::object {
            if (!r.result().success) return py::none();
            return py::cast(trajectory_of(r.trajectory(),
                                          static_cast<int>(r.query.request.problem.start.size())));
          },
          "The trajectory (t, q, dq, ddq, cmd, edges, cost, duration, stops): the executable one, "
          "or the raw chain with raw=True; None without a solution.")
      .def(
          "to_dict", [](const PyResult& r) { return from_json(r.json()); },
          "The result line of lazyboe-query --trajectories inline, as a dict.")
      .def("__repr__", [](const PyResult& r) {
        return "<lazyboe.PlanResult " + r.query.request.planner +
               (r.result().success ? ": solved, cost " + std::to_string(r.trajectory().cost)
                                   : ": " + r.result().failure) +
               ">";
      });
}

}  // namespace

py::object make_bundle_object(std::shared_ptr<const BundleView> view);

namespace {

PyScene load_scene(const Session& s, const py::object& env) {
  if (py::isinstance<py::dict>(env)) {
    const nlohmann::json doc = to_json(env, "env");
    py::gil_scoped_release free;
    try {
      return PyScene{s.session->scenes.inline_scene(JsonField(doc, "", "env"))};
    } catch (const Error& e) {
      throw InputError(e.what());
    }
  }
  const std::string path = py::str(env).cast<std::string>();
  py::gil_scoped_release free;
  return file_errors([&] { return PyScene{s.session->scenes.load(path)}; });
}

void bind_scene(py::module_& m) {
  py::class_<PyScene>(m, "Scene",
                      "A scene loaded once by PlanningSession.load_scene: its collision model "
                      "is built, and plan(scene=...) plans in it without reading it again.")
      .def_property_readonly(
          "name", [](const PyScene& p) { return p.world->env.name; }, "The environment's name.")
      .def_property_readonly(
          "hash", [](const PyScene& p) { return p.world->env.identity; },
          "Its content hash, as results carry it.")
      .def_property_readonly(
          "obstacles",
          [](const PyScene& p) {
            std::vector<std::string> names;
            for (const Obstacle& o : p.world->env.obstacles) names.push_back(o.name);
            return names;
          },
          "The obstacles' names.")
      .def_property_readonly(
          "marked_edges",
          [](const PyScene& p) -> py::object {
            if (!p.world->edge_marks) return py::none();
            return py::int_(p.world->edge_marks->marked);
          },
          "How many bundle edges the scene's new obstacles may block (the workspace index's "
          "marks, which steer lazysp and LazyBoE); None for the bundle's own scene or without "
          "an index.")
      .def("__repr__", [](const PyScene& p) {
        return "<lazyboe.Scene " + p.world->env.name + " " + p.world->env.identity + ">";
      });
}

// What a PlanningSession holds, read-only.
void bind_session_properties(py::class_<Session>& c) {
  c.def_property_readonly(
       "robot",
       [](const Session& s) {
         return PyRobot{std::shared_ptr<const RobotModel>(s.session, &s.session->robot)};
       },
       "The bundle's robot (a lazyboe.Robot).")
      .def_property_readonly(
          "bundle",
          [](const Session& s) {
            return make_bundle_object(
                std::shared_ptr<const BundleView>(s.session, &s.session->bundle));
          },
          "The bundle (a lazyboe.Bundle sharing the session's mapping).")
      .def_property_readonly(
          "scene", [](const Session& s) { return scene_dict(s.session->world().env); },
          "The default scene planned in: {'name', 'hash'} (the content hash results carry).")
      .def_property_readonly(
          "load_seconds", [](const Session& s) { return s.session->load_seconds; },
          "Wall time of opening the session, s.")
      .def_property_readonly(
          "index_source", [](const Session& s) { return s.session->indexes.source; },
          "Where the k-d trees came from: 'mapped from <bundle>.kd-index', 'read from ...' "
          "(memory_map=False), or 'built at load (why)'.")
      .def_property_readonly(
          "workspace_index_source", [](const Session& s) { return s.session->workspace.source; },
          "Where the workspace index came from ('mapped from <bundle>.ws-index', ...), or why "
          "there is none in use: without it, scenes other than the bundle's get no collision "
          "prior.")
      .def_property_readonly(
          "default_theta", [](const Session& s) { return s.session->default_theta(); },
          "theta of the bundle's perturbation analysis (or its design theta).");
}

}  // namespace

void bind_planning(py::module_& m) {
  bind_result(m);
  bind_scene(m);
  m.def("planners", &planners,
        "The planner registry: per planner its name, description, needs, availability in this "
        "build, and parameters (type, default, range, description).");
  py::class_<Session> session(m, "PlanningSession",
                              "A bundle opened once for planning (memory-mapped), with its robot, "
                              "neighbour indexes and the scenes it plans in. Thread-safe: plan() "
                              "releases the GIL, so Python threads plan in parallel.");
  session
      .def(py::init([](const py::object& path, bool memory_map, const py::object& robot,
                       const py::object& env) {
             const std::string p = py::str(path).cast<std::string>();
             const std::string r = robot.is_none() ? "" : py::str(robot).cast<std::string>();
             const std::string e = env.is_none() ? "" : py::str(env).cast<std::string>();
             Session s;
             {
               py::gil_scoped_release free;
               s.session = file_errors(
                   [&] { return std::make_shared<const PlanningSession>(p, memory_map, r, e); });
             }
             return s;
           }),
           py::arg("bundle_path"), py::arg("memory_map") = true, py::arg("robot") = py::none(),
           py::arg("env") = py::none(),
           "Opens a bundle for planning. robot: the bundle's robot config (default: the one "
           "named in the bundle; refused unless it matches). env: the environment planned in by "
           "default (default: the bundle's own; any scene for the bundle's robot). OSError for "
           "a missing or corrupt bundle or a mismatching robot.")
      .def("plan", &plan_one, py::arg("start"), py::arg("goal"), py::arg("planner") = "lazyboe",
           py::arg("budget") = py::none(), py::arg("seed") = py::none(), py::arg("id") = "",
           py::arg("scene") = py::none(), py::arg("sample_interval") = 0.01,
           py::arg("sim_threads") = 1, py::arg("raw") = false,
           "Plans one query, as a line of lazyboe-query would: start (dof values), goal "
           "({'q': [...], 'tolerance': 0.1}, {'position': [x, y, z], 'tolerance': 0.02, "
           "'link': name}, {'pose': {'position': [x, y, z], 'orientation': [w, x, y, z]}, "
           "'position_tolerance': 0.01, 'orientation_tolerance': 0.05}, or a list of goals, any "
           "of which will do), planner (lazyboe.planners()), budget (s, default 5), seed (default "
           "1), and the planner's parameters and the task by name as keywords (stop_at_first=True, "
           "theta=0.4, payload={'mass': 3.0, 'com': [0, 0, 0.05]}, end_effector_limits="
           "{'max_linear_acceleration': 3.0}, ...). scene: the environment to plan in: a Scene "
           "(load_scene), an "
           "environment file's path or an environment dict (default: the session's); scenes "
           "are kept by content, so naming one again reuses its collision model. "
           "sample_interval: trajectory sample spacing, s (0.001: every control "
           "tick); sim_threads: threads simulating one query's edges (the answer does not depend "
           "on it); raw: the planner's edge chain with a stop at every junction (lazyboe-query "
           "--raw) instead of the executable trajectory (blended, shortcut). ValueError "
           "(with the field's name) for a bad query; returns a PlanResult. Ctrl-C stops the "
           "solve at its next check and raises KeyboardInterrupt.")
      .def("plan_many", &plan_many, py::arg("queries"), py::arg("jobs") = 0,
           py::arg("sample_interval") = 0.01, py::arg("raw") = false,
           "Plans a batch of queries (dicts in the query format: start, goal, planner, budget, "
           "seed, parameters; id optional) on `jobs` threads (0: all cores); results in input "
           "order. Every query is checked before any is planned (ValueError naming the first bad "
           "one); a query whose planner fails (RuntimeError from plan()) gets a result with its "
           "`error`, and the others are planned. Ctrl-C cancels the queries in flight and "
           "raises KeyboardInterrupt.");
  session.def("load_scene", &load_scene, py::arg("env"),
              "Loads a scene once (an environment file's path, or an environment dict) and "
              "returns a Scene to pass as plan(scene=...): any scene of the bundle's robot. "
              "Scenes are kept by content, so loading one again is cheap. OSError for a file "
              "that cannot be read, ValueError for a bad environment.");
  bind_session_properties(session);
}

}  // namespace lazyboe::python
