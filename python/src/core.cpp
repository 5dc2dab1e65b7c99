// cairn.SO3, SE3, SE2, Sim3 (core/) and cairn.ParseError (io/parse_error.hpp).
//
// The groups follow cairn's C++ conventions: tangent vectors translation first (Sophus, g2o),
// quaternions given and returned as (x, y, z, w) (Eigen's coefficient order, as in TUM files),
// `T * points` for points of shape (3,) or (N, 3).

#include <pybind11/eigen.h>
#include <pybind11/operators.h>
#include <pybind11/stl.h>

#include <cstdio>
#include <string>

#include "bindings.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/sim3.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::python {
namespace {

/// `group * p` for p of shape (3,) or (N, 3) (float64), as an array of the same shape.
template <class Group>
py::array_t<double> transform_points(const Group& g, const DoubleArray& p) {
  if (p.ndim() == 1 && p.shape(0) == 3) {
    const Vector3 q = g * Vector3(p.at(0), p.at(1), p.at(2));
    return py::array_t<double>(3, q.data());
  }
  if (p.ndim() != 2 || p.shape(1) != 3) throw_value_error("points: expected an array of shape (3,) or (N, 3)");
  py::array_t<double> out({p.shape(0), py::ssize_t{3}});
  auto in = p.unchecked<2>();
  auto o = out.mutable_unchecked<2>();
  for (py::ssize_t k = 0; k < p.shape(0); ++k) {
    const Vector3 q = g * Vector3(in(k, 0), in(k, 1), in(k, 2));
    for (int c = 0; c < 3; ++c) o(k, c) = q[c];
  }
  return out;
}

/// (x, y, z, w) as a quaternion; ValueError if it is far from unit norm (as the file readers).
Quaternion quaternion_from_xyzw(const Eigen::Vector4d& xyzw) {
  const double norm = xyzw.norm();
  if (!(std::abs(norm - 1.0) < 1e-3)) {
    throw_value_error("quaternion (x, y, z, w): expected unit norm, found " + std::to_string(norm));
  }
  return Quaternion(xyzw[3], xyzw[0], xyzw[1], xyzw[2]).normalized();
}

Eigen::Vector4d xyzw(const Quaternion& q) { return {q.x(), q.y(), q.z(), q.w()}; }

std::string format_vector(const char* name, const Eigen::VectorXd& v) {
  std::string s = std::string(name) + "(";
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%s%.6g", k ? ", " : "", v[k]);
    s += buffer;
  }
  return s + ")";
}

void bind_so3(py::module_& m) {
  using core::SO3;
  py::class_<SO3>(m, "SO3", "3-D rotation (unit quaternion). Tangent: the rotation vector phi (rad).")
      .def(py::init<>(), "The identity.")
      .def_static("from_matrix", &SO3::from_matrix, py::arg("R"), "From a 3 x 3 matrix, projected onto SO(3).")
      .def_static("from_quaternion", [](const Eigen::Vector4d& q) { return SO3(quaternion_from_xyzw(q)); },
                  py::arg("xyzw"), "From a unit quaternion given as (x, y, z, w).")
      .def_static("from_rpy", &SO3::from_rpy, py::arg("roll"), py::arg("pitch"), py::arg("yaw"),
                  "From roll, pitch, yaw (rad): Rz(yaw) Ry(pitch) Rx(roll).")
      .def_static("exp", &SO3::exp, py::arg("phi"), "exp of a rotation vector (rad).")
      .def("log", py::overload_cast<>(&SO3::log, py::const_), "The rotation vector (rad), |phi| <= pi.")
      .def("inverse", &SO3::inverse)
      .def("matrix", &SO3::matrix, "The 3 x 3 rotation matrix.")
      .def("quaternion", [](const SO3& R) { return xyzw(R.unit_quaternion()); }, "The unit quaternion (x, y, z, w).")
      .def("to_rpy", &SO3::to_rpy, "(roll, pitch, yaw) in rad.")
      .def("angle", &SO3::angle, "The rotation angle in rad, in [0, pi].")
      .def("Adj", &SO3::Adj, "The adjoint (the matrix itself).")
      .def_static("hat", &SO3::hat, py::arg("phi"))
      .def_static("vee", &SO3::vee, py::arg("Phi"))
      .def_static("left_jacobian", &SO3::left_jacobian, py::arg("phi"))
      .def_static("left_jacobian_inverse", &SO3::left_jacobian_inverse, py::arg("phi"))
      .def_static("right_jacobian", &SO3::right_jacobian, py::arg("phi"))
      .def_static("right_jacobian_inverse", &SO3::right_jacobian_inverse, py::arg("phi"))
      .def(py::self * py::self)
      .def("__mul__", &transform_points<SO3>, py::arg("points"), "Rotates points of shape (3,) or (N, 3).")
      .def("__repr__", [](const SO3& R) { return format_vector("SO3.exp", R.log()); });
}

