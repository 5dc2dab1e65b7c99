#include "cairn/inertial/allan_deviation.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"

namespace cairn::inertial {
namespace {

// sigma(tau) at the bottom of the bias-instability region is sqrt(2 ln 2 / pi) B = 0.664 B
// (IEEE Std 952-1997, Annex C, the bias-instability term; El-Sheimy et al. 2008, the same).
const double kBiasInstabilityFactor = std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi);
// A point belongs to a slope's line when its local log-log slope is within this of it.
constexpr double kSlopeTolerance = 0.1;
// Local slopes are least-squares slopes over +-this many decades around each point: neighbouring
// points alone give slopes too noisy at long cluster times.
constexpr double kSlopeHalfWindowDecades = 0.25;
// Points resting on fewer clusters than this relative error allows are left out of the fits.
constexpr double kMaxFitRelativeError = 0.5;

std::vector<std::size_t> cluster_sizes(std::size_t largest, int per_decade) {
  std::vector<std::size_t> sizes;
  for (int j = 0;; ++j) {
    const double m = std::round(std::pow(10.0, static_cast<double>(j) / per_decade));
    if (m > static_cast<double>(largest)) break;
    const auto size = static_cast<std::size_t>(m);
    if (sizes.empty() || size != sizes.back()) sizes.push_back(size);
  }
  return sizes;
}

// Least-squares slope of log sigma against log tau over the points within the window.
std::vector<double> local_slopes(const std::vector<AllanPoint>& curve) {
  std::vector<double> slopes(curve.size(), std::nan(""));
  for (std::size_t j = 0; j < curve.size(); ++j) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0, count = 0;
    for (const AllanPoint& p : curve) {
      const double x = std::log10(p.tau_s), y = std::log10(p.deviation);
      if (std::abs(x - std::log10(curve[j].tau_s)) > kSlopeHalfWindowDecades || !std::isfinite(y)) continue;
      sx += x, sy += y, sxx += x * x, sxy += x * y, count += 1;
    }
    const double denominator = count * sxx - sx * sx;
    if (count >= 3 && denominator > 0.0) slopes[j] = (count * sxy - sx * sy) / denominator;
  }
  return slopes;
}

// The line of slope `slope` through the selected points, read at tau = tau_read_s: the weighted
// mean of log sigma - slope log(tau / tau_read) with weights 1 / relative_error^2.
struct LineFit {
  double value = 0.0;
  std::size_t points = 0;
};
template <class Select>
LineFit fit_line(const std::vector<AllanPoint>& curve, double slope, double tau_read_s, Select select) {
  double sum = 0.0, weights = 0.0;
  LineFit fit;
  for (std::size_t j = 0; j < curve.size(); ++j) {
    if (!select(j)) continue;
    const double w = 1.0 / (curve[j].relative_error * curve[j].relative_error);
    sum += w * (std::log(curve[j].deviation) - slope * std::log(curve[j].tau_s / tau_read_s));
    weights += w;
    ++fit.points;
  }
  if (fit.points > 0) fit.value = std::exp(sum / weights);
  return fit;
}

}  // namespace

bool AllanOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (points_per_decade < 1 || points_per_decade > 100) problems.add("points_per_decade must be in [1, 100]");
  if (!(std::isfinite(max_tau_s) && max_tau_s >= 0.0)) problems.add("max_tau_s must be finite and >= 0 (0: half the recording)");
  return problems.report(why);
}

