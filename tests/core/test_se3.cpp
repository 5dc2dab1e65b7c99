// SE3-specific tests: quaternion normalisation through the SE3 constructor, from_matrix and
// matrix3x4, and the translation-first tangent order and Adj layout pinned on known values. The
// group properties are in test_lie_groups.cpp.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/lie_test_utils.hpp"

namespace cairn::core::testing {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

TEST(SE3Test, QuaternionConstructorNormalisesAndKeepsTheTranslation) {
  Rng rng(501);
  WorstCase worst("se3_unit_quaternion_norm_error");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Quaternion q(std::pow(10.0, uniform(rng, -3.0, 3.0)) *
                       random_unit_quaternion(rng).coeffs());
    const Vector3 t = random_translation(rng);
    const SE3 T(q, t);
    ASSERT_EQ(T.translation(), t);
    worst.add(std::abs(T.unit_quaternion().squaredNorm() - 1.0),
              [&] { return to_string(q.coeffs().transpose()); });
    // Same rotation as SO3 gives for the same quaternion, bit for bit.
    ASSERT_EQ(T.unit_quaternion().coeffs(), SO3(q).unit_quaternion().coeffs());
  }
  worst.expect_at_most(4.0 * kEps, kRandomSamples);
}

TEST(SE3Test, FromMatrixRoundTripAndProjection) {
  Rng rng(502);
  WorstCase round_trip("from_matrix_round_trip");
  WorstCase round_trip_3x4("from_matrix3x4_round_trip");
  for (int i = 0; i < kRandomSamples; ++i) {
    const SE3 T = LieTraits<SE3>::random_element(rng);
    const auto d = [&] { return describe<LieTraits<SE3>>(T); };
    round_trip.add(scaled_error(SE3::from_matrix(T.matrix()).matrix(), T.matrix()), d);
    round_trip_3x4.add(scaled_error(SE3::from_matrix3x4(T.matrix3x4()).matrix(), T.matrix()), d);
    ASSERT_EQ(T.matrix3x4(), T.matrix().topRows<3>());
    ASSERT_EQ(T.rotation_matrix(), T.so3().matrix());
    // A rotation block that is not quite orthonormal is projected with SO3::from_matrix; the
    // translation is copied as is.
    Matrix4 M = T.matrix();
    M.topLeftCorner<3, 3>() += random_matrix<3, 3>(rng, 1e-4);
    const SE3 P = SE3::from_matrix(M);
    ASSERT_EQ(P.translation(), T.translation());
    ASSERT_EQ(P.rotation_matrix(), SO3::from_matrix(M.topLeftCorner<3, 3>()).matrix());
    const SE3 P34 = SE3::from_matrix3x4(M.topRows<3>());
    ASSERT_EQ(P34.matrix(), P.matrix());
  }
  round_trip.expect_at_most(1e-14, kRandomSamples);
  round_trip_3x4.expect_at_most(1e-14, kRandomSamples);
}

// log with Jr^-1 at the log (shared J^-1 of SO(3)) against log() and right_jacobian_inverse().
TEST(SE3Test, LogWithRightJacobianInverseMatchesTheSeparateFunctions) {
  Rng rng(409);
  WorstCase log_error("log_with_jacobian_vs_log");
  WorstCase jacobian_error("right_jacobian_inverse_at_log");
  const std::vector<SE3> elements = test_elements<LieTraits<SE3>>(rng);
  for (const SE3& T : elements) {
    SE3::Jacobian J;
    const SE3::Tangent xi = T.log(J);
    const auto d = [&] { return to_string(T.matrix()); };
    log_error.add(scaled_error(xi, T.log()), d);
    jacobian_error.add(scaled_error(J, SE3::right_jacobian_inverse(T.log())), d);
  }
  log_error.expect_at_most(0.0, static_cast<int>(elements.size()));
  jacobian_error.expect_at_most(1e-13, static_cast<int>(elements.size()));
}

TEST(SE3Test, TangentIsTranslationFirst) {
  Vector6 xi;
  xi << 1.0, 2.0, 3.0, 0.0, 0.0, 0.0;
  const SE3 T = SE3::exp(xi);
  EXPECT_EQ(T.translation(), Vector3(1.0, 2.0, 3.0));
  EXPECT_EQ(T.rotation_matrix(), Matrix3::Identity());
  EXPECT_EQ(T.log(), xi);

  xi << 0.0, 0.0, 0.0, 0.1, -0.2, 0.3;
  EXPECT_EQ(SE3::exp(xi).translation(), Vector3::Zero());

  // A screw along its own axis translates by rho: Jl(phi) phi = phi.
  const Vector3 axis = Vector3(1.0, -2.0, 2.0).normalized();
  xi << 0.7 * axis, 2.0 * axis;
  EXPECT_LE((SE3::exp(xi).translation() - 0.7 * axis).norm(), 1e-15);

  // Half a turn about z while moving 1 along x ends at 2/pi along y, as in the plane.
  xi << 1.0, 0.0, 0.0, 0.0, 0.0, kPi;
  EXPECT_LE((SE3::exp(xi).translation() - Vector3(0.0, 2.0 / kPi, 0.0)).norm(), 1e-15);
}

TEST(SE3Test, AdjointLayoutIsTranslationFirst) {
  // Adj = [[R, [t]x R], [0, R]] for tangent (rho, phi).
  Rng rng(503);
  for (int i = 0; i < 100; ++i) {
    const SE3 T = LieTraits<SE3>::random_element(rng);
    const Matrix6 A = T.Adj();
    const Matrix3 R = T.rotation_matrix();
    EXPECT_EQ((A.topLeftCorner<3, 3>()), R);
    EXPECT_EQ((A.bottomRightCorner<3, 3>()), R);
    EXPECT_EQ((A.bottomLeftCorner<3, 3>()), Matrix3::Zero());
    EXPECT_LE((A.topRightCorner<3, 3>() - SO3::hat(T.translation()) * R).norm(), 1e-14);
  }
  // A pure translation moves a rotation's tangent into translation: Adj (0, phi) = (t x phi, phi).
  const SE3 T(SO3(), Vector3(1.0, 2.0, 3.0));
  Vector6 xi;
  xi << 0.0, 0.0, 0.0, 0.0, 0.0, 1.0;
  Vector6 expected;
  expected << 2.0, -1.0, 0.0, 0.0, 0.0, 1.0;
  EXPECT_EQ(T.Adj() * xi, expected);
}

}  // namespace
}  // namespace cairn::core::testing
