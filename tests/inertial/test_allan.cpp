// Allan deviation: the O(n) cumulative-sum estimator against the definition computed cluster by
// cluster, the white-noise curve against its closed form N / sqrt(tau), and the fits recovering
// the densities of synthetic white noise plus a bias random walk (seeded std::mt19937).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "cairn/inertial/allan_deviation.hpp"

namespace cairn::inertial {
namespace {

constexpr double kRateHz = 200.0;
constexpr double kPeriodS = 1.0 / kRateHz;

// Discrete white noise of density N at rate f has standard deviation N sqrt(f); a random walk of
// density K steps by K sqrt(dt) per sample (Kalibr's IMU noise model, as imu_types.hpp says).
std::vector<double> white_plus_walk(std::size_t count, double N, double K, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> values(count);
  const double white_sigma = N * std::sqrt(kRateHz), walk_sigma = K * std::sqrt(kPeriodS);
  double bias = 0.0;
  for (double& v : values) {
    v = bias + white_sigma * normal(rng);
    bias += walk_sigma * normal(rng);
  }
  return values;
}

// The overlapping Allan variance by its definition: half the mean squared difference of
// adjacent averages of m samples, over every start (IEEE Std 952-1997, Annex C).
double allan_variance_by_definition(const std::vector<double>& y, std::size_t m) {
  double sum = 0.0;
  std::size_t terms = 0;
  for (std::size_t k = 0; k + 2 * m <= y.size(); ++k) {
    double first = 0.0, second = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      first += y[k + i];
      second += y[k + m + i];
    }
    const double d = (second - first) / static_cast<double>(m);
    sum += d * d;
    ++terms;
  }
  return sum / (2.0 * static_cast<double>(terms));
}

TEST(AllanDeviation, CumulativeSumsMatchTheDefinition) {
  // An offset of 9.8 (an accelerometer's gravity) must not cost precision.
  std::vector<double> y = white_plus_walk(3000, 2e-3, 3e-3, 7);
  for (double& v : y) v += 9.8;
  const auto curve = allan_deviation(y, kPeriodS, AllanOptions{});
  ASSERT_FALSE(curve.empty());
  EXPECT_EQ(curve.front().cluster_samples, 1u);
  EXPECT_LE(curve.back().cluster_samples, (y.size() - 1) / 2);
  for (const AllanPoint& p : curve) {
    const double expected = std::sqrt(allan_variance_by_definition(y, p.cluster_samples));
    EXPECT_NEAR(p.deviation, expected, 1e-9 * expected) << "m = " << p.cluster_samples;
    EXPECT_DOUBLE_EQ(p.tau_s, static_cast<double>(p.cluster_samples) * kPeriodS);
  }
  // Log spacing, 10 per decade: m = 1, 2, 3, 4, 5, 6, 8, 10, 13, 16, 20, 25, 32, 40, 50, 63, ...
  EXPECT_EQ(curve[6].cluster_samples, 8u);
  EXPECT_EQ(curve[15].cluster_samples, 63u);
  EXPECT_TRUE(allan_deviation({1.0, 2.0}, kPeriodS, AllanOptions{}).empty());
  AllanOptions short_taus;
  short_taus.max_tau_s = 0.1;
  EXPECT_EQ(allan_deviation(y, kPeriodS, short_taus).back().cluster_samples, 20u);
}

TEST(AllanDeviation, WhiteNoiseFollowsItsClosedForm) {
  // One hour of white noise of density N at 200 Hz: sigma(tau) = N / sqrt(tau) exactly in
  // expectation (for averages of m samples, sigma^2 = N^2 f / m = N^2 / tau). Each estimate must
  // be within 4 of its relative standard errors of that.
  const double N = 1.7e-4;
  const auto y = white_plus_walk(720'000, N, 0.0, 42);
  const auto curve = allan_deviation(y, kPeriodS, AllanOptions{});
  double worst_sigmas = 0.0;
  for (const AllanPoint& p : curve) {
    const double expected = N / std::sqrt(p.tau_s);
    const double sigmas = std::abs(p.deviation / expected - 1.0) / p.relative_error;
    worst_sigmas = std::max(worst_sigmas, sigmas);
    EXPECT_LT(sigmas, 4.0) << "tau " << p.tau_s << " s: " << p.deviation << " vs " << expected;
  }
  const AllanFit fit = fit_allan_noise(curve);
  ASSERT_TRUE(fit.white_noise_found);
  EXPECT_NEAR(fit.white_noise_density, N, 0.01 * N);
  std::cout << "white noise only: N fitted " << fit.white_noise_density << " (true " << N << ", "
            << fit.white_noise_points << " points), worst point " << worst_sigmas << " standard errors\n";
}

TEST(AllanDeviation, FitsRecoverWhiteNoiseAndRandomWalk) {
  // Two hours at 200 Hz of white noise N plus a bias random walk K; the two lines cross at
  // tau = sqrt(3) N / K = 5.8 s, so the -1/2 line spans 5 ms..~1 s and the +1/2 line ~60 s..1 h.
  const double N = 1e-3, K = 3e-4;
  const auto y = white_plus_walk(1'440'000, N, K, 2024);
  const auto curve = allan_deviation(y, kPeriodS, AllanOptions{});
  const AllanFit fit = fit_allan_noise(curve);
  ASSERT_TRUE(fit.white_noise_found);
  ASSERT_TRUE(fit.random_walk_found);
  std::cout << "white + walk: N fitted " << fit.white_noise_density << " (true " << N << ", " << fit.white_noise_points
            << " points), K fitted " << fit.random_walk << " (true " << K << ", " << fit.random_walk_points
            << " points), B " << fit.bias_instability << " at " << fit.bias_instability_tau_s << " s\n";
  // Measured over seeds 1..12 of this set-up: N within 0.26 %, K from -29 % to +12 % (a random
  // walk's long-tau points rest on few clusters; one realisation in twelve lies 20-30 % low over
  // the whole +1/2 region). Hence 1 % and 30 %.
  EXPECT_NEAR(fit.white_noise_density, N, 0.01 * N);
  EXPECT_NEAR(fit.random_walk, K, 0.30 * K);
  // No flicker noise here: the curve's bottom is where the two lines cross, sigma_min =
  // sqrt(2 N K / sqrt(3)) (the minimum of N^2 / tau + K^2 tau / 3), so "B" is that / 0.664.
  const double bottom = std::sqrt(2.0 * N * K / std::sqrt(3.0));
  EXPECT_NEAR(fit.bias_instability * std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi), bottom, 0.1 * bottom);
}

TEST(AllanDeviation, ImuReportAndNoiseModel) {
  // Six axes of 20 minutes each: the report's fits per axis and the noise model from them.
  const double N_gyro = 1.6968e-4, N_accel = 2e-3;
  std::vector<ImuSample> samples(240'000);
  std::array<std::vector<double>, 6> axes;
  for (int a = 0; a < 6; ++a) axes[static_cast<std::size_t>(a)] = white_plus_walk(samples.size(), a < 3 ? N_gyro : N_accel, 0.0, 100u + static_cast<unsigned>(a));
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i].stamp = core::Timestamp::from_nanoseconds(static_cast<std::int64_t>(i) * 5'000'000);
    samples[i].gyro_rad_s = Vector3(axes[0][i], axes[1][i], axes[2][i]);
    samples[i].accel_mps2 = Vector3(axes[3][i], axes[4][i], 9.8 + axes[5][i]);
  }
  const ImuAllanReport report = imu_allan_deviation(samples, AllanOptions{});
  EXPECT_DOUBLE_EQ(report.sample_period_s, kPeriodS);
  const ImuNoise fallback;
  const ImuNoise noise = noise_from_allan(report, fallback);
  EXPECT_NEAR(noise.gyro_noise_density, N_gyro, 0.02 * N_gyro);
  EXPECT_NEAR(noise.accel_noise_density, N_accel, 0.02 * N_accel);
  for (const AllanFit& fit : report.gyro_fit) EXPECT_FALSE(fit.random_walk_found && fit.random_walk > 1e-5);
  EXPECT_NE(to_json(report).dump().find("\"white_noise_density\""), std::string::npos);
}

TEST(AllanOptions, Validation) {
  AllanOptions options;
  EXPECT_TRUE(options.is_valid(nullptr));
  options.points_per_decade = 0;
  options.max_tau_s = -1.0;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  EXPECT_NE(why.find("points_per_decade"), std::string::npos);
  EXPECT_NE(why.find("max_tau_s"), std::string::npos);
}

}  // namespace
}  // namespace cairn::inertial
