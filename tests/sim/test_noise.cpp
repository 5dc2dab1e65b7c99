// Noise statistics against the documented models. Tolerances: with N independent samples the
// sample mean has standard error sigma / sqrt(N) and the sample variance (Gaussian data)
// sigma^2 sqrt(2 / (N - 1)); a proportion p has sqrt(p (1 - p) / N). Every check allows 5
// standard errors, so a correct implementation fails with probability < 1e-6 per check; the
// seeds are fixed, so the tests are deterministic anyway.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "cairn/sim/landmark_sensor.hpp"
#include "cairn/sim/lidar.hpp"
#include "cairn/sim/odometry.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/ray_cast.hpp"

namespace cairn::sim {
namespace {

struct Moments {
  double mean = 0.0;
  double variance = 0.0;
  std::size_t n = 0;
};

Moments moments(const std::vector<double>& x) {
  Moments m;
  m.n = x.size();
  for (double v : x) m.mean += v;
  m.mean /= static_cast<double>(m.n);
  for (double v : x) m.variance += (v - m.mean) * (v - m.mean);
  m.variance /= static_cast<double>(m.n - 1);
  return m;
}

/// Checks mean and variance of Gaussian-like samples against (mu, sigma^2), 5 standard errors.
void expect_moments(const std::vector<double>& samples, double mu, double sigma, const char* what) {
  const Moments m = moments(samples);
  const double n = static_cast<double>(m.n);
  EXPECT_NEAR(m.mean, mu, 5.0 * sigma / std::sqrt(n)) << what << ": mean";
  EXPECT_NEAR(m.variance, sigma * sigma, 5.0 * sigma * sigma * std::sqrt(2.0 / (n - 1))) << what << ": variance";
}

void expect_proportion(std::size_t hits, std::size_t n, double p, const char* what) {
  const double N = static_cast<double>(n);
  EXPECT_NEAR(static_cast<double>(hits) / N, p, 5.0 * std::sqrt(p * (1 - p) / N)) << what;
}

constexpr std::size_t kSamples = 200000;

TEST(Random, UniformIsTheTop53BitsOfTheStandardEngine) {
  // std::mt19937_64's output is fixed by the C++ standard, so this pins uniform() everywhere.
  std::mt19937_64 reference(12345);
  Random random(12345);
  for (int i = 0; i < 1000; ++i) {
    EXPECT_EQ(random.uniform(), std::ldexp(static_cast<double>(reference() >> 11), -53));
  }
}

TEST(Random, GaussianHasZeroMeanUnitVarianceAndNormalTails) {
  Random random(7);
  std::vector<double> x(kSamples);
  std::size_t beyond_two_sigma = 0;
  for (auto& v : x) {
    v = random.gaussian();
    beyond_two_sigma += std::abs(v) > 2.0 ? 1 : 0;
  }
  expect_moments(x, 0.0, 1.0, "N(0,1)");
  // P(|Z| > 2) = erfc(2 / sqrt 2) = 0.0455.
  expect_proportion(beyond_two_sigma, kSamples, std::erfc(std::numbers::sqrt2), "P(|Z| > 2)");
}

TEST(Random, UniformMeanAndVariance) {
  Random random(8);
  std::vector<double> x(kSamples);
  for (auto& v : x) v = random.uniform();
  const Moments m = moments(x);
  EXPECT_NEAR(m.mean, 0.5, 5.0 * std::sqrt(1.0 / 12.0 / kSamples));
  // Standard error of the sample variance: sqrt((mu4 - sigma^4) / N), mu4 = 1/80 for U(0, 1).
  EXPECT_NEAR(m.variance, 1.0 / 12.0, 5.0 * std::sqrt((1.0 / 80.0 - 1.0 / 144.0) / kSamples));
}

TEST(Random, IndexIsUniform) {
  Random random(9);
  std::vector<std::size_t> counts(7, 0);
  for (std::size_t i = 0; i < kSamples; ++i) ++counts[random.index(7)];
  for (std::size_t c : counts) expect_proportion(c, kSamples, 1.0 / 7.0, "index(7)");
}

TEST(LidarNoise, RangeNoiseAndDropoutsHaveTheStatedStatistics) {
  LidarOptions options;
  options.range_sigma_m = 0.05;
  options.dropout_probability = 0.1;
  options.range_decimals = -1;
  options.max_range_m = 30.0;
  const std::vector<double> ideal(1000, 5.0);
  Random random(3);
  std::vector<double> errors;
  std::size_t dropouts = 0;
  for (int scan = 0; scan < 200; ++scan) {
    for (double r : add_scan_noise(ideal, options, random)) {
      if (r == options.max_range_m) {
        ++dropouts;
      } else {
        errors.push_back(r - 5.0);
      }
    }
  }
  expect_proportion(dropouts, 200000, 0.1, "dropout fraction");
  expect_moments(errors, 0.0, 0.05, "range error");
}

TEST(LidarNoise, MissesStayAtMaxRangeAndRoundingIsToTheMillimetre) {
  LidarOptions options;
  options.range_sigma_m = 0.2;
  options.dropout_probability = 0.0;
  options.range_decimals = 3;
  const std::vector<double> ideal = {options.max_range_m, 1.23456789, 29.99};
  Random random(4);
  for (int i = 0; i < 1000; ++i) {
    const auto r = add_scan_noise(ideal, options, random);
    EXPECT_EQ(r[0], options.max_range_m);
    EXPECT_EQ(r[1], std::round(r[1] * 1000.0) / 1000.0);
    EXPECT_LE(r[2], options.max_range_m);  // noise never pushes past max range
  }
}

TEST(OdometryNoise, IncrementErrorsHaveTheStatedMeanAndVariance) {
  OdometryNoise noise = OdometryNoise::none();
  noise.forward_sigma_m_per_sqrt_m = 0.03;
  noise.lateral_sigma_m_per_sqrt_m = 0.01;
  noise.yaw_sigma_rad_per_sqrt_rad = 0.04;
  noise.yaw_sigma_rad_per_sqrt_m = 0.02;
  noise.scale_error = 0.02;
  noise.yaw_scale_error = -0.01;
  noise.yaw_bias_rad_per_m = 0.003;
  WheelOdometry sensor(noise, 5);
  const double dx = 0.1;
  const double dtheta = 0.05;
  const core::SE2 truth(dx, 0.0, dtheta);
  std::vector<double> ex, ey, et;
  for (std::size_t i = 0; i < kSamples; ++i) {
    const core::SE2 z = sensor.measure(truth, 0.1);
    ex.push_back(z.x());
    ey.push_back(z.y());
    et.push_back(z.angle());
  }
  // File comment of odometry.hpp: d = 0.1, a = 0.05.
  expect_moments(ex, 1.02 * dx, 0.03 * std::sqrt(dx), "forward");
  expect_moments(ey, 0.0, 0.01 * std::sqrt(dx), "lateral");
  expect_moments(et, 0.99 * dtheta + 0.003 * dx, std::sqrt(0.04 * 0.04 * dtheta + 0.02 * 0.02 * dx), "yaw");
}

TEST(OdometryNoise, SlipEventsHaveTheStatedRateAndSize) {
  // Zero duration: every slip lasts exactly one step, so steps are independent Bernoulli trials
  // with p = 1 - exp(-rate dt), and the excess during a slip is U(0, max).
  OdometryNoise noise = OdometryNoise::none();
  noise.slip_rate_per_s = 2.0;
  noise.slip_duration_s = 0.0;
  noise.slip_max_excess = 0.3;
  WheelOdometry sensor(noise, 6);
  const double dt = 0.05;
  const core::SE2 truth(0.1, 0.0, 0.0);
  std::vector<double> excess;
  for (std::size_t i = 0; i < kSamples; ++i) {
    const double e = sensor.measure(truth, dt).x() / 0.1 - 1.0;
    if (e > 0.0) excess.push_back(e);
  }
  const double p = 1.0 - std::exp(-2.0 * dt);
  expect_proportion(sensor.slip_events(), kSamples, p, "slip events");
  EXPECT_EQ(excess.size(), sensor.slip_events());
  const Moments m = moments(excess);
  const double sigma = 0.3 / std::sqrt(12.0);
  EXPECT_NEAR(m.mean, 0.15, 5.0 * sigma / std::sqrt(static_cast<double>(m.n)));
}

TEST(LandmarkNoise, RangeBearingStatisticsAndDetectionRate) {
  World world;
  world.landmarks.push_back({17, {3.0, 4.0}});
  RangeBearingOptions options;
  options.range_sigma_m = 0.1;
  options.bearing_sigma_rad = 0.02;
  options.detection_probability = 0.8;
  Random random(10);
  std::vector<double> ranges, bearings;
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (const auto& o : observe_landmarks(world, core::SE2(), core::Timestamp(), options, random)) {
      EXPECT_EQ(o.landmark_id, 17);
      ranges.push_back(o.range_m);
      bearings.push_back(o.bearing_rad);
    }
  }
  expect_proportion(ranges.size(), kSamples, 0.8, "detections");
  expect_moments(ranges, 5.0, 0.1, "range");
  expect_moments(bearings, std::atan2(4.0, 3.0), 0.02, "bearing");
}

TEST(LandmarkSensor, RangeFieldOfViewAndOcclusion) {
  World world;
  world.landmarks.push_back({0, {5.0, 0.0}});    // ahead, visible
  world.landmarks.push_back({1, {-5.0, 0.0}});   // behind: outside a 180 degree view
  world.landmarks.push_back({2, {0.0, 20.0}});   // too far
  world.landmarks.push_back({3, {0.0, -5.0}});   // at the edge of view, behind a wall
  world.add_wall({-1, -3}, {1, -3});
  world.circles.push_back({{5.0, 0.0}, 0.2});    // the post of landmark 0 does not hide it
  RangeBearingOptions options;
  options.field_of_view_rad = std::numbers::pi;
  options.detection_probability = 1.0;
  Random random(11);
  const auto seen = observe_landmarks(world, core::SE2(), core::Timestamp(), options, random);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].landmark_id, 0);
}

}  // namespace
}  // namespace cairn::sim
