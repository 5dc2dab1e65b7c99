// Measurement, inverse-measurement and motion models: analytic Jacobians against central
// differences on 1,000 random cases each, and the model/inverse round trip.

#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>
#include <random>

#include "cairn/core/so2.hpp"
#include "cairn/filter/range_bearing.hpp"

namespace cairn::filter {
namespace {

constexpr double kPi = std::numbers::pi;

template <int Out, int In, typename F>
Eigen::Matrix<double, Out, In> numeric_jacobian(F f, const Eigen::Matrix<double, In, 1>& x, int angle_row) {
  constexpr double h = 1e-6;
  Eigen::Matrix<double, Out, In> J;
  for (int c = 0; c < In; ++c) {
    Eigen::Matrix<double, In, 1> plus = x;
    Eigen::Matrix<double, In, 1> minus = x;
    plus(c) += h;
    minus(c) -= h;
    Eigen::Matrix<double, Out, 1> d = f(plus) - f(minus);
    if (angle_row >= 0) d(angle_row) = core::wrap_angle(d(angle_row));
    J.col(c) = d / (2 * h);
  }
  return J;
}

template <typename A, typename B>
double relative_error(const A& analytic, const B& numeric) {
  return (analytic - numeric).cwiseAbs().maxCoeff() / (1.0 + numeric.cwiseAbs().maxCoeff());
}

struct Random {
  std::mt19937_64 rng{42};
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  PoseVector pose() { return {uniform(-50, 50), uniform(-50, 50), uniform(-kPi, kPi)}; }
};

TEST(RangeBearing, JacobiansMatchNumericOn1000RandomCases) {
  Random random;
  double worst = 0.0;
  for (int n = 0; n < 1000;) {
    const PoseVector pose = random.pose();
    const Vector2 p = pose.head<2>() + Vector2(random.uniform(-15, 15), random.uniform(-15, 15));
    if ((p - pose.head<2>()).norm() < 0.3) continue;
    ++n;
    Matrix23 J_pose;
    Matrix2 J_landmark;
    range_bearing(pose, p, &J_pose, &J_landmark);
    worst = std::max(worst, relative_error(J_pose, numeric_jacobian<2, 3>([&](const Vector3& x) { return range_bearing(x, p); },
                                                                          pose, 1)));
    worst = std::max(worst, relative_error(J_landmark, numeric_jacobian<2, 2>(
                                                           [&](const Vector2& x) { return range_bearing(pose, x); }, p, 1)));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(RangeBearing, InverseJacobiansMatchNumericAndRoundTrip) {
  Random random;
  double worst = 0.0;
  double worst_round_trip = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const PoseVector pose = random.pose();
    const Vector2 z(random.uniform(0.2, 30), random.uniform(-kPi, kPi));
    Matrix23 J_pose;
    Matrix2 J_z;
    const Vector2 p = landmark_from_range_bearing(pose, z, &J_pose, &J_z);
    worst = std::max(worst, relative_error(J_pose, numeric_jacobian<2, 3>(
                                                       [&](const Vector3& x) { return landmark_from_range_bearing(x, z); }, pose, -1)));
    worst = std::max(worst, relative_error(J_z, numeric_jacobian<2, 2>(
                                                    [&](const Vector2& x) { return landmark_from_range_bearing(pose, x); }, z, -1)));
    const Vector2 back = range_bearing(pose, p);
    worst_round_trip = std::max({worst_round_trip, std::abs(back.x() - z.x()), std::abs(core::wrap_angle(back.y() - z.y()))});
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worst_round_trip, 1e-9);
}

TEST(MotionModel, ComposeAndBetweenJacobiansMatchNumericAndInvert) {
  Random random;
  double worst = 0.0;
  double worst_round_trip = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const PoseVector a = random.pose();
    const PoseVector b = random.pose();
    const PoseVector u(random.uniform(-3, 3), random.uniform(-3, 3), random.uniform(-kPi, kPi));
    Matrix3 J_a;
    Matrix3 J_u;
    compose(a, u, &J_a, &J_u);
    worst = std::max(worst, relative_error(J_a, numeric_jacobian<3, 3>([&](const Vector3& x) { return compose(x, u); }, a, 2)));
    worst = std::max(worst, relative_error(J_u, numeric_jacobian<3, 3>([&](const Vector3& x) { return compose(a, x); }, u, 2)));
    Matrix3 J_i;
    Matrix3 J_j;
    between(a, b, &J_i, &J_j);
    worst = std::max(worst, relative_error(J_i, numeric_jacobian<3, 3>([&](const Vector3& x) { return between(x, b); }, a, 2)));
    worst = std::max(worst, relative_error(J_j, numeric_jacobian<3, 3>([&](const Vector3& x) { return between(a, x); }, b, 2)));
    const PoseVector b_again = compose(a, between(a, b));
    worst_round_trip = std::max({worst_round_trip, (b_again.head<2>() - b.head<2>()).norm(),
                                 std::abs(core::wrap_angle(b_again.z() - b.z()))});
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worst_round_trip, 1e-9);
}

TEST(RangeBearing, KnownValues) {
  // Landmark 3 m ahead-left at 45 degrees of a robot facing +y from (1, 1).
  const PoseVector pose(1.0, 1.0, kPi / 2);
  const Vector2 z = range_bearing(pose, Vector2(1.0 - 3.0 / std::sqrt(2.0), 1.0 + 3.0 / std::sqrt(2.0)));
  EXPECT_NEAR(z.x(), 3.0, 1e-12);
  EXPECT_NEAR(z.y(), kPi / 4, 1e-12);
  EXPECT_NEAR(innovation(Vector2(1.0, kPi - 0.01), Vector2(1.0, -kPi + 0.01)).y(), -0.02, 1e-12);
}

}  // namespace
}  // namespace cairn::filter