void bind_se3(py::module_& m) {
  using core::SE3;
  using core::SO3;
  py::class_<SE3>(m, "SE3", "Rigid motion T = (R, t), T * p = R p + t. Tangent: (rho, phi), translation first.")
      .def(py::init<>(), "The identity.")
      .def(py::init<const SO3&, const Vector3&>(), py::arg("rotation"), py::arg("translation"))
      .def(py::init([](const Matrix3& R, const Vector3& t) { return SE3(SO3::from_matrix(R), t); }),
           py::arg("rotation"), py::arg("translation"), "From a 3 x 3 rotation matrix (projected) and a translation.")
      .def_static("from_matrix", &SE3::from_matrix, py::arg("T"), "From a 4 x 4 matrix; the rotation is projected.")
      .def_static("exp", &SE3::exp, py::arg("xi"), "exp of (rho, phi).")
      .def("log", py::overload_cast<>(&SE3::log, py::const_), "(rho, phi), translation first.")
      .def("inverse", &SE3::inverse)
      .def("matrix", &SE3::matrix, "The 4 x 4 homogeneous matrix.")
      .def("matrix3x4", &SE3::matrix3x4, "The top 3 x 4 rows (a KITTI pose line).")
      .def_property_readonly("rotation", &SE3::so3, "The rotation (SO3).")
      .def_property_readonly("translation", &SE3::translation, "The translation (3,).")
      .def("Adj", &SE3::Adj, "Adj = [[R, [t]x R], [0, R]]: T exp(xi) T^-1 = exp(Adj xi).")
      .def_static("hat", &SE3::hat, py::arg("xi"))
      .def_static("vee", &SE3::vee, py::arg("Xi"))
      .def_static("left_jacobian", &SE3::left_jacobian, py::arg("xi"))
      .def_static("left_jacobian_inverse", &SE3::left_jacobian_inverse, py::arg("xi"))
      .def_static("right_jacobian", &SE3::right_jacobian, py::arg("xi"))
      .def_static("right_jacobian_inverse", &SE3::right_jacobian_inverse, py::arg("xi"))
      .def(py::self * py::self)
      .def("__mul__", &transform_points<SE3>, py::arg("points"), "Transforms points of shape (3,) or (N, 3).")
      .def("__repr__", [](const SE3& T) { return format_vector("SE3.exp", T.log()); });
}