// Overlapping Allan variance (IEEE Std 952-1997, Annex C, the estimate from the integrated
// signal theta; El-Sheimy et al. 2008, the same with overlapping clusters), from the
// cumulative sums theta_k = sum_{i<k} (y_i - mean), k = 0..n:
//   sigma^2(m tau0) = 1 / (2 m^2 (n - 2m + 1)) sum_{k=0}^{n-2m} (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2,
// which is half the mean squared difference of adjacent cluster averages (theta_{k+m} - theta_k) / m
// over every start k: O(n) per cluster size. Removing the mean first changes no difference but
// keeps the sums small (an accelerometer's 9.8 m/s^2 summed over hours would cost digits).
std::vector<AllanPoint> allan_deviation(const std::vector<double>& values, double sample_period_s,
                                        const AllanOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "allan_deviation needs valid AllanOptions");
  CAIRN_ASSERT(sample_period_s > 0.0 && std::isfinite(sample_period_s), "allan_deviation needs a sample period > 0");
  const std::size_t n = values.size();
  if (n < 3) return {};
  long double total = 0.0L;
  for (const double v : values) total += v;
  const long double mean = total / static_cast<long double>(n);
  std::vector<double> theta(n + 1, 0.0);
  long double running = 0.0L;
  for (std::size_t i = 0; i < n; ++i) {
    running += static_cast<long double>(values[i]) - mean;
    theta[i + 1] = static_cast<double>(running);
  }
  std::size_t largest = (n - 1) / 2;
  if (options.max_tau_s > 0.0) {
    largest = std::min(largest, static_cast<std::size_t>(std::max(1.0, std::floor(options.max_tau_s / sample_period_s))));
  }
  std::vector<AllanPoint> curve;
  for (const std::size_t m : cluster_sizes(largest, options.points_per_decade)) {
    double sum = 0.0;
    for (std::size_t k = 0; k + 2 * m <= n; ++k) {
      const double d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
      sum += d * d;
    }
    const double md = static_cast<double>(m);
    const double variance = sum / (2.0 * md * md * static_cast<double>(n - 2 * m + 1));
    curve.push_back({md * sample_period_s, m, std::sqrt(variance),
                     1.0 / std::sqrt(2.0 * (static_cast<double>(n) / md - 1.0))});
  }
  return curve;
}

// The readings allan_variance_ros and imu_utils give (IEEE Std 952-1997, Annex C, the noise terms'
// sigma(tau) laws):
//  * white noise sigma = N / sqrt(tau): the -1/2 line through the points whose local slope is
//    -1/2 +- 0.1, before the minimum, read at tau = 1 s;
//  * bias instability: sigma's minimum over the points with relative error <= 0.5, / 0.664;
//    "found" only when the curve rises again after it (a minimum at the last trustworthy point is
//    an upper bound, not a bottom);
//  * rate random walk sigma = K sqrt(tau / 3): the +1/2 line through the points after the minimum
//    with slope +1/2 +- 0.1 (and relative error <= 0.5), read at tau = 3 s.
AllanFit fit_allan_noise(const std::vector<AllanPoint>& curve) {
  AllanFit fit;
  if (curve.size() < 3) return fit;
  const std::vector<double> slopes = local_slopes(curve);
  // The bottom among the trustworthy points: the last few rest on one or two clusters and can
  // dip far below the curve (a random walk's realisation that happens to return).
  std::size_t bottom = 0;
  for (std::size_t j = 1; j < curve.size(); ++j) {
    if (curve[j].relative_error <= kMaxFitRelativeError && curve[j].deviation < curve[bottom].deviation) bottom = j;
  }
  const AllanPoint* lowest = &curve[bottom];
  const auto near = [&](std::size_t j, double slope) { return std::abs(slopes[j] - slope) <= kSlopeTolerance; };
  const LineFit white = fit_line(curve, -0.5, 1.0, [&](std::size_t j) { return j <= bottom && near(j, -0.5); });
  fit.white_noise_found = white.points > 0;
  fit.white_noise_density = white.value;
  fit.white_noise_points = white.points;
  fit.bias_instability = lowest->deviation / kBiasInstabilityFactor;
  fit.bias_instability_tau_s = lowest->tau_s;
  fit.bias_instability_found =
      bottom > 0 && bottom + 1 < curve.size() && curve[bottom + 1].relative_error <= kMaxFitRelativeError;
  const LineFit walk = fit_line(curve, 0.5, 3.0, [&](std::size_t j) {
    return j >= bottom && near(j, 0.5) && curve[j].relative_error <= kMaxFitRelativeError;
  });
  fit.random_walk_found = walk.points > 0;
  fit.random_walk = walk.value;
  fit.random_walk_points = walk.points;
  return fit;
}

