// SO3-specific tests: quaternion normalisation (and its idempotence), from_matrix as the nearest
// rotation, roll-pitch-yaw both ways including gimbal lock, and conventions pinned on known
// values. The group properties are in test_lie_groups.cpp.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <vector>

#include "core/lie_test_utils.hpp"

namespace cairn::core::testing {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

bool same_bits(const Quaternion& a, const Quaternion& b) {
  // Element-wise ==, which also tells 0.0 from -0.0 apart through the sign check.
  for (int i = 0; i < 4; ++i) {
    if (a.coeffs()(i) != b.coeffs()(i) ||
        std::signbit(a.coeffs()(i)) != std::signbit(b.coeffs()(i))) {
      return false;
    }
  }
  return true;
}

/// Gaussian 4-vector times 10^u, u uniform in [-3, 3]: norms from ~1e-3 to ~1e3.
Quaternion random_non_unit_quaternion(Rng& rng) {
  const Quaternion u = random_unit_quaternion(rng);
  return Quaternion(std::pow(10.0, uniform(rng, -3.0, 3.0)) * u.coeffs());
}

Matrix3 rot_x(double a) { return Eigen::AngleAxisd(a, Vector3::UnitX()).toRotationMatrix(); }
Matrix3 rot_y(double a) { return Eigen::AngleAxisd(a, Vector3::UnitY()).toRotationMatrix(); }
Matrix3 rot_z(double a) { return Eigen::AngleAxisd(a, Vector3::UnitZ()).toRotationMatrix(); }

// -- quaternions ------------------------------------------------------------------------------

TEST(SO3Test, QuaternionConstructorNormalises) {
  Rng rng(401);
  WorstCase norm("unit_quaternion_norm_error");
  WorstCase coefficients("unit_quaternion_vs_q_over_norm");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Quaternion q = random_non_unit_quaternion(rng);
    const Quaternion u = SO3(q).unit_quaternion();
    const auto d = [&] { return to_string(q.coeffs().transpose()); };
    norm.add(std::abs(u.squaredNorm() - 1.0), d);
    coefficients.add(scaled_error(u.coeffs(), (q.coeffs() / q.norm()).eval()), d);
  }
  // The constructor's own criterion for "already unit" is |squaredNorm - 1| <= 4 eps.
  norm.expect_at_most(4.0 * kEps, kRandomSamples);
  coefficients.expect_at_most(4.0 * kEps, kRandomSamples);
}

TEST(SO3Test, NormalisationIsIdempotent) {
  Rng rng(402);
  int changed = 0;
  for (int i = 0; i < kRandomSamples; ++i) {
    const Quaternion q = (i % 2 == 0)
                             ? random_non_unit_quaternion(rng)
                             : Quaternion(random_unit_quaternion(rng).coeffs() * (1.0 + 1e-9));
    const SO3 once(q);
    const SO3 twice(once.unit_quaternion());
    changed += same_bits(twice.unit_quaternion(), once.unit_quaternion()) ? 0 : 1;
  }
  EXPECT_EQ(changed, 0) << "of " << kRandomSamples
                        << " normalised quaternions changed when normalised again";
}

TEST(SO3Test, KeepsUnitQuaternionsBitForBit) {
  Rng rng(403);
  const double h = std::sqrt(0.5);
  std::vector<Quaternion> unit = {Quaternion(1.0, 0.0, 0.0, 0.0), Quaternion(-1.0, 0.0, 0.0, 0.0),
                                  Quaternion(0.0, 1.0, 0.0, 0.0), Quaternion(0.0, 0.0, 0.0, -1.0),
                                  Quaternion(0.5, 0.5, 0.5, 0.5), Quaternion(-0.5, 0.5, -0.5, 0.5),
                                  Quaternion(h, h, 0.0, 0.0),     Quaternion(-0.0, 0.0, -1.0, 0.0)};
  for (int i = 0; i < kRandomSamples; ++i) unit.push_back(random_unit_quaternion(rng));
  int kept = 0;
  int eligible = 0;
  for (const Quaternion& q : unit) {
    if (std::abs(q.squaredNorm() - 1.0) > 4.0 * kEps) continue;  // not unit to the documented 4 ulp
    ++eligible;
    // Stored as given, sign included: q and -q stay distinct representations.
    kept += same_bits(SO3(q).unit_quaternion(), q) ? 1 : 0;
  }
  EXPECT_EQ(kept, eligible);
  EXPECT_GE(eligible, kRandomSamples);  // Eigen's normalized() lands within 4 ulp every time
}

