// SE2-specific tests: (x, y, theta) kept bit for bit, the translation-first tangent order and
// Adj layout pinned on known values, and from_matrix. The group properties are in
// test_lie_groups.cpp.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "core/lie_test_utils.hpp"

namespace cairn::core::testing {
namespace {

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

TEST(SE2Test, KeepsXYAndThetaBitForBit) {
  Rng rng(301);
  std::vector<double> thetas = {kPi,
                                std::nextafter(kPi, 0.0),
                                std::nextafter(-kPi, 0.0),
                                -kPi + 1e-12,
                                0.0,
                                -0.0,
                                1e-300,
                                kPi / 2.0,
                                -kPi / 2.0};
  for (int i = 0; i < kRandomSamples; ++i) thetas.push_back(uniform(rng, -kPi, kPi));
  for (const double theta : thetas) {
    if (theta == -kPi) continue;  // outside (-pi, pi]; see WrapsThetaOutsideTheRange
    const double x = uniform(rng, -1e3, 1e3);
    const double y = uniform(rng, -1e3, 1e3);
    const SE2 T(x, y, theta);
    ASSERT_EQ(bits(T.angle()), bits(theta)) << std::hexfloat << theta;
    ASSERT_EQ(bits(T.x()), bits(x));
    ASSERT_EQ(bits(T.y()), bits(y));
    // Written as g2o and TORO do (17 significant digits) and read back: the same bits.
    std::ostringstream out;
    out << std::setprecision(17) << T.x() << ' ' << T.y() << ' ' << T.angle();
    std::istringstream in(out.str());
    double x2 = 0.0;
    double y2 = 0.0;
    double theta2 = 0.0;
    in >> x2 >> y2 >> theta2;
    const SE2 T2(x2, y2, theta2);
    ASSERT_EQ(bits(T2.angle()), bits(theta));
    ASSERT_EQ(bits(T2.x()), bits(x));
    ASSERT_EQ(bits(T2.y()), bits(y));
  }
}

TEST(SE2Test, WrapsThetaOutsideTheRange) {
  Rng rng(302);
  std::vector<double> thetas = {-kPi, 3.0 * kPi, -3.0 * kPi, 1e6, -1e6};
  for (int i = 0; i < kRandomSamples; ++i) thetas.push_back(uniform(rng, -50.0, 50.0));
  for (const double theta : thetas) {
    ASSERT_EQ(bits(SE2(1.0, 2.0, theta).angle()), bits(wrap_angle(theta))) << theta;
  }
  EXPECT_EQ(bits(SE2(0.0, 0.0, -kPi).angle()), bits(kPi));
}

TEST(SE2Test, TangentIsTranslationFirst) {
  const SE2 T = SE2::exp(Vector3(1.0, 2.0, 0.0));
  EXPECT_EQ(T.translation(), Vector2(1.0, 2.0));
  EXPECT_EQ(T.angle(), 0.0);
  const SE2 R = SE2::exp(Vector3(0.0, 0.0, 0.5));
  EXPECT_EQ(R.translation(), Vector2::Zero());
  EXPECT_EQ(R.angle(), 0.5);
  EXPECT_EQ(SE2(3.0, 4.0, 0.0).log(), Vector3(3.0, 4.0, 0.0));
  // Half a turn while moving 1 forward along the arc ends 2/pi to the left: t = V(pi) (1, 0)
  // with V(pi) = [[0, -2/pi], [2/pi, 0]].
  const SE2 half_turn = SE2::exp(Vector3(1.0, 0.0, kPi));
  EXPECT_NEAR(half_turn.x(), 0.0, 1e-16);
  EXPECT_NEAR(half_turn.y(), 2.0 / kPi, 1e-15);
  EXPECT_EQ(half_turn.angle(), kPi);
}

TEST(SE2Test, AdjointLayoutIsTranslationFirst) {
  // Adj = [[R, (y, -x)], [0, 1]] for tangent (rho_x, rho_y, theta).
  Matrix3 expected;
  expected << 1.0, 0.0, 2.0,  //
      0.0, 1.0, -1.0,         //
      0.0, 0.0, 1.0;
  EXPECT_EQ(SE2(1.0, 2.0, 0.0).Adj(), expected);
  const SE2 T(1.0, 2.0, 0.3);
  const Matrix3 A = T.Adj();
  EXPECT_EQ((A.topLeftCorner<2, 2>()), T.so2().matrix());
  EXPECT_EQ(A(0, 2), 2.0);
  EXPECT_EQ(A(1, 2), -1.0);
  EXPECT_EQ(A.row(2), Eigen::RowVector3d(0.0, 0.0, 1.0));
}

TEST(SE2Test, FromMatrixRoundTripAndProjection) {
  Rng rng(303);
  WorstCase round_trip("from_matrix_round_trip");
  for (int i = 0; i < kRandomSamples; ++i) {
    const SE2 T = LieTraits<SE2>::random_element(rng);
    const SE2 T2 = SE2::from_matrix(T.matrix());
    round_trip.add(scaled_error(T2.matrix(), T.matrix()),
                   [&] { return describe<LieTraits<SE2>>(T); });
    // A rotation block that is not quite orthonormal is projected with SO2::from_matrix; the
    // translation is copied as is.
    Matrix3 M = T.matrix();
    M.topLeftCorner<2, 2>() += random_matrix<2, 2>(rng, 1e-4);
    const SE2 P = SE2::from_matrix(M);
    ASSERT_EQ(P.translation(), T.translation());
    ASSERT_EQ(bits(P.angle()), bits(SO2::from_matrix(M.topLeftCorner<2, 2>()).angle()));
  }
  round_trip.expect_at_most(1e-15, kRandomSamples);
}

}  // namespace
}  // namespace cairn::core::testing
