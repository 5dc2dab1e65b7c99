// Chi-square CDF and quantiles against published table values (Abramowitz & Stegun Table 26.8;
// any statistics table), not against our own code.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cairn/filter/chi_square.hpp"
#include "cairn/filter/nees.hpp"

namespace cairn::filter {
namespace {

TEST(ChiSquare, QuantilesMatchTables) {
  EXPECT_NEAR(chi_square_quantile(0.95, 2), 5.991464547, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.99, 2), 9.210340372, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.975, 3), 9.348403604, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.025, 3), 0.2157952826, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.95, 1), 3.841458821, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.5, 10), 9.341817766, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.99, 100), 135.807, 1e-3);  // the table gives 3 decimals
  EXPECT_NEAR(chi_square_cdf(2.0, 2), 1.0 - std::exp(-1.0), 1e-12);  // chi^2_2 is exponential(1/2)
}

TEST(ChiSquare, MonteCarloBandIsTheScaledQuantiles) {
  // Table values chi2inv(0.025, 30) = 16.791, chi2inv(0.975, 30) = 46.979: 10 runs of 3 dof.
  const ChiSquareBand band = mean_chi_square_band(3.0, 10, 0.95);
  EXPECT_NEAR(band.lower, 1.6791, 1e-4);
  EXPECT_NEAR(band.upper, 4.6979, 1e-4);
  const ChiSquareBand single = mean_chi_square_band(3.0, 1, 0.95);
  EXPECT_NEAR(single.lower, 0.2157952826, 1e-8);
  EXPECT_NEAR(single.upper, 9.348403604, 1e-8);
}

TEST(Nees, KnownValuesAndSingularCovariance) {
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Identity(2, 2) * 4.0;
  EXPECT_NEAR(*nees(Eigen::Vector2d(2.0, 2.0), covariance), 2.0, 1e-12);
  EXPECT_FALSE(nees(Eigen::Vector2d(1.0, 0.0), Eigen::MatrixXd::Zero(2, 2)).has_value());
  // The angle error wraps: 2 pi - 0.1 away is 0.1 away.
  const Matrix3 pose_covariance = Matrix3::Identity() * 0.01;
  EXPECT_NEAR(*pose_nees(PoseVector(0, 0, 3.1), PoseVector(0, 0, -3.1), pose_covariance),
              std::pow(2 * std::numbers::pi - 6.2, 2) / 0.01, 1e-9);
}

}  // namespace
}  // namespace cairn::filter
