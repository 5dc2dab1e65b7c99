// Analytic Jacobians of the reprojection factors against central differences through each
// variable's manifold (x [+] h e_k), on 1,000+ random configurations per factor.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "cairn/backend/reprojection_factors.hpp"
#include "factor_jacobian_check.hpp"

namespace cairn::backend {
namespace {

using test::jacobian_error;

TEST(ReprojectionFactors, BalJacobiansMatchNumericDerivatives) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    // Cameras as in BAL: rotations up to pi, the point in front (BAL's -z forward) at 2-20 m,
    // f 300-1500 px, small k1, k2; every tenth case with a rotation near zero (the series branch).
    const double angle = trial % 10 == 0 ? 1e-9 * unit(rng) : 3.0 * unit(rng);
    const Eigen::Vector3d axis = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const Eigen::Vector3d w = angle * axis;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(w.norm(), w.norm() > 0 ? w.normalized() : axis).toRotationMatrix();
    const Eigen::Vector3d P(2.0 * unit(rng), 2.0 * unit(rng), -(2.0 + 9.0 * (1.0 + unit(rng))));
    const Eigen::Vector3d t(unit(rng), unit(rng), unit(rng));
    const Eigen::Vector3d X = R.transpose() * (P - t);
    std::vector<double> camera = {w.x(), w.y(), w.z(), t.x(), t.y(), t.z(), 900.0 + 600.0 * unit(rng),
                                  0.1 * unit(rng), 0.01 * unit(rng)};
    std::vector<double> point = {X.x(), X.y(), X.z()};
    const BalReprojectionFactor factor(100.0 * unit(rng), 100.0 * unit(rng));
    worst = std::max(worst, jacobian_error(factor, {camera, point}, {&euclidean_manifold(9), &euclidean_manifold(3)}));
  }
  EXPECT_LT(worst, 1e-5);
}

std::vector<double> random_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
  return {q.x(), q.y(), q.z(), q.w(), 3.0 * unit(rng), 3.0 * unit(rng), 3.0 * unit(rng)};
}

std::vector<double> point_in_front(std::mt19937& rng, const std::vector<double>& pose) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q(pose[3], pose[0], pose[1], pose[2]);
  const Eigen::Vector3d p_camera(2.0 * unit(rng), 2.0 * unit(rng), 3.0 + 2.0 * unit(rng));
  const Eigen::Vector3d p_world = q * p_camera + Eigen::Vector3d(pose[4], pose[5], pose[6]);
  return {p_world.x(), p_world.y(), p_world.z()};
}

TEST(ReprojectionFactors, PinholeAndStereoJacobiansMatchNumericDerivatives) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const PinholeIntrinsics K{718.856, 718.856, 607.19, 185.22};  // KITTI 00's P0
  double worst_mono = 0.0, worst_stereo = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const std::vector<double> pose = random_pose(rng);
    const std::vector<double> point = point_in_front(rng, pose);
    const PinholeReprojectionFactor mono(K, 600.0 + 50.0 * unit(rng), 180.0 + 50.0 * unit(rng));
    const StereoReprojectionFactor stereo(K, 0.537, 600.0, 180.0, 550.0);
    worst_mono = std::max(worst_mono, jacobian_error(mono, {pose, point}, {&se3_manifold(), &euclidean_manifold(3)}));
    worst_stereo =
        std::max(worst_stereo, jacobian_error(stereo, {pose, point}, {&se3_manifold(), &euclidean_manifold(3)}));
  }
  EXPECT_LT(worst_mono, 1e-5);
  EXPECT_LT(worst_stereo, 1e-5);
}

TEST(ReprojectionFactors, BalMatchesTheFormulaOfTheDataReadme) {
  // P = R X + t, p = -P/P.z, r = 1 + k1 |p|^2 + k2 |p|^4, predicted = f r p (BAL's model), by hand:
  // w = 0 (R = I), t = (0, 0, -4), X = (1, 2, 0): P = (1, 2, -4), p = (0.25, 0.5), |p|^2 = 0.3125.
  const std::vector<double> camera = {0.0, 0.0, 0.0, 0.0, 0.0, -4.0, 500.0, 0.1, 0.01};
  const std::vector<double> point = {1.0, 2.0, 0.0};
  const double* values[2] = {camera.data(), point.data()};
  const BalReprojectionFactor factor(10.0, 20.0);
  double residual[2];
  ASSERT_TRUE(factor.evaluate(values, residual, nullptr));
  const double r = 1.0 + 0.1 * 0.3125 + 0.01 * 0.3125 * 0.3125;
  EXPECT_NEAR(residual[0], 500.0 * r * 0.25 - 10.0, 1e-12);
  EXPECT_NEAR(residual[1], 500.0 * r * 0.5 - 20.0, 1e-12);
}

TEST(ReprojectionFactors, PinholeRejectsPointsBehindTheCamera) {
  const std::vector<double> pose = {0, 0, 0, 1, 0, 0, 0};
  const std::vector<double> behind = {0.1, 0.2, -1.0};
  const double* values[2] = {pose.data(), behind.data()};
  double residual[2];
  EXPECT_FALSE(PinholeReprojectionFactor(PinholeIntrinsics{}, 0.0, 0.0).evaluate(values, residual, nullptr));
}

}  // namespace
}  // namespace cairn::backend
