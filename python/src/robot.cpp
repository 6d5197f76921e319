// lazyboe.Robot, lazyboe.Environment, lazyboe.CollisionChecker: the robot model's algorithms on
// one state or vectorized over the rows of an (N, dof) array, with the GIL released.
#include <pybind11/stl.h>

#include <memory>

#include "convert.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe::python {
namespace {

using Model = std::shared_ptr<const RobotModel>;

Eigen::Map<const Eigen::VectorXd> row_of(const JointRows& r, py::ssize_t k) {
  return Eigen::Map<const Eigen::VectorXd>(r.row(k), r.cols);
}

void write_pose(const Pose& pose, double* out) {  // 4 x 4 homogeneous, row-major
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out[4 * i + j] = pose.R(i, j);
    out[4 * i + 3] = pose.p[i];
  }
  out[12] = out[13] = out[14] = 0;
  out[15] = 1;
}

int link_of(const RobotModel& m, const py::object& link) {
  if (link.is_none()) return m.tip_link();
  if (!py::isinstance<py::str>(link)) throw InputError("link: expected a link name");
  const std::string name = link.cast<std::string>();
  const int k = m.link_index(name);
  if (k < 0) throw InputError("link: " + m.unknown_link(name));
  return k;
}

DoubleArray forward_kinematics_of(const Model& m, const py::handle& q_in, const py::object& link) {
  const int l = link_of(*m, link);
  const JointRows q = joint_rows(q_in, m->dof, "q");
  DoubleArray out = new_array(q.rows, q.batch, {4, 4});
  double* o = out.mutable_data();
  py::gil_scoped_release free;
  RobotData data(*m);
  for (py::ssize_t k = 0; k < q.rows; ++k) {
    forward_kinematics(*m, data, row_of(q, k));
    write_pose(link_pose(*m, data, l), o + 16 * k);
  }
  return out;
}

// f(state args...) -> a joint vector, per row.
template <int Args, typename F>
DoubleArray per_row(const Model& m, const std::array<py::handle, Args>& in,
                    const std::array<const char*, Args>& names, F&& f) {
  std::array<JointRows, Args> rows;
  for (int a = 0; a < Args; ++a) {
    rows[a] = joint_rows(in[a], m->dof, names[a]);
    if (a > 0) check_same_rows(rows[0], rows[a], names[a]);
  }
  DoubleArray out = new_array(rows[0].rows, rows[0].batch, {m->dof});
  double* o = out.mutable_data();
  py::gil_scoped_release free;
  RobotData data(*m);
  for (py::ssize_t k = 0; k < rows[0].rows; ++k) {
    const JointVector& v = f(data, rows, k);
    std::copy(v.data(), v.data() + m->dof, o + k * m->dof);
  }
  return out;
}

DoubleArray mass_matrix_of(const Model& m, const py::handle& q_in) {
  const JointRows q = joint_rows(q_in, m->dof, "q");
  const int n = m->dof;
  DoubleArray out = new_array(q.rows, q.batch, {n, n});
  double* o = out.mutable_data();
  py::gil_scoped_release free;
  RobotData data(*m);
  for (py::ssize_t k = 0; k < q.rows; ++k) {
    const JointMatrix& M = mass_matrix(*m, data, row_of(q, k));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) o[k * n * n + i * n + j] = M(i, j);
  }
  return out;
}

// The collision model of a robot in an environment, and the checks on it.
struct CollisionChecker {
  Model robot;
  std::shared_ptr<const Environment> env;
  std::shared_ptr<const CollisionModel> model;

  CollisionChecker(Model r, std::shared_ptr<const Environment> e)
      : robot(std::move(r)), env(std::move(e)) {
    model = input_errors(
        [&] { return std::make_shared<CollisionModel>(build_collision_model(*robot, *env)); });
  }