TEST(SO3Test, LongProductChainsStayUnit) {
  Rng rng(404);
  SO3 R;
  double worst = 0.0;
  for (int i = 0; i < kRandomSamples; ++i) {
    R = R * SO3::exp(0.1 * random_unit_vector(rng));
    worst = std::max(worst, std::abs(R.unit_quaternion().squaredNorm() - 1.0));
  }
  EXPECT_LE(worst, 4.0 * kEps);
}

TEST(SO3DeathTest, RejectsZeroAndNonFiniteQuaternions) {
  EXPECT_DEATH(SO3(Quaternion(0.0, 0.0, 0.0, 0.0)), "finite, non-zero quaternion");
  EXPECT_DEATH(SO3(Quaternion(std::nan(""), 0.0, 0.0, 1.0)), "finite, non-zero quaternion");
  EXPECT_DEATH(SO3(Quaternion(std::numeric_limits<double>::infinity(), 0.0, 0.0, 0.0)),
               "finite, non-zero quaternion");
}

// -- from_matrix ------------------------------------------------------------------------------

TEST(SO3Test, FromMatrixOfARotationGivesItBack) {
  Rng rng(405);
  WorstCase worst("from_matrix_round_trip");
  for (int i = 0; i < kRandomSamples; ++i) {
    const SO3 R(random_unit_quaternion(rng));
    worst.add(scaled_error(SO3::from_matrix(R.matrix()).matrix(), R.matrix()),
              [&] { return to_string(R.matrix()); });
  }
  worst.expect_at_most(1e-14, kRandomSamples);
}

// The rotation nearest to M in Frobenius norm is the polar factor R, characterised by R^T M
// symmetric positive semi-definite. Also checked directly: no rotation R exp(+-1e-5 e_i) is
// nearer to M.
TEST(SO3Test, FromMatrixGivesTheNearestRotation) {
  Rng rng(406);
  WorstCase orthonormal("from_matrix_orthonormality");
  WorstCase symmetric("polar_factor_asymmetry");
  int not_positive = 0;
  int not_nearest = 0;
  for (int i = 0; i < kRandomSamples; ++i) {
    const double noise = std::pow(10.0, uniform(rng, -9.0, -1.0));
    const Matrix3 M = SO3(random_unit_quaternion(rng)).matrix() + random_matrix<3, 3>(rng, noise);
    const Matrix3 R = SO3::from_matrix(M).matrix();
    const auto d = [&] { return to_string(M); };
    orthonormal.add(
        scaled_error(R.transpose() * R, Matrix3::Identity()) + std::abs(R.determinant() - 1.0), d);
    const Matrix3 S = R.transpose() * M;
    symmetric.add(scaled_error(S, S.transpose()), d);
    const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(0.5 * (S + S.transpose()));
    not_positive += eigen.eigenvalues().minCoeff() > 0.0 ? 0 : 1;
    const double best = (M - R).norm();
    for (int axis = 0; axis < 3; ++axis) {
      for (const double step : {-1e-5, 1e-5}) {
        const Matrix3 other = R * SO3::exp(step * Vector3::Unit(axis)).matrix();
        not_nearest += (M - other).norm() < best ? 1 : 0;
      }
    }
  }
  // ~30 roundings from M through the SVD and the quaternion to R: a few 1e-15.
  orthonormal.expect_at_most(2e-14, kRandomSamples);
  symmetric.expect_at_most(2e-14, kRandomSamples);
  EXPECT_EQ(not_positive, 0);
  EXPECT_EQ(not_nearest, 0);
}

