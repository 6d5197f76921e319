// lazyboe.Bundle: a bundle file opened read-only (memory-mapped), its header as a dict and its
// per-edge datasets as read-only NumPy views of the mapping.
#include <pybind11/stl.h>

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "convert.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/bundle/inspect.h"
#include "lazyboe/io/bundle_report.h"

namespace lazyboe::python {

py::dict header_dict(const BundleHeader& h) {
  py::dict d;
  d["schema_version"] = h.schema_version;
  d["tool_version"] = h.tool_version;
  d["complete"] = h.complete;
  d["robot_name"] = h.robot_name;
  d["robot_config"] = h.robot_config;
  d["robot_hash"] = h.robot_hash;
  d["env_name"] = h.env_name;
  d["env_file"] = h.env_file;
  d["env_hash"] = h.env_hash;
  d["dof"] = h.dof;
  d["seed"] = h.seed;
  d["target_edges"] = h.target_edges;
  d["region_lower"] = h.region_lower;
  d["region_upper"] = h.region_upper;
  d["min_duration"] = h.min_duration;
  d["max_duration"] = h.max_duration;
  d["knot_interval"] = h.knot_interval;
  d["integrator"] = h.integrator;
  d["substeps"] = h.substeps;
  d["velocity_scale"] = h.velocity_scale;
  d["limit_scale"] = h.limit_scale;
  d["control_rate"] = h.control_rate;
  d["sample_interval"] = h.sample_interval;
  d["design_theta"] = h.design_theta;
  d["attempts"] = h.attempts;
  d["valid"] = h.valid;
  d["rejected"] = h.rejected;
  d["start_resamples"] = h.start_resamples;
  d["simulated_seconds"] = h.simulated_seconds;
  d["wall_seconds"] = h.wall_seconds;
  return d;
}

// What a print_* function of the library writes, as a string.
template <typename Print>
std::string printed(Print&& print) {
  char* text = nullptr;
  size_t size = 0;
  std::FILE* out = open_memstream(&text, &size);
  if (!out) throw std::runtime_error("open_memstream failed");
  try {
    print(out);
  } catch (...) {
    std::fclose(out);
    std::free(text);
    throw;
  }
  std::fclose(out);
  std::string s(text, size);
  std::free(text);
  return s;
}

namespace {

using View = std::shared_ptr<BundleView>;

// A per-edge dataset as a read-only view; None when the bundle does not have it.
py::object edge_array(const py::object& self, const double* (BundleView::*data)() const) {
  const View& v = self.cast<const View&>();
  const double* p = ((*v).*data)();
  if (!p) return py::none();
  return readonly_view(p, {static_cast<py::ssize_t>(v->size())}, self);
}

py::object edge_rows(const py::object& self, bool end) {
  const View& v = self.cast<const View&>();
  const double* p = v->size() ? (end ? v->qf(0) : v->q0(0)) : nullptr;
  return readonly_view(p, {static_cast<py::ssize_t>(v->size()), v->dof()}, self);
}

py::dict command_of(const py::object& self, int64_t edge) {
  const View& v = self.cast<const View&>();
  if (edge < 0) edge += static_cast<int64_t>(v->size());
  if (edge < 0 || edge >= static_cast<int64_t>(v->size()))
    throw py::index_error("edge: out of range (the bundle has " + std::to_string(v->size()) +
                          " edges)");
  const CommandProfile c = v->command(static_cast<size_t>(edge));
  py::dict d;
  d["knots"] = readonly_view(c.knots, {c.n_knots, c.dof}, self);
  d["duration"] = c.duration;
  return d;
}

// The per-edge arrays: read-only NumPy views of the (mapped) datasets.
void bind_edge_arrays(py::class_<BundleView, View>& c) {
  c.def_property_readonly(
       "q0", [](const py::object& s) { return edge_rows(s, false); },
       "Edge start states, (N, dof), read-only view.")
      .def_property_readonly(
          "qf", [](const py::object& s) { return edge_rows(s, true); },
          "Edge end states, (N, dof), read-only view.")
      .def_property_readonly(
          "duration", [](const py::object& s) { return edge_array(s, &BundleView::duration_data); },
          "Simulated edge durations including settling, s, (N,).")
      .def_property_readonly(
          "command_duration",
          [](const py::object& s) { return edge_array(s, &BundleView::command_duration_data); },
          "Durations of the velocity commands, s, (N,).")
      .def_property_readonly(
          "p_lazy_prop",
          [](const py::object& s) { return edge_array(s, &BundleView::p_lazy_prop_data); },
          "P_lazy_prop per edge (N,), or None without a perturbation analysis.")
      .def_property_readonly(
          "p_collision",
          [](const py::object& s) { return edge_array(s, &BundleView::p_collision_data); },
          "P_collision per edge (N,), or None without a perturbation analysis.")
      .def_property_readonly(
          "p_lazy_prop_transfer",
          [](const py::object& s) { return edge_array(s, &BundleView::p_lazy_prop_transfer_data); },
          "P_lazy_prop under displacement transfer (N,), or None.")
      .def_property_readonly(
          "transfer_max_error",
          [](const py::object& s) { return edge_array(s, &BundleView::transfer_max_error_data); },
          "Largest transfer residual per edge, rad (N,), or None.");
}

}  // namespace

void bind_bundle(py::module_& m) {
  py::class_<BundleView, View> bundle(
      m, "Bundle",
      "An edge bundle file, opened read-only. The per-edge arrays (q0, qf, duration, "
      "command_duration, p_lazy_prop, p_collision, p_lazy_prop_transfer, transfer_max_error) "
      "are read-only NumPy views of the memory-mapped file, not copies; they keep the bundle "
      "open.");
  bind_edge_arrays(bundle);
  bundle
      .def(py::init([](const py::object& path, bool memory_map) {
             const std::string p = py::str(path).cast<std::string>();
             return file_errors(
                 [&] { return std::make_shared<BundleView>(BundleView::open(p, memory_map)); });
           }),
           py::arg("path"), py::arg("memory_map") = true,
           "Opens a bundle file. memory_map=False reads every dataset into memory. OSError for "
           "a missing, corrupt or incomplete bundle.")
      .def_property_readonly("path", &BundleView::path, "The bundle file.")
      .def_property_readonly(
          "header", [](const BundleView& v) { return header_dict(v.header()); },
          "The header (the file's root attributes) as a dict.")
      .def_property_readonly("dof", &BundleView::dof, "Joints of the robot.")
      .def("__len__", &BundleView::size, "Number of edges.")
      .def_property_readonly("size", &BundleView::size, "Number of edges.")
      .def_property_readonly("memory_mapped", &BundleView::memory_mapped,
                             "True when every dataset is mapped from the file (not read).")
      .def_property_readonly("warnings", &BundleView::warnings,
                             "Why datasets were read instead of mapped, if any.")
      .def_property_readonly("has_perturbation", &BundleView::has_perturbation,
                             "The bundle holds a finished perturbation analysis.")
      .def_property_readonly(
          "perturbation_theta",
          [](const BundleView& v) -> py::object {
            if (!v.has_perturbation()) return py::none();
            return py::float_(v.perturbation_theta());
          },
          "theta of the perturbation analysis, rad; None without one.")
      .def("command", &command_of, py::arg("edge"),
           "The velocity command of an edge: {'knots': (k, dof) view, 'duration': s}.")
      .def(
          "inspect",
          [](const BundleView& v) {
            const std::string path = v.path();
            py::gil_scoped_release free;
            return file_errors([&] {
              return printed([&](std::FILE* out) {
                print_inspection(path, out);
                print_files_beside(path, out);
              });
            });
          },
          "The text of `lazyboe-build --inspect`: header and statistics (durations, "
          "displacements, coverage, neighbours within theta; the k-d tree index and checkpoint "
          "journals beside the file).")
      .def("__repr__", [](const BundleView& v) {
        return "<lazyboe.Bundle '" + v.path() + "': " + std::to_string(v.size()) + " edges>";
      });
}

}  // namespace lazyboe::python

namespace lazyboe::python {
py::object make_bundle_object(std::shared_ptr<const BundleView> view) {
  return py::cast(std::const_pointer_cast<BundleView>(view));
}
}  // namespace lazyboe::python
