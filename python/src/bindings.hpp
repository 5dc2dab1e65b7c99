#pragma once
/// \file
/// What the binding files of the `cairn` Python module (python/src/*.cpp) share: one bind_*
/// function per cairn module, called by module.cpp, and the conversions between cairn's types and
/// numpy arrays. Arrays go out as new numpy arrays that own their data (row-major, float64 poses
/// N x 4 x 4, float32 points N x 3) and come in as numpy arrays of any dtype and layout, converted
/// (pybind11's forcecast) once; a wrong shape is a ValueError that names the argument and the
/// shape expected.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"
#include "cairn/io/pose_graph.hpp"

namespace cairn::python {

namespace py = pybind11;

/// A float64 array accepted in any layout and dtype, converted to C order once.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

void bind_core(py::module_& m);       // core.cpp: SO3, SE3, SE2, Sim3, errors
void bind_io(py::module_& m);         // io.cpp: trajectories, pose graphs, point clouds, bags
void bind_backend(py::module_& m);    // backend.cpp: optimize (pose graphs)
void bind_eval(py::module_& m);       // eval.cpp: APE, RPE, the KITTI metric, alignment
void bind_lidar3d(py::module_& m);    // lidar3d.cpp: LidarSlam, scan_sequence, register, Localizer3d
void bind_slam2d(py::module_& m);     // slam2d.cpp: Slam2d, LaserScan, read_carmen_log
void bind_vslam(py::module_& m);      // vslam.cpp: VisualSlam, CameraCalibration, image readers

/// cairn.PoseGraph: a 2-D or 3-D graph and what its reader repaired or ignored.
struct PoseGraphObject {
  io::PoseGraph graph;
  std::vector<std::string> warnings;
};

/// Poses as an N x 4 x 4 float64 array.
py::array_t<double> poses_to_array(const std::vector<Matrix4>& poses);
py::array_t<double> poses_to_array(const std::vector<core::SE3>& poses);
/// An N x 4 x 4 array as matrices; ValueError naming `what` when the shape is another.
std::vector<Matrix4> poses_from_array(const DoubleArray& array, const char* what);
/// One 4 x 4 matrix; ValueError naming `what` otherwise.
Matrix4 matrix4_from_array(const DoubleArray& array, const char* what);

/// Points as an N x 3 float32 array.
py::array_t<float> points_to_array(const std::vector<Eigen::Vector3f>& points);
py::array_t<double> points_to_array(const std::vector<Eigen::Vector3d>& points);
/// An N x 3 array as points; ValueError naming `what` when the shape is another or a value is not
/// finite.
std::vector<Eigen::Vector3f> points_from_array(const FloatArray& array, const char* what);

/// A 1-D float64 array of `values`.
py::array_t<double> vector_to_array(const std::vector<double>& values);

/// JSON (a report, a configuration) as Python dicts, lists and numbers.
py::object json_to_python(const nlohmann::json& value);

/// ValueError with `message`.
[[noreturn]] void throw_value_error(const std::string& message);

}  // namespace cairn::python