// Far from any rotation too (Gaussian matrices, either sign of the determinant, as a chordal
// relaxation may give): the same two characterisations of the nearest rotation as above.
TEST(SO3Test, FromMatrixGivesTheNearestRotationOfArbitraryMatrices) {
  Rng rng(408);
  WorstCase orthonormal("from_matrix_orthonormality_arbitrary");
  WorstCase symmetric("polar_factor_asymmetry_arbitrary");
  int not_nearest = 0;
  for (int i = 0; i < kRandomSamples; ++i) {
    const Matrix3 M = random_matrix<3, 3>(rng, 1.0);
    const Matrix3 R = SO3::from_matrix(M).matrix();
    const auto d = [&] { return to_string(M); };
    orthonormal.add(scaled_error(R.transpose() * R, Matrix3::Identity()) + std::abs(R.determinant() - 1.0), d);
    const Matrix3 S = R.transpose() * M;
    symmetric.add(scaled_error(S, S.transpose()), d);
    const double best = (M - R).norm();
    for (int axis = 0; axis < 3; ++axis) {
      for (const double step : {-1e-4, 1e-4}) {
        not_nearest += (M - R * SO3::exp(step * Vector3::Unit(axis)).matrix()).norm() < best ? 1 : 0;
      }
    }
  }
  orthonormal.expect_at_most(2e-14, kRandomSamples);
  symmetric.expect_at_most(1e-12, kRandomSamples);
  EXPECT_EQ(not_nearest, 0);
}

TEST(SO3Test, FromMatrixWithNegativeDeterminantFlipsTheWeakestDirection) {
  // M = R diag(1, 0.5, -0.1): singular values 1, 0.5, 0.1 and det < 0. The nearest rotation
  // keeps the two strong directions and flips the weakest one, giving R back.
  Rng rng(407);
  WorstCase worst("from_matrix_negative_determinant");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Matrix3 R = SO3(random_unit_quaternion(rng)).matrix();
    const Matrix3 M = R * Vector3(1.0, 0.5, -0.1).asDiagonal();
    worst.add(scaled_error(SO3::from_matrix(M).matrix(), R), [&] { return to_string(M); });
  }
  worst.expect_at_most(1e-14, kRandomSamples);
}

// -- roll, pitch, yaw -------------------------------------------------------------------------

TEST(SO3Test, FromRpyIsRzRyRx) {
  Rng rng(408);
  WorstCase worst("from_rpy_vs_Rz_Ry_Rx");
  for (int i = 0; i < kRandomSamples; ++i) {
    const double roll = uniform(rng, -kPi, kPi);
    const double pitch = uniform(rng, -kPi / 2.0, kPi / 2.0);
    const double yaw = uniform(rng, -kPi, kPi);
    worst.add(scaled_error(SO3::from_rpy(roll, pitch, yaw).matrix(),
                           (rot_z(yaw) * rot_y(pitch) * rot_x(roll)).eval()),
              [&] { return to_string(Vector3(roll, pitch, yaw).transpose()); });
  }
  // Two different roundings of the same product (quaternions vs matrices): a few ulp.
  worst.expect_at_most(4e-15, kRandomSamples);
}

// Away from gimbal lock the angles come back; their error grows as eps / cos(pitch), so pitch
// stays 1e-3 away from +-pi/2 here (error ~1e-13 at worst).
TEST(SO3Test, RpyRoundTripAwayFromGimbalLock) {
  Rng rng(409);
  WorstCase worst("rpy_round_trip");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Vector3 rpy(uniform(rng, -kPi, kPi), uniform(rng, -kPi / 2.0 + 1e-3, kPi / 2.0 - 1e-3),
                      uniform(rng, -kPi, kPi));
    const Vector3 back = SO3::from_rpy(rpy.x(), rpy.y(), rpy.z()).to_rpy();
    double error = 0.0;
    for (int k = 0; k < 3; ++k) error = std::max(error, std::abs(wrap_angle(back(k) - rpy(k))));
    worst.add(error, [&] { return to_string(rpy.transpose()); });
    ASSERT_TRUE(back.y() >= -kPi / 2.0 && back.y() <= kPi / 2.0);
  }
  worst.expect_at_most(1e-11, kRandomSamples);
}