void bind_se2(py::module_& m) {
  using core::SE2;
  py::class_<SE2>(m, "SE2", "Planar rigid motion (x, y, theta). Tangent: (rho_x, rho_y, theta).")
      .def(py::init<>(), "The identity.")
      .def(py::init<double, double, double>(), py::arg("x"), py::arg("y"), py::arg("theta"))
      .def_static("from_matrix", &SE2::from_matrix, py::arg("T"), "From a 3 x 3 matrix; the rotation is projected.")
      .def_static("exp", &SE2::exp, py::arg("xi"))
      .def("log", py::overload_cast<>(&SE2::log, py::const_))
      .def("inverse", &SE2::inverse)
      .def("matrix", &SE2::matrix, "The 3 x 3 homogeneous matrix.")
      .def_property_readonly("x", &SE2::x)
      .def_property_readonly("y", &SE2::y)
      .def_property_readonly("theta", &SE2::angle, "The heading in rad, in (-pi, pi].")
      .def_property_readonly("translation", &SE2::translation)
      .def("Adj", &SE2::Adj)
      .def_static("hat", &SE2::hat, py::arg("xi"))
      .def_static("vee", &SE2::vee, py::arg("Xi"))
      .def_static("left_jacobian", &SE2::left_jacobian, py::arg("xi"))
      .def_static("right_jacobian", &SE2::right_jacobian, py::arg("xi"))
      .def(py::self * py::self)
      .def("__mul__", [](const SE2& T, const Vector2& p) -> Vector2 { return T * p; }, py::arg("point"))
      .def("__repr__", [](const SE2& T) { return format_vector("SE2", Vector3(T.x(), T.y(), T.angle())); });
}

void bind_sim3(py::module_& m) {
  using core::Sim3;
  py::class_<Sim3>(m, "Sim3", "Similarity S = (s R, t), S * p = s R p + t. Tangent: (rho, phi, sigma = ln s).")
      .def(py::init<>(), "The identity.")
      .def(py::init<const core::SO3&, const Vector3&, double>(), py::arg("rotation"), py::arg("translation"),
           py::arg("scale"))
      .def(py::init<const core::SE3&, double>(), py::arg("T"), py::arg("scale") = 1.0)
      .def_static("from_matrix", &Sim3::from_matrix, py::arg("S"), "From a 4 x 4 matrix [[s R, t], [0, 1]].")
      .def_static("exp", &Sim3::exp, py::arg("xi"))
      .def("log", py::overload_cast<>(&Sim3::log, py::const_))
      .def("inverse", &Sim3::inverse)
      .def("matrix", &Sim3::matrix)
      .def_property_readonly("scale", &Sim3::scale)
      .def_property_readonly("rotation", &Sim3::so3)
      .def_property_readonly("translation", &Sim3::translation)
      .def("to_se3", &Sim3::to_se3, "(R, t), the scale dropped.")
      .def("Adj", &Sim3::Adj)
      .def_static("hat", &Sim3::hat, py::arg("xi"))
      .def_static("vee", &Sim3::vee, py::arg("Xi"))
      .def_static("left_jacobian", &Sim3::left_jacobian, py::arg("xi"))
      .def_static("right_jacobian", &Sim3::right_jacobian, py::arg("xi"))
      .def(py::self * py::self)
      .def("__mul__", &transform_points<Sim3>, py::arg("points"))
      .def("__repr__", [](const Sim3& S) { return format_vector("Sim3.exp", S.log()); });
}

/// io::ParseError as cairn.ParseError (a ValueError) with the file, the line (0: none) and the
/// detail as attributes, so that a caller can point at the input as the CLI does.
void bind_errors(py::module_& m) {
  static py::exception<io::ParseError> parse_error(m, "ParseError", PyExc_ValueError);
  parse_error.doc() = "Bad input: str() names the file, the line (or byte offset) and what was expected; the "
                      "attributes file, line (0 when none) and detail give them apart.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const io::ParseError& e) {
      py::object error = py::handle(parse_error.ptr())(e.what());  // an instance of the type
      error.attr("file") = e.file();
      error.attr("line") = e.line();
      error.attr("detail") = e.detail();
      PyErr_SetObject(parse_error.ptr(), error.ptr());
    }
  });
}

}  // namespace

void bind_core(py::module_& m) {
  bind_errors(m);
  bind_so3(m);
  bind_se3(m);
  bind_se2(m);
  bind_sim3(m);
}

}  // namespace cairn::python
