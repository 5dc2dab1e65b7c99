// Tests of the simulated GNSS receiver (sim/gnss_receiver): rate, dropout windows, the lever arm,
// the noise's statistics, the outliers' fraction and size, and that the chi-square gate at the
// true poses flags exactly the simulated jumps.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/gnss/gnss_outliers.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/sim/gnss_receiver.hpp"

namespace cairn::sim {
namespace {

// A 300 s drive at 100 Hz around a circle of radius 50 m, turning at the rate that keeps the
// body's x axis tangent (yaw = omega t + pi/2).
struct Drive {
  std::vector<core::Timestamp> stamps;
  std::vector<core::SE3> poses;
};

Drive circle_drive() {
  Drive drive;
  const double omega = 0.02;  // rad/s: 1 m/s on r = 50 m
  for (int i = 0; i <= 30000; ++i) {
    const double t_s = 0.01 * i;
    drive.stamps.push_back(core::Timestamp::from_nanoseconds(1'000'000'000'000LL + 10'000'000LL * i));
    drive.poses.emplace_back(core::SO3::exp(Vector3(0.0, 0.0, omega * t_s + std::numbers::pi / 2.0)),
                             Vector3(50.0 * std::cos(omega * t_s), 50.0 * std::sin(omega * t_s), 0.0));
  }
  return drive;
}

TEST(GnssReceiver, RateDropoutAndLeverArmWithoutNoise) {
  const Drive drive = circle_drive();
  GnssReceiverOptions options;
  options.sigma_horizontal_m = 0.0;
  options.sigma_vertical_m = 0.0;
  options.report_covariance = false;
  options.lever_arm_body_m = Vector3(0.5, 0.0, 1.2);
  options.dropouts_s = {{100.0, 160.0}};
  ASSERT_TRUE(options.is_valid(nullptr));
  const SimulatedGnss gnss = simulate_gnss_receiver(drive.stamps, drive.poses, options);
  // 300 s at 5 Hz: epochs 0, 0.2, ..., 300 s = 1501; [100, 160) holds 300 of them.
  EXPECT_EQ(gnss.fixes.size(), 1201u);
  EXPECT_EQ(gnss.dropped_in_dropouts, 300u);
  const gnss::LocalFrame frame(options.origin);
  for (std::size_t i = 0; i < gnss.fixes.size(); ++i) {
    const double t_s = static_cast<double>(gnss.fixes[i].stamp.nanoseconds() - drive.stamps[0].nanoseconds()) * 1e-9;
    EXPECT_FALSE(t_s >= 100.0 && t_s < 160.0);
    // The antenna by hand: the body centre on the circle, x forward (tangent), y towards the centre.
    const double angle = 0.02 * t_s;
    const Vector3 centre(50.0 * std::cos(angle), 50.0 * std::sin(angle), 0.0);
    const Vector3 forward(-std::sin(angle), std::cos(angle), 0.0);
    const Vector3 antenna = centre + 0.5 * forward + Vector3(0.0, 0.0, 1.2);
    ASSERT_LT((gnss.p_enu_true_m[i] - antenna).norm(), 1e-6) << "fix " << i;
    ASSERT_LT((frame.forward(gnss.fixes[i]) - antenna).norm(), 1e-6) << "fix " << i;  // lat/lon/alt round trip
    EXPECT_FALSE(gnss.fixes[i].covariance_known);
  }
}

TEST(GnssReceiver, NoiseOutliersAndTheirGate) {
  const Drive drive = circle_drive();
  GnssReceiverOptions options;
  options.rate_hz = 10.0;
  options.sigma_horizontal_m = 0.5;
  options.sigma_vertical_m = 1.0;
  options.outlier_fraction = 0.05;
  options.dropouts_s = {{120.0, 180.0}};
  options.seed = 38;
  const SimulatedGnss gnss = simulate_gnss_receiver(drive.stamps, drive.poses, options);
  ASSERT_EQ(gnss.fixes.size(), 2401u);  // 3001 epochs, 600 in the dropout
  std::size_t outliers = 0;
  double sum_h2 = 0.0, sum_v2 = 0.0, good = 0.0;
  for (std::size_t i = 0; i < gnss.fixes.size(); ++i) {
    const Vector3 e = gnss.p_enu_measured_m[i] - gnss.p_enu_true_m[i];
    if (gnss.outlier[i]) {
      ++outliers;
      EXPECT_GT(e.norm(), 10.0 - 5.0);
      EXPECT_LT(e.norm(), 50.0 + 5.0);
      continue;
    }
    sum_h2 += e.head<2>().squaredNorm();
    sum_v2 += e.z() * e.z();
    good += 1.0;
  }
  // 5 % of 2401 = 120, binomial sd 10.7.
  EXPECT_NEAR(static_cast<double>(outliers), 120.0, 40.0);
  // Sample sigmas within 5 % (the relative sd of a sample sigma over ~2300 values is ~1.5 %).
  EXPECT_NEAR(std::sqrt(sum_h2 / (2.0 * good)), 0.5, 0.025);
  EXPECT_NEAR(std::sqrt(sum_v2 / good), 1.0, 0.05);
  ASSERT_TRUE(gnss.fixes[0].covariance_known);
  EXPECT_DOUBLE_EQ(gnss.fixes[0].covariance_enu_m2(2, 2), 1.0);

  // At the true poses, the 0.999 gate flags every jump and about 0.1 % of the good fixes.
  std::vector<core::SE3> truth;
  for (const Vector3& p : gnss.p_enu_true_m) truth.emplace_back(core::SO3(), p);
  const gnss::GnssOutlierReport report = gnss::gnss_outlier_report(
      gnss.fixes, truth, gnss::LocalFrame(options.origin), gnss::GnssFactorOptions{}, gnss::GnssOutlierOptions{});
  std::size_t caught = 0, false_alarms = 0;
  for (std::size_t i = 0; i < gnss.fixes.size(); ++i) {
    if (report.fixes[i].outlier) (gnss.outlier[i] ? caught : false_alarms)++;
  }
  EXPECT_EQ(caught, outliers);
  EXPECT_LE(false_alarms, 8u);
  ASSERT_EQ(report.dropouts.size(), 1u);
  EXPECT_NEAR(report.dropouts[0].duration_s, 60.1, 1e-6);  // last fix at 119.9 s, next at 180.0 s
}

TEST(GnssReceiver, OptionsReportEveryProblem) {
  GnssReceiverOptions options;
  options.rate_hz = 0.0;
  options.outlier_fraction = 1.5;
  options.dropouts_s = {{10.0, 5.0}};
  options.origin.latitude_deg = 100.0;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  for (const char* word : {"rate_hz", "outlier_fraction", "dropout", "latitude"}) {
    EXPECT_NE(why.find(word), std::string::npos) << why;
  }
}

}  // namespace
}  // namespace cairn::sim
