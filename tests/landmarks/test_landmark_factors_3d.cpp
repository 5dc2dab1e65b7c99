// 3D landmark factors: analytic Jacobians against central differences over the SE(3) right
// perturbation T * exp(delta) and the landmark, on 1,000 random cases each.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "cairn/backend/landmark_factors_3d.hpp"
#include "cairn/core/so2.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::backend {
namespace {

core::SE3 random_pose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vector3 phi = Vector3(u(rng), u(rng), u(rng)) * 3.0;
  return core::SE3(core::SO3::exp(phi), Vector3(u(rng), u(rng), u(rng)) * 20.0);
}

template <typename F>
Matrix36 numeric_pose_jacobian(F f, const core::SE3& T) {
  constexpr double h = 1e-6;
  Matrix36 J;
  for (int c = 0; c < 6; ++c) {
    core::SE3::Tangent delta = core::SE3::Tangent::Zero();
    delta(c) = h;
    Vector3 d = f(T * core::SE3::exp(delta)) - f(T * core::SE3::exp(-delta));
    d(1) = core::wrap_angle(d(1));
    d(2) = core::wrap_angle(d(2));
    J.col(c) = d / (2 * h);
  }
  return J;
}

template <typename F>
Matrix3 numeric_landmark_jacobian(F f, const Vector3& p) {
  constexpr double h = 1e-6;
  Matrix3 J;
  for (int c = 0; c < 3; ++c) {
    Vector3 plus = p;
    Vector3 minus = p;
    plus(c) += h;
    minus(c) -= h;
    Vector3 d = f(plus) - f(minus);
    d(1) = core::wrap_angle(d(1));
    d(2) = core::wrap_angle(d(2));
    J.col(c) = d / (2 * h);
  }
  return J;
}

template <typename A, typename B>
double relative_error(const A& analytic, const B& numeric) {
  return (analytic - numeric).cwiseAbs().maxCoeff() / (1.0 + numeric.cwiseAbs().maxCoeff());
}

TEST(LandmarkFactors3D, PointJacobiansMatchNumericOn1000RandomCases) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  double worst = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const core::SE3 T = random_pose(rng);
    const Vector3 p = T.translation() + Vector3(u(rng), u(rng), u(rng));
    const Vector3 q_measured(1.0, 2.0, 3.0);
    Matrix36 J_pose;
    Matrix3 J_landmark;
    point_residual_3d(T, p, q_measured, &J_pose, &J_landmark);
    worst = std::max(worst, relative_error(J_pose, numeric_pose_jacobian(
                                                       [&](const core::SE3& X) { return point_residual_3d(X, p, q_measured); }, T)));
    worst = std::max(worst, relative_error(J_landmark, numeric_landmark_jacobian(
                                                           [&](const Vector3& x) { return point_residual_3d(T, x, q_measured); }, p)));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(LandmarkFactors3D, RangeBearingElevationJacobiansMatchNumericOn1000RandomCases) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  double worst = 0.0;
  for (int n = 0; n < 1000;) {
    const core::SE3 T = random_pose(rng);
    const Vector3 p = T.translation() + Vector3(u(rng), u(rng), u(rng));
    const Vector3 q = T.inverse() * p;
    if (q.head<2>().norm() < 0.5) continue;  // near the body z axis the bearing is undefined
    ++n;
    const Vector3 z(5.0, 0.2, -0.1);
    Matrix36 J_pose;
    Matrix3 J_landmark;
    range_bearing_elevation_residual_3d(T, p, z, &J_pose, &J_landmark);
    worst = std::max(worst, relative_error(J_pose, numeric_pose_jacobian(
                                                       [&](const core::SE3& X) { return range_bearing_elevation_residual_3d(X, p, z); }, T)));
    worst = std::max(worst, relative_error(J_landmark, numeric_landmark_jacobian(
                                                           [&](const Vector3& x) { return range_bearing_elevation_residual_3d(T, x, z); }, p)));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(LandmarkFactors3D, KnownValues) {
  // Body at (1, 0, 0) facing +y (yaw 90 degrees); a point 2 m ahead and 2 m up.
  const core::SE3 T(core::SO3::from_rpy(0.0, 0.0, std::numbers::pi / 2), Vector3(1.0, 0.0, 0.0));
  const Vector3 p(1.0, 2.0, 2.0);
  const Vector3 e = range_bearing_elevation_residual_3d(T, p, Vector3::Zero());
  EXPECT_NEAR(e.x(), std::sqrt(8.0), 1e-12);
  EXPECT_NEAR(e.y(), 0.0, 1e-12);
  EXPECT_NEAR(e.z(), std::numbers::pi / 4, 1e-12);
  EXPECT_LT((point_residual_3d(T, p, Vector3(2.0, 0.0, 2.0))).norm(), 1e-12);
}

}  // namespace
}  // namespace cairn::backend
