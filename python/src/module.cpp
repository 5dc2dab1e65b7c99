// The `cairn._cairn` extension module: one bind_* function per cairn module (bindings.hpp).
// python/cairn/__init__.py re-exports it as `cairn`.

#include "bindings.hpp"

PYBIND11_MODULE(_cairn, m) {
  m.doc() = "cairn: SLAM, pose-graph optimisation and trajectory evaluation (C++20, bound with pybind11)";
  m.attr("__version__") = CAIRN_VERSION;
  cairn::python::bind_core(m);
  cairn::python::bind_io(m);
  cairn::python::bind_backend(m);
  cairn::python::bind_eval(m);
  cairn::python::bind_lidar3d(m);
  cairn::python::bind_slam2d(m);
  cairn::python::bind_vslam(m);
}
