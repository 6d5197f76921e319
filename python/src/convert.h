// What every part of the module shares: the library's errors as Python exceptions, and NumPy
// arrays in and out.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "lazyboe/common/error.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/robot/types.h"

namespace lazyboe::python {

namespace py = pybind11;

// Raised as ValueError (bad input) and OSError (files); lazyboe::Error elsewhere is a
// RuntimeError (pybind11's translation of std::runtime_error).
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct FileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
void register_exceptions(py::module_& m);

// Runs `body`, turning a lazyboe::Error into InputError / FileError with the same message.
template <typename Body>
decltype(auto) input_errors(Body&& body) {
  try {
    return body();
  } catch (const Error& e) {
    throw InputError(e.what());
  }
}
template <typename Body>
decltype(auto) file_errors(Body&& body) {
  try {
    return body();
  } catch (const Error& e) {
    throw FileError(e.what());
  }
}

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// One state (shape (n,)) or a batch (shape (N, n)) of joint-space rows.
struct JointRows {
  DoubleArray array;
  const double* data = nullptr;
  py::ssize_t rows = 0;
  bool batch = false;
  const double* row(py::ssize_t k) const { return data + k * cols; }
  py::ssize_t cols = 0;
};
// Throws InputError("<name>: expected 7 values or an (N, 7) array, got shape (3, 2)").
JointRows joint_rows(const py::handle& value, int dof, const std::string& name);
// Several arguments of one call must agree on single/batch and on N.
void check_same_rows(const JointRows& a, const JointRows& b, const std::string& name_b);

// A new array of shape (rows, inner...) or (inner...) when !batch.
DoubleArray new_array(py::ssize_t rows, bool batch, std::vector<py::ssize_t> inner);

// A read-only NumPy view of `data` (not copied), keeping `owner` alive.
py::array readonly_view(const double* data, std::vector<py::ssize_t> shape, py::handle owner);

// Copies.
py::array_t<double> to_array(const JointVectorRef& v);
py::array_t<double> to_array(const std::vector<double>& v);
py::array_t<double> rows_to_array(const std::vector<JointVector>& rows, int cols);
std::vector<double> to_vector(const JointVectorRef& v);

// Python values (dict, list, tuple, str, bool, int, float, None, NumPy arrays and scalars, and
// objects with to_query(), as lazyboe.Pose) as JSON, for the query format; throws InputError
// naming `where` for anything else.
nlohmann::json to_json(const py::handle& value, const std::string& where);
py::object from_json(const nlohmann::json& value);

// lazyboe.Robot: a shared, read-only robot model (possibly a part of a PlanningSession).
struct PyRobot {
  std::shared_ptr<const RobotModel> model;
};

}  // namespace lazyboe::python
