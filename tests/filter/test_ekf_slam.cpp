// EKF-SLAM: the O(n^2) prediction, Joseph-form update and state augmentation against the dense
// textbook formulas written out here (numeric Jacobians, full matrices); refusal of bad
// observations with the state untouched; convergence on a static toy problem.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Dense>

#include "cairn/core/so2.hpp"
#include "cairn/filter/ekf_slam.hpp"
#include "cairn/filter/range_bearing.hpp"

namespace cairn::filter {
namespace {

// An EKF with a pose, three landmarks and a correlated covariance after a few steps.
EkfSlam make_filter() {
  EkfSlam ekf(PoseVector(1.0, -2.0, 0.4), Matrix3(Vector3(0.01, 0.02, 0.003).asDiagonal()));
  ekf.add_landmark(Vector2(4.0, 0.3));
  ekf.add_landmark(Vector2(6.0, -1.2));
  ekf.predict(PoseVector(0.5, 0.05, 0.1), Matrix3(Vector3(1e-3, 5e-4, 2e-4).asDiagonal()));
  ekf.add_landmark(Vector2(3.0, 2.0));
  ekf.update(0, Vector2(3.6, 0.25));
  ekf.predict(PoseVector(0.4, -0.02, -0.05), Matrix3(Vector3(1e-3, 5e-4, 2e-4).asDiagonal()));
  return ekf;
}

// h(x) for landmark i as a function of the whole state, differentiated numerically.
Eigen::MatrixXd numeric_H(const Eigen::VectorXd& x, std::size_t i) {
  const auto h = [&](const Eigen::VectorXd& s) {
    return range_bearing(s.head<3>(), s.segment<2>(3 + 2 * static_cast<Eigen::Index>(i)));
  };
  Eigen::MatrixXd H(2, x.size());
  for (Eigen::Index c = 0; c < x.size(); ++c) {
    Eigen::VectorXd plus = x;
    Eigen::VectorXd minus = x;
    plus(c) += 1e-6;
    minus(c) -= 1e-6;
    Vector2 d = h(plus) - h(minus);
    d.y() = core::wrap_angle(d.y());
    H.col(c) = d / 2e-6;
  }
  return H;
}

TEST(EkfSlam, UpdateEqualsTheDenseJosephForm) {
  EkfSlam ekf = make_filter();
  const Eigen::VectorXd x = ekf.state();
  const Eigen::MatrixXd P = ekf.covariance();
  const Matrix2 R = ekf.measurement_covariance();
  const Vector2 z(5.9, -1.5);
  const std::size_t i = 1;
  // Dense: K = P H^T (H P H^T + R)^-1, x+ = x + K nu, P+ = (I - K H) P (I - K H)^T + K R K^T.
  const Eigen::MatrixXd H = numeric_H(x, i);
  const Eigen::MatrixXd S = H * P * H.transpose() + R;
  const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
  const Vector2 nu = innovation(z, range_bearing(x.head<3>(), x.segment<2>(5)));
  Eigen::VectorXd x_expected = x + K * nu;
  x_expected(2) = core::wrap_angle(x_expected(2));
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(x.size(), x.size());
  const Eigen::MatrixXd P_expected = (I - K * H) * P * (I - K * H).transpose() + K * R * K.transpose();

  ASSERT_TRUE(ekf.update(i, z));
  EXPECT_LT((ekf.state() - x_expected).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((ekf.covariance() - P_expected).cwiseAbs().maxCoeff(), 1e-8 * P.cwiseAbs().maxCoeff());
  EXPECT_TRUE(ekf.covariance().isApprox(ekf.covariance().transpose(), 1e-14));
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(ekf.covariance()).eigenvalues().minCoeff(), 0.0);
}

TEST(EkfSlam, PredictionEqualsTheDenseFormula) {
  EkfSlam ekf = make_filter();
  const Eigen::VectorXd x = ekf.state();
  const Eigen::MatrixXd P = ekf.covariance();
  const PoseVector u(0.7, 0.1, 0.3);
  const Matrix3 Q = Vector3(2e-3, 1e-3, 5e-4).asDiagonal();
  Matrix3 F_pose;
  Matrix3 G;
  compose(x.head<3>(), u, &F_pose, &G);
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(x.size(), x.size());
  F.topLeftCorner<3, 3>() = F_pose;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(x.size(), 3);
  W.topRows<3>() = G;
  const Eigen::MatrixXd P_expected = F * P * F.transpose() + W * Q * W.transpose();
  ekf.predict(u, Q);
  EXPECT_LT((ekf.covariance() - P_expected).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((ekf.pose() - compose(x.head<3>(), u)).norm(), 1e-14);
}

TEST(EkfSlam, AugmentationEqualsTheDenseFormula) {
  EkfSlam ekf = make_filter();
  const Eigen::VectorXd x = ekf.state();
  const Eigen::MatrixXd P = ekf.covariance();
  const Vector2 z(4.5, -0.7);
  // x_aug = (x, g(x_pose, z)); P_aug = J P J^T + J_z R J_z^T with J = [I; G_p 0].
  const Eigen::Index n = x.size();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n + 2, n);
  J.topRows(n) = Eigen::MatrixXd::Identity(n, n);
  for (int c = 0; c < 3; ++c) {
    Vector3 plus = x.head<3>();
    Vector3 minus = x.head<3>();
    plus(c) += 1e-6;
    minus(c) -= 1e-6;
    J.block(n, c, 2, 1) = (landmark_from_range_bearing(plus, z) - landmark_from_range_bearing(minus, z)) / 2e-6;
  }
  Eigen::MatrixXd J_z = Eigen::MatrixXd::Zero(n + 2, 2);
  for (int c = 0; c < 2; ++c) {
    Vector2 plus = z;
    Vector2 minus = z;
    plus(c) += 1e-6;
    minus(c) -= 1e-6;
    J_z.block(n, c, 2, 1) = (landmark_from_range_bearing(x.head<3>(), plus) - landmark_from_range_bearing(x.head<3>(), minus)) / 2e-6;
  }
  const Eigen::MatrixXd P_expected = J * P * J.transpose() + J_z * ekf.measurement_covariance() * J_z.transpose();
  const std::optional<std::size_t> index = ekf.add_landmark(z);
  ASSERT_TRUE(index.has_value());
  EXPECT_EQ(*index, 3u);
  EXPECT_LT((ekf.covariance() - P_expected).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((ekf.landmark(3) - landmark_from_range_bearing(x.head<3>(), z)).norm(), 1e-14);
}

TEST(EkfSlam, BadObservationsAreRefusedAndCountedWithTheStateUntouched) {
  EkfSlam ekf = make_filter();
  const Eigen::VectorXd x = ekf.state();
  const Eigen::MatrixXd P = ekf.covariance();
  const std::size_t rejected = ekf.counters().rejected_invalid;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(ekf.update(0, Vector2(nan, 0.1)));
  EXPECT_FALSE(ekf.update(0, Vector2(-1.0, 0.1)));
  EXPECT_FALSE(ekf.update(0, Vector2(0.0, 0.1)));
  EXPECT_FALSE(ekf.update(0, Vector2(2.0, std::numeric_limits<double>::infinity())));
  EXPECT_FALSE(ekf.update(99, Vector2(2.0, 0.1)));  // no such landmark
  EXPECT_FALSE(ekf.add_landmark(Vector2(nan, 0.0)).has_value());
  EXPECT_FALSE(ekf.add_landmark(Vector2(-3.0, 0.0)).has_value());
  EXPECT_EQ(ekf.counters().rejected_invalid, rejected + 7);
  EXPECT_EQ(ekf.landmark_count(), 3u);
  EXPECT_EQ(ekf.state(), x);  // bit for bit
  EXPECT_EQ(ekf.covariance(), P);
}

TEST(EkfSlam, StaticRobotConvergesOnALandmarkAndCovarianceShrinksAsOneOverN) {
  // Robot fixed (zero motion noise), one landmark observed N times with noise: the landmark's
  // covariance should fall like R / N (in the sensor's frame) and the estimate approach truth.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  const EkfSlamOptions options;
  EkfSlam ekf(PoseVector(0, 0, 0), Matrix3::Zero(), options);
  const Vector2 truth(5.0, 0.0);  // at bearing 0: range along x, bearing across (y = r b)
  const auto observe = [&] {
    return Vector2(5.0 + options.range_sigma_m * n01(rng), options.bearing_sigma_rad * n01(rng));
  };
  ekf.add_landmark(observe());
  for (int k = 1; k < 400; ++k) {
    ekf.predict(PoseVector::Zero(), Matrix3::Zero());
    ASSERT_TRUE(ekf.update(0, observe()));
  }
  const Matrix2 covariance = ekf.landmark_covariance(0);
  EXPECT_NEAR(covariance(0, 0), options.range_sigma_m * options.range_sigma_m / 400, 1e-3 * covariance(0, 0) + 1e-12);
  EXPECT_NEAR(covariance(1, 1), std::pow(5.0 * options.bearing_sigma_rad, 2) / 400, 0.02 * covariance(1, 1));
  EXPECT_LT((ekf.landmark(0) - truth).norm(), 4 * std::sqrt(covariance.trace()));
}

TEST(EkfSlam, FromStateRestoresAFilterThatBehavesTheSame) {
  EkfSlam original = make_filter();
  EkfSlam restored = EkfSlam::from_state(original.state(), original.covariance());
  EXPECT_EQ(restored.landmark_count(), original.landmark_count());
  ASSERT_TRUE(original.update(2, Vector2(2.9, 1.9)));
  ASSERT_TRUE(restored.update(2, Vector2(2.9, 1.9)));
  EXPECT_EQ(restored.state(), original.state());
  EXPECT_EQ(restored.covariance(), original.covariance());
}

}  // namespace
}  // namespace cairn::filter
