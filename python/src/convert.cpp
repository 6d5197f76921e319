#include "convert.h"

#include <cmath>

namespace lazyboe::python {

void register_exceptions(py::module_& m) {
  (void)m;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const FileError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });
}

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

JointRows joint_rows(const py::handle& value, int dof, const std::string& name) {
  JointRows r;
  const std::string expected =
      "expected " + std::to_string(dof) + " values or an (N, " + std::to_string(dof) + ") array";
  py::array raw;
  try {
    raw = py::array::ensure(value);
  } catch (const py::error_already_set&) {
  }
  if (!raw || raw.dtype().kind() == 'O' || raw.dtype().kind() == 'U' || raw.dtype().kind() == 'S') {
    throw InputError(name + ": " + expected + " of numbers");
  }
  if (!(raw.ndim() == 1 && raw.shape(0) == dof) && !(raw.ndim() == 2 && raw.shape(1) == dof))
    throw InputError(name + ": " + expected + ", got shape " + shape_text(raw));
  r.array = DoubleArray::ensure(raw);
  if (!r.array) throw InputError(name + ": " + expected + " of numbers");
  r.batch = r.array.ndim() == 2;
  r.rows = r.batch ? r.array.shape(0) : 1;
  r.cols = dof;
  r.data = r.array.data();
  for (py::ssize_t k = 0; k < r.rows * dof; ++k) {
    if (!std::isfinite(r.data[k])) throw InputError(name + ": not a finite number");
  }
  return r;
}

void check_same_rows(const JointRows& a, const JointRows& b, const std::string& name_b) {
  if (a.batch != b.batch || a.rows != b.rows) {
    throw InputError(name_b + ": expected the shape of the first argument (" +
                     (a.batch ? std::to_string(a.rows) + " rows" : std::string("one state")) + ")");
  }
}

DoubleArray new_array(py::ssize_t rows, bool batch, std::vector<py::ssize_t> inner) {
  if (batch) inner.insert(inner.begin(), rows);
  return DoubleArray(inner);
}

py::array readonly_view(const double* data, std::vector<py::ssize_t> shape, py::handle owner) {
  static const double empty = 0;
  py::array a(py::dtype::of<double>(), shape, {}, data ? data : &empty, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array_t<double> to_array(const JointVectorRef& v) {
  py::array_t<double> a(v.size());
  std::copy(v.data(), v.data() + v.size(), a.mutable_data());
  return a;
}
py::array_t<double> to_array(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}
py::array_t<double> rows_to_array(const std::vector<JointVector>& rows, int cols) {
  py::array_t<double> a({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(cols)});
  double* out = a.mutable_data();
  for (const JointVector& r : rows) out = std::copy(r.data(), r.data() + cols, out);
  return a;
}
std::vector<double> to_vector(const JointVectorRef& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

nlohmann::json to_json(const py::handle& value, const std::string& where) {
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) {
    try {
      return value.cast<int64_t>();
    } catch (const py::cast_error&) {
      throw InputError(where + ": integer out of range");
    }
  }
  if (py::isinstance<py::float_>(value)) return value.cast<double>();
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  // lazyboe.Pose, Payload, EndEffectorLimits (lazyboe/task.py): the query format's object.
  if (py::hasattr(value, "to_query")) return to_json(value.attr("to_query")(), where);
  if (py::isinstance<py::dict>(value)) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [k, v] : value.cast<py::dict>()) {
      if (!py::isinstance<py::str>(k)) throw InputError(where + ": keys must be strings");
      const std::string key = k.cast<std::string>();
      j[key] = to_json(v, where.empty() ? key : where + "." + key);
    }
    return j;
  }
  if (py::isinstance<py::array>(value) || py::hasattr(value, "tolist"))  // NumPy arrays, scalars
    return to_json(value.attr("tolist")(), where);
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& v : value) j.push_back(to_json(v, where));
    return j;
  }
  throw InputError(where + ": cannot be given as " +
                   py::str(value.get_type().attr("__name__")).cast<std::string>());
}

py::object from_json(const nlohmann::json& value) {
  switch (value.type()) {
    case nlohmann::json::value_t::null:
      return py::none();
    case nlohmann::json::value_t::boolean:
      return py::bool_(value.get<bool>());
    case nlohmann::json::value_t::number_integer:
      return py::int_(value.get<int64_t>());
    case nlohmann::json::value_t::number_unsigned:
      return py::int_(value.get<uint64_t>());
    case nlohmann::json::value_t::number_float:
      return py::float_(value.get<double>());
    case nlohmann::json::value_t::string:
      return py::str(value.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& v : value) l.append(from_json(v));
      return std::move(l);
    }
    default: {
      py::dict d;
      for (const auto& [k, v] : value.items()) d[py::str(k)] = from_json(v);
      return std::move(d);
    }
  }
}

}  // namespace lazyboe::python