ImuAllanReport imu_allan_deviation(const std::vector<ImuSample>& samples, const AllanOptions& options) {
  CAIRN_ASSERT(samples.size() >= 3, "imu_allan_deviation needs at least 3 samples");
  ImuAllanReport report;
  const auto steps = static_cast<double>(samples.size() - 1);
  report.sample_period_s = static_cast<double>(samples.back().stamp.nanoseconds() - samples.front().stamp.nanoseconds()) * 1e-9 / steps;
  CAIRN_ASSERT(report.sample_period_s > 0.0, "imu_allan_deviation needs increasing stamps");
  std::vector<double> values(samples.size());
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t i = 0; i < samples.size(); ++i) values[i] = samples[i].gyro_rad_s[axis];
    report.gyro[static_cast<std::size_t>(axis)] = allan_deviation(values, report.sample_period_s, options);
    for (std::size_t i = 0; i < samples.size(); ++i) values[i] = samples[i].accel_mps2[axis];
    report.accel[static_cast<std::size_t>(axis)] = allan_deviation(values, report.sample_period_s, options);
  }
  for (std::size_t axis = 0; axis < 3; ++axis) {
    report.gyro_fit[axis] = fit_allan_noise(report.gyro[axis]);
    report.accel_fit[axis] = fit_allan_noise(report.accel[axis]);
  }
  return report;
}

ImuNoise noise_from_allan(const ImuAllanReport& report, const ImuNoise& fallback) {
  const auto rms = [](const std::array<AllanFit, 3>& fits, bool AllanFit::*found, double AllanFit::*value, double otherwise) {
    double squares = 0.0;
    int count = 0;
    for (const AllanFit& fit : fits) {
      if (!(fit.*found)) continue;
      squares += fit.*value * (fit.*value);
      ++count;
    }
    return count > 0 ? std::sqrt(squares / count) : otherwise;
  };
  ImuNoise noise;
  noise.gyro_noise_density = rms(report.gyro_fit, &AllanFit::white_noise_found, &AllanFit::white_noise_density, fallback.gyro_noise_density);
  noise.accel_noise_density = rms(report.accel_fit, &AllanFit::white_noise_found, &AllanFit::white_noise_density, fallback.accel_noise_density);
  noise.gyro_random_walk = rms(report.gyro_fit, &AllanFit::random_walk_found, &AllanFit::random_walk, fallback.gyro_random_walk);
  noise.accel_random_walk = rms(report.accel_fit, &AllanFit::random_walk_found, &AllanFit::random_walk, fallback.accel_random_walk);
  return noise;
}

nlohmann::json to_json(const ImuAllanReport& report) {
  const auto axes = [](const std::array<std::vector<AllanPoint>, 3>& curves, const std::array<AllanFit, 3>& fits) {
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t axis = 0; axis < 3; ++axis) {
      nlohmann::json tau = nlohmann::json::array(), deviation = nlohmann::json::array(), error = nlohmann::json::array();
      for (const AllanPoint& p : curves[axis]) {
        tau.push_back(p.tau_s);
        deviation.push_back(p.deviation);
        error.push_back(p.relative_error);
      }
      const AllanFit& f = fits[axis];
      out.push_back({{"axis", std::string(1, static_cast<char>('x' + axis))},
                     {"tau_s", tau},
                     {"deviation", deviation},
                     {"relative_error", error},
                     {"white_noise_found", f.white_noise_found},
                     {"white_noise_density", f.white_noise_density},
                     {"bias_instability_found", f.bias_instability_found},
                     {"bias_instability", f.bias_instability},
                     {"bias_instability_tau_s", f.bias_instability_tau_s},
                     {"random_walk_found", f.random_walk_found},
                     {"random_walk", f.random_walk}});
    }
    return out;
  };
  return {{"sample_period_s", report.sample_period_s},
          {"gyro", axes(report.gyro, report.gyro_fit)},
          {"accel", axes(report.accel, report.accel_fit)}};
}

}  // namespace cairn::inertial