  py::object in_collision(const py::handle& q_in) const {
    const JointRows q = joint_rows(q_in, robot->dof, "q");
    py::array_t<bool> out(q.rows);
    bool* o = out.mutable_data();
    {
      py::gil_scoped_release free;
      RobotData rd(*robot);
      CollisionData cd(*model);
      for (py::ssize_t k = 0; k < q.rows; ++k) {
        forward_kinematics(*robot, rd, row_of(q, k));
        update_collision_transforms(*model, cd, rd);
        o[k] = lazyboe::in_collision(*model, cd);
      }
    }
    if (!q.batch) return py::bool_(o[0]);
    return std::move(out);
  }

  py::object min_distance(const py::handle& q_in) const {
    const JointRows q = joint_rows(q_in, robot->dof, "q");
    DoubleArray out(q.rows);
    double* o = out.mutable_data();
    {
      py::gil_scoped_release free;
      RobotData rd(*robot);
      CollisionData cd(*model);
      for (py::ssize_t k = 0; k < q.rows; ++k) {
        forward_kinematics(*robot, rd, row_of(q, k));
        update_collision_transforms(*model, cd, rd);
        o[k] = lazyboe::min_distance(*model, cd).min();
      }
    }
    if (!q.batch) return py::float_(o[0]);
    return std::move(out);
  }
};

std::shared_ptr<const Environment> environment_of(const py::object& env) {
  if (env.is_none())
    return file_errors(
        [] { return std::make_shared<Environment>(load_environment(default_environment_path())); });
  if (py::isinstance<Environment>(env)) return env.cast<std::shared_ptr<Environment>>();
  const std::string path = py::str(env).cast<std::string>();  // str or os.PathLike
  return file_errors([&] { return std::make_shared<Environment>(load_environment(path)); });
}

std::vector<std::string> joint_names(const RobotModel& m) {
  std::vector<std::string> names;
  for (const Joint& j : m.joints) names.push_back(j.name);
  return names;
}
std::vector<std::string> link_names(const RobotModel& m) {
  std::vector<std::string> names;
  for (const Link& l : m.links) names.push_back(l.name);
  return names;
}

py::list joint_dicts(const RobotModel& m) {
  static const char* frictions[] = {"none", "sigmoid", "viscous_coulomb"};
  py::list out;
  for (const Joint& j : m.joints) {
    py::dict d, f;
    d["name"] = j.name;
    d["type"] = j.type == JointType::Revolute ? "revolute" : "prismatic";
    d["axis"] = std::vector<double>{j.axis.x(), j.axis.y(), j.axis.z()};
    d["lower"] = j.lower;
    d["upper"] = j.upper;
    d["max_velocity"] = j.max_velocity;
    d["max_acceleration"] = j.max_acceleration;
    d["max_jerk"] = j.max_jerk;
    d["max_effort"] = j.max_effort;
    d["max_torque_rate"] = j.max_torque_rate;
    f["model"] = frictions[static_cast<int>(j.friction.model)];
    f["a"] = j.friction.a;
    f["b"] = j.friction.b;
    f["c"] = j.friction.c;
    d["friction"] = f;
    out.append(d);
  }
  return out;
}

py::list link_dicts(const RobotModel& m) {
  py::list out;
  for (const Link& l : m.links) {
    py::dict d;
    d["name"] = l.name;
    d["body"] = l.body;  // the moving body it is fixed to (joint index); -1 for the base
    out.append(d);
  }
  return out;
}

void bind_environment(py::module_& m) {
  py::class_<Environment, std::shared_ptr<Environment>>(
      m, "Environment",
      "A static environment: named primitive obstacles (an environment JSON file).")
      .def(py::init([](const py::object& path) {
             return std::const_pointer_cast<Environment>(environment_of(path));
           }),
           py::arg("path") = py::none(),
           "Loads an environment file (default: the bundled table.json). OSError for a missing "
           "or malformed file.")
      .def_readonly("name", &Environment::name, "Its name.")
      .def_readonly("path", &Environment::path, "The file it was read from.")
      .def_readonly("description", &Environment::description, "Its description.")
      .def_property_readonly(
          "obstacles",
          [](const Environment& e) {
            std::vector<std::string> names;
            for (const Obstacle& o : e.obstacles) names.push_back(o.name);
            return names;
          },
          "Obstacle names.")
      .def("__repr__", [](const Environment& e) {
        return "<lazyboe.Environment '" + e.name + "': " + std::to_string(e.obstacles.size()) +
               " obstacles>";
      });
}

