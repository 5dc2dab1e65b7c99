// SO2-specific tests: angle wrapping (range, idempotence, pi kept exactly), the stored angle kept
// bit for bit, and the nearest-rotation projection. The group properties are in
// test_lie_groups.cpp.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/lie_test_utils.hpp"

namespace cairn::core::testing {
namespace {

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

/// Angles inside (-pi, pi] that sit on or next to the edges of the range.
std::vector<double> edge_angles_in_range() {
  return {kPi,
          std::nextafter(kPi, 0.0),
          std::nextafter(-kPi, 0.0),
          -kPi + 1e-12,
          0.0,
          -0.0,
          std::numeric_limits<double>::denorm_min(),
          -std::numeric_limits<double>::min(),
          1e-300,
          kPi / 2.0,
          -kPi / 2.0};
}

TEST(WrapAngle, KeepsEveryAngleInRangeBitForBit) {
  Rng rng(201);
  std::vector<double> angles = edge_angles_in_range();
  for (int i = 0; i < kRandomSamples; ++i) angles.push_back(uniform(rng, -kPi, kPi));
  for (const double a : angles) {
    if (a == -kPi) continue;  // uniform() may return the excluded end point
    ASSERT_EQ(bits(wrap_angle(a)), bits(a)) << std::hexfloat << a;
  }
}

TEST(WrapAngle, MapsPiToPiAndMinusPiToPi) {
  EXPECT_EQ(bits(wrap_angle(kPi)), bits(kPi));
  EXPECT_EQ(bits(wrap_angle(-kPi)), bits(kPi));
  EXPECT_EQ(bits(SO2(-kPi).angle()), bits(kPi));
  // One step past the ends wraps to the other end.
  EXPECT_LE(wrap_angle(std::nextafter(kPi, 4.0)), -kPi + 1e-15);
  EXPECT_GT(wrap_angle(std::nextafter(kPi, 4.0)), -kPi);
  EXPECT_GE(wrap_angle(std::nextafter(-kPi, -4.0)), kPi - 1e-15);
}

// For every input: the result lies in (-pi, pi], wrapping it again changes no bit, and it is
// the same direction as the input. std::remainder is exact, but the double 2 pi is 2.4e-16 short
// of 2 pi, so removing k turns turns the direction by k * 2.4e-16: at most 4e-13 for |x| <= 1e4,
// where the direction is checked (to 1e-12).
TEST(WrapAngle, IsIdempotentInRangeAndKeepsTheDirection) {
  Rng rng(202);
  std::vector<double> inputs = {3.0 * kPi,
                                -3.0 * kPi,
                                2.0 * kPi,
                                -2.0 * kPi,
                                1e10,
                                -1e10,
                                1e300,
                                -1e300,
                                std::nextafter(kPi, 4.0),
                                std::nextafter(-kPi, -4.0)};
  for (int k = -100; k <= 100; ++k) inputs.push_back(static_cast<double>(k) * kPi);
  for (int i = 0; i < kRandomSamples; ++i) inputs.push_back(uniform(rng, -1e4, 1e4));
  WorstCase direction("wrap_direction_error");
  for (const double x : inputs) {
    const double y = wrap_angle(x);
    ASSERT_TRUE(y > -kPi && y <= kPi) << std::hexfloat << x << " -> " << y;
    ASSERT_EQ(bits(wrap_angle(y)), bits(y)) << std::hexfloat << x;
    if (std::abs(x) <= 1e4) {
      direction.add(std::abs(std::sin(y) - std::sin(x)) + std::abs(std::cos(y) - std::cos(x)),
                    [&] { return to_string(x); });
    }
  }
  direction.expect_at_most(1e-12, kRandomSamples);
}

TEST(WrapAngle, PropagatesNaN) { EXPECT_TRUE(std::isnan(wrap_angle(std::nan("")))); }

TEST(SO2Test, StoresTheAngleBitForBitAndCachesItsCosineAndSine) {
  Rng rng(203);
  std::vector<double> angles = edge_angles_in_range();
  for (int i = 0; i < kRandomSamples; ++i) angles.push_back(uniform(rng, -kPi, kPi));
  for (const double a : angles) {
    if (a == -kPi) continue;
    const SO2 R(a);
    ASSERT_EQ(bits(R.angle()), bits(a)) << std::hexfloat << a;
    ASSERT_EQ(bits(R.log()), bits(a));
    ASSERT_EQ(bits(SO2::exp(a).angle()), bits(a));
    ASSERT_EQ(bits(R.cos()), bits(std::cos(a)));
    ASSERT_EQ(bits(R.sin()), bits(std::sin(a)));
  }
}

TEST(SO2Test, RotatesCounterClockwise) {
  const SO2 R(kPi / 2.0);
  const Vector2 p = R * Vector2(1.0, 0.0);
  EXPECT_NEAR(p.x(), 0.0, 1e-16);
  EXPECT_NEAR(p.y(), 1.0, 1e-16);
  EXPECT_EQ(SO2::hat(2.0), (Matrix2() << 0.0, -2.0, 2.0, 0.0).finished());
  EXPECT_EQ(SO2::Adj(), 1.0);
}

TEST(SO2Test, FromMatrixOfARotationGivesItsAngle) {
  Rng rng(204);
  WorstCase worst("from_matrix_angle_error");
  for (int i = 0; i < kRandomSamples; ++i) {
    const double a = uniform(rng, -kPi, kPi);
    const double b = SO2::from_matrix(SO2(a).matrix()).angle();
    worst.add(std::abs(std::remainder(b - a, 2.0 * kPi)), [&] { return to_string(a); });
  }
  worst.expect_at_most(2e-15, kRandomSamples);
}

// The nearest rotation R to M in Frobenius norm is the polar factor: R^T M is symmetric with a
// positive trace. Also checked directly against rotations a little either side.
TEST(SO2Test, FromMatrixGivesTheNearestRotation) {
  Rng rng(205);
  WorstCase symmetric("polar_factor_asymmetry");
  int not_nearest = 0;
  for (int i = 0; i < kRandomSamples; ++i) {
    const double noise = std::pow(10.0, uniform(rng, -9.0, -1.0));
    Matrix2 M = SO2(uniform(rng, -kPi, kPi)).matrix();
    for (int k = 0; k < 4; ++k) M(k / 2, k % 2) += noise * uniform(rng, -1.0, 1.0);
    const SO2 R = SO2::from_matrix(M);
    const Matrix2 S = R.matrix().transpose() * M;
    symmetric.add(std::abs(S(0, 1) - S(1, 0)), [&] { return to_string(M); });
    EXPECT_GT(S.trace(), 0.0);
    const double best = (M - R.matrix()).norm();
    for (const double step : {-1e-6, 1e-6}) {
      not_nearest += (M - SO2(R.angle() + step).matrix()).norm() < best ? 1 : 0;
    }
  }
  symmetric.expect_at_most(2e-15, kRandomSamples);
  EXPECT_EQ(not_nearest, 0);
}

}  // namespace
}  // namespace cairn::core::testing
