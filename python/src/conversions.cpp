// Conversions between cairn's types and numpy arrays (bindings.hpp).

#include <cmath>
#include <cstring>
#include <string>

#include "bindings.hpp"

namespace cairn::python {
namespace {

std::string shape_of(const py::array& array) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < array.ndim(); ++k) s += (k ? ", " : "") + std::to_string(array.shape(k));
  return s + (array.ndim() == 1 ? ",)" : ")");
}

}  // namespace

void throw_value_error(const std::string& message) { throw py::value_error(message); }

py::array_t<double> poses_to_array(const std::vector<Matrix4>& poses) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto view = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) view(static_cast<py::ssize_t>(k), r, c) = poses[k](r, c);
    }
  }
  return out;
}

py::array_t<double> poses_to_array(const std::vector<core::SE3>& poses) {
  std::vector<Matrix4> matrices;
  matrices.reserve(poses.size());
  for (const auto& T : poses) matrices.push_back(T.matrix());
  return poses_to_array(matrices);
}

std::vector<Matrix4> poses_from_array(const DoubleArray& array, const char* what) {
  if (array.ndim() != 3 || array.shape(1) != 4 || array.shape(2) != 4) {
    throw_value_error(std::string(what) + ": expected an array of shape (N, 4, 4), found " + shape_of(array));
  }
  auto view = array.unchecked<3>();
  std::vector<Matrix4> poses(static_cast<std::size_t>(array.shape(0)));
  for (std::size_t k = 0; k < poses.size(); ++k) {
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) poses[k](r, c) = view(static_cast<py::ssize_t>(k), r, c);
    }
  }
  return poses;
}

Matrix4 matrix4_from_array(const DoubleArray& array, const char* what) {
  if (array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4) {
    throw_value_error(std::string(what) + ": expected a 4 x 4 array, found " + shape_of(array));
  }
  auto view = array.unchecked<2>();
  Matrix4 T;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) T(r, c) = view(r, c);
  }
  return T;
}

py::array_t<float> points_to_array(const std::vector<Eigen::Vector3f>& points) {
  py::array_t<float> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  // Eigen::Vector3f is three packed floats: one copy of the whole buffer.
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  if (!points.empty()) std::memcpy(out.mutable_data(), points.data(), points.size() * sizeof(Eigen::Vector3f));
  return out;
}

py::array_t<double> points_to_array(const std::vector<Eigen::Vector3d>& points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
  if (!points.empty()) std::memcpy(out.mutable_data(), points.data(), points.size() * sizeof(Eigen::Vector3d));
  return out;
}

std::vector<Eigen::Vector3f> points_from_array(const FloatArray& array, const char* what) {
  if (array.ndim() != 2 || array.shape(1) != 3) {
    throw_value_error(std::string(what) + ": expected an array of shape (N, 3), found " + shape_of(array));
  }
  std::vector<Eigen::Vector3f> points(static_cast<std::size_t>(array.shape(0)));
  if (!points.empty()) std::memcpy(static_cast<void*>(points.data()), array.data(), points.size() * sizeof(Eigen::Vector3f));
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (!points[k].allFinite()) {
      throw_value_error(std::string(what) + ": row " + std::to_string(k) + " is not finite (NaN or infinity)");
    }
  }
  return points;
}

py::array_t<double> vector_to_array(const std::vector<double>& values) {
  py::array_t<double> out(static_cast<py::ssize_t>(values.size()));
  if (!values.empty()) std::memcpy(out.mutable_data(), values.data(), values.size() * sizeof(double));
  return out;
}

py::object json_to_python(const nlohmann::json& value) {
  // Through Python's own json module: cairn's reports are small, and its parser gives exactly
  // the dicts, lists, ints and floats a user of json.load expects.
  return py::module_::import("json").attr("loads")(value.dump());
}

}  // namespace cairn::python