// Any rotation, gimbal lock or not: from_rpy(to_rpy(R)) is R again.
TEST(SO3Test, ToRpyThenFromRpyReproducesTheRotation) {
  Rng rng(410);
  WorstCase worst("rpy_rotation_round_trip");
  for (int i = 0; i < kRandomSamples; ++i) {
    const SO3 R(random_unit_quaternion(rng));
    const Vector3 rpy = R.to_rpy();
    worst.add(scaled_error(SO3::from_rpy(rpy.x(), rpy.y(), rpy.z()).matrix(), R.matrix()),
              [&] { return to_string(R.matrix()); });
  }
  worst.expect_at_most(1e-9, kRandomSamples);
}

// At pitch = +-pi/2 only yaw - roll (pitch up) or yaw + roll (pitch down) is defined; to_rpy
// puts it all in yaw and returns roll = 0.
TEST(SO3Test, RpyAtGimbalLock) {
  Rng rng(411);
  for (const double pitch : {kPi / 2.0, -kPi / 2.0}) {
    for (int i = 0; i < 1000; ++i) {
      const double roll = uniform(rng, -kPi, kPi);
      const double yaw = uniform(rng, -kPi, kPi);
      const SO3 R = SO3::from_rpy(roll, pitch, yaw);
      const Vector3 rpy = R.to_rpy();
      ASSERT_EQ(rpy.x(), 0.0);
      ASSERT_NEAR(rpy.y(), pitch, 1e-8);
      const double combined = pitch > 0.0 ? yaw - roll : yaw + roll;
      ASSERT_NEAR(std::abs(wrap_angle(rpy.z() - combined)), 0.0, 1e-12) << roll << " " << yaw;
      ASSERT_LE(scaled_error(SO3::from_rpy(rpy.x(), rpy.y(), rpy.z()).matrix(), R.matrix()), 1e-12);
    }
  }
}

// -- conventions ------------------------------------------------------------------------------

TEST(SO3Test, ConventionsOnKnownValues) {
  // Active, right-handed: a quarter turn about z takes x to y.
  const Vector3 y = SO3::exp(Vector3(0.0, 0.0, kPi / 2.0)) * Vector3::UnitX();
  EXPECT_LE((y - Vector3::UnitY()).norm(), 1e-15);
  // Quaternion constructor takes w first.
  const SO3 Rz(Quaternion(std::cos(0.25), 0.0, 0.0, std::sin(0.25)));
  EXPECT_LE((Rz.log() - Vector3(0.0, 0.0, 0.5)).norm(), 1e-15);
  // hat(a) b = a x b; Adj = R.
  Rng rng(412);
  for (int i = 0; i < 100; ++i) {
    const Vector3 a = random_translation(rng);
    const Vector3 b = random_translation(rng);
    EXPECT_LE((SO3::hat(a) * b - a.cross(b)).norm(), 1e-13);
    const SO3 R(random_unit_quaternion(rng));
    EXPECT_EQ(R.Adj(), R.matrix());
  }
}

TEST(SO3Test, AngleIsTheNormOfLogInZeroToPi) {
  Rng rng(413);
  WorstCase worst("angle_vs_log_norm");
  for (const SO3& R : test_elements<LieTraits<SO3>>(rng)) {
    const double angle = R.angle();
    ASSERT_TRUE(angle >= 0.0 && angle <= kPi) << angle;
    worst.add(std::abs(angle - R.log().norm()), [&] { return to_string(R.matrix()); });
  }
  // Both are ~pi at most and computed along different paths: a few ulp of pi.
  worst.expect_at_most(8.0 * kEps, kRandomSamples);
}

}  // namespace
}  // namespace cairn::core::testing