void bind_robot_properties(py::class_<PyRobot>& c) {
  c.def_property_readonly(
       "joints", [](const PyRobot& r) { return joint_dicts(*r.model); },
       "Per joint (chain order) a dict: name, type, axis, lower, upper, max_velocity, "
       "max_acceleration, max_jerk, max_effort, max_torque_rate, friction {model, a, b, c}.")
      .def_property_readonly(
          "links", [](const PyRobot& r) { return link_dicts(*r.model); },
          "Per link (base first) a dict: name, body (the joint moving it; -1 for the base).")
      .def_property_readonly(
          "name", [](const PyRobot& r) { return r.model->name; }, "The robot config's name.")
      .def_property_readonly(
          "config_path", [](const PyRobot& r) { return r.model->files.config; },
          "The robot config file.")
      .def_property_readonly(
          "dof", [](const PyRobot& r) { return r.model->dof; }, "Joints of the chain.")
      .def_property_readonly(
          "control_rate", [](const PyRobot& r) { return r.model->control_rate; },
          "Control ticks per second, Hz.")
      .def_property_readonly(
          "joint_names", [](const PyRobot& r) { return joint_names(*r.model); },
          "Joint names, in chain order.")
      .def_property_readonly(
          "link_names", [](const PyRobot& r) { return link_names(*r.model); },
          "Every link of the chain, base first; the last is the tip.")
      .def_property_readonly(
          "lower", [](const PyRobot& r) { return to_array(r.model->q_min); },
          "Joint position lower limits (rad or m).")
      .def_property_readonly(
          "upper", [](const PyRobot& r) { return to_array(r.model->q_max); },
          "Joint position upper limits (rad or m).")
      .def_property_readonly(
          "velocity_limits", [](const PyRobot& r) { return to_array(r.model->dq_max); },
          "Joint velocity limits (rad/s or m/s).")
      .def_property_readonly(
          "acceleration_limits", [](const PyRobot& r) { return to_array(r.model->ddq_max); },
          "Joint acceleration limits.")
      .def_property_readonly(
          "jerk_limits", [](const PyRobot& r) { return to_array(r.model->dddq_max); },
          "Joint jerk limits.")
      .def_property_readonly(
          "effort_limits", [](const PyRobot& r) { return to_array(r.model->tau_max); },
          "Joint torque (force) limits.")
      .def_property_readonly(
          "torque_rate_limits", [](const PyRobot& r) { return to_array(r.model->dtau_max); },
          "Joint torque rate limits.")
      .def_property_readonly(
          "region_lower", [](const PyRobot& r) { return to_array(r.model->region.lower); },
          "Default sampling box of bundle start states, lower corner.")
      .def_property_readonly(
          "region_upper", [](const PyRobot& r) { return to_array(r.model->region.upper); },
          "Default sampling box of bundle start states, upper corner.");
}

