// The extension module lazyboe._lazyboe; the package lazyboe re-exports it (docs/python.md).
#include "convert.h"
#include "lazyboe/common/version.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe::python {
void bind_robot(py::module_& m);
void bind_bundle(py::module_& m);
void bind_planning(py::module_& m);
void bind_offline(py::module_& m);
}  // namespace lazyboe::python

PYBIND11_MODULE(_lazyboe, m) {
  using namespace lazyboe::python;
  m.doc() = "LazyBoE: kinodynamic motion planning on an edge bundle (the C++ library's types).";
  register_exceptions(m);
  m.attr("__version__") = lazyboe::version();
  m.def("data_dir", &lazyboe::data_dir,
        "The bundled data directory (robots, environments, queries).");
  m.def("default_robot_path", &lazyboe::default_robot_path, "The bundled Panda's robot config.");
  bind_robot(m);
  bind_bundle(m);
  bind_planning(m);
  bind_offline(m);
}