void bind_robot_algorithms(py::class_<PyRobot>& c) {
  c.def(
       "forward_kinematics",
       [](const PyRobot& r, const py::handle& q, const py::object& link) {
         return forward_kinematics_of(r.model, q, link);
       },
       py::arg("q"), py::arg("link") = py::none(),
       "Pose of `link` (default: the tip) in the base frame as a 4x4 homogeneous transform; "
       "(N, 4, 4) for an (N, dof) array of q.")
      .def(
          "inverse_dynamics",
          [](const PyRobot& r, const py::handle& q, const py::handle& dq, const py::handle& ddq) {
            return per_row<3>(r.model, {q, dq, ddq}, {"q", "dq", "ddq"},
                              [&](RobotData& d, const std::array<JointRows, 3>& a,
                                  py::ssize_t k) -> const JointVector& {
                                return inverse_dynamics(*r.model, d, row_of(a[0], k),
                                                        row_of(a[1], k), row_of(a[2], k));
                              });
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"),
          "Joint torques tau = M(q) ddq + C(q, dq) dq + g(q) + tau_f(dq), friction included "
          "(recursive Newton-Euler); one row per row of (N, dof) arrays.")
      .def(
          "forward_dynamics",
          [](const PyRobot& r, const py::handle& q, const py::handle& dq, const py::handle& tau) {
            return per_row<3>(r.model, {q, dq, tau}, {"q", "dq", "tau"},
                              [&](RobotData& d, const std::array<JointRows, 3>& a,
                                  py::ssize_t k) -> const JointVector& {
                                return forward_dynamics(*r.model, d, row_of(a[0], k),
                                                        row_of(a[1], k), row_of(a[2], k));
                              });
          },
          py::arg("q"), py::arg("dq"), py::arg("tau"),
          "Joint accelerations ddq = M^-1 (tau - C dq - g - tau_f); one row per row of (N, dof) "
          "arrays.")
      .def(
          "gravity_torques",
          [](const PyRobot& r, const py::handle& q) {
            return per_row<1>(r.model, {q}, {"q"},
                              [&](RobotData& d, const std::array<JointRows, 1>& a,
                                  py::ssize_t k) -> const JointVector& {
                                return gravity_torques(*r.model, d, row_of(a[0], k));
                              });
          },
          py::arg("q"), "Gravity torques g(q).")
      .def(
          "friction_torques",
          [](const PyRobot& r, const py::handle& dq) {
            return per_row<1>(r.model, {dq}, {"dq"},
                              [&](RobotData& d, const std::array<JointRows, 1>& a,
                                  py::ssize_t k) -> const JointVector& {
                                return friction_torques(*r.model, d, row_of(a[0], k));
                              });
          },
          py::arg("dq"), "Joint friction torques tau_f(dq).")
      .def(
          "mass_matrix",
          [](const PyRobot& r, const py::handle& q) { return mass_matrix_of(r.model, q); },
          py::arg("q"),
          "Joint-space mass matrix M(q) (dof x dof; (N, dof, dof) for an (N, dof) array).")
      .def(
          "collision_checker",
          [](const PyRobot& r, const py::object& env) {
            return CollisionChecker(r.model, environment_of(env));
          },
          py::arg("env") = py::none(),
          "The collision model in `env` (an Environment or a path; default: the bundled "
          "table.json), to check many states.")
      .def(
          "in_collision",
          [](const PyRobot& r, const py::handle& q, const py::object& env) {
            return CollisionChecker(r.model, environment_of(env)).in_collision(q);
          },
          py::arg("q"), py::arg("env") = py::none(),
          "collision_checker(env).in_collision(q): True when q collides; a bool array for an "
          "(N, dof) array.")
      .def("__repr__", [](const PyRobot& r) {
        return "<lazyboe.Robot '" + r.model->name + "': " + std::to_string(r.model->dof) +
               " joints>";
      });
}

}  // namespace

void bind_robot(py::module_& m) {
  bind_environment(m);
  py::class_<CollisionChecker>(m, "CollisionChecker",
                               "The collision model of a robot in an environment (self and "
                               "environment collision, with the robot's margin).")
      .def("in_collision", &CollisionChecker::in_collision, py::arg("q"),
           "True when q collides (self or environment, closer than the margin); a bool array "
           "for an (N, dof) array.")
      .def("min_distance", &CollisionChecker::min_distance, py::arg("q"),
           "Exact smallest distance over the tested pairs, m (0 when touching); an array for "
           "an (N, dof) array.");

  py::class_<PyRobot> robot(m, "Robot",
                            "A robot model: a serial chain from a robot config and its URDF.");
  robot.def(
      py::init([](const py::object& config) {
        const std::string path =
            config.is_none() ? default_robot_path() : py::str(config).cast<std::string>();
        return PyRobot{file_errors([&] { return std::make_shared<RobotModel>(load_robot(path)); })};
      }),
      py::arg("config") = py::none(),
      "Loads a robot config (JSON) and its URDF (default: the bundled Panda). OSError "
      "naming the file and field for anything missing or malformed.");
  bind_robot_properties(robot);
  bind_robot_algorithms(robot);
}

}  // namespace lazyboe::python
