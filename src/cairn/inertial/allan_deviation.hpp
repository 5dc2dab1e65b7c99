#pragma once
/// \file
/// Overlapping Allan deviation of IMU rate signals, and the noise terms read off its curve as
/// allan_variance_ros and imu_utils report them: white noise density N (angle / velocity random
/// walk), bias instability B and rate random walk K (IEEE Std 952-1997, Annex C; El-Sheimy, Hou,
/// Niu, "Analysis and modeling of inertial sensors using Allan variance", IEEE TIM 57(1), 2008).
/// For a static recording: motion is not noise, and the curve of a moving IMU means nothing.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

struct AllanOptions {
  /// Cluster times per decade, log-spaced (cluster sizes rounded to whole samples, repeats
  /// dropped). [1, 100].
  int points_per_decade = 10;
  /// Longest cluster time, s; 0: the longest the overlapping estimator allows, half the
  /// recording (its last points rest on very few independent clusters: see relative_error).
  /// >= 0.
  double max_tau_s = 0.0;

  bool is_valid(std::string* why) const;
};

/// One point of an Allan deviation curve.
struct AllanPoint {
  double tau_s = 0.0;           ///< cluster time m * sample period
  std::size_t cluster_samples = 0;  ///< m
  double deviation = 0.0;       ///< Allan deviation, in the signal's unit (rad/s, m/s^2)
  /// The estimate's relative standard error 1 / sqrt(2 (n / m - 1)) for n samples (El-Sheimy et
  /// al. 2008's percentage error, for non-overlapping clusters; the overlapping estimate is somewhat
  /// better).
  double relative_error = 0.0;
};

/// The noise terms of one axis. Units for a gyroscope (accelerometer): N in rad/s/sqrt(Hz)
/// (m/s^2/sqrt(Hz)), B in rad/s (m/s^2), K in rad/s^2/sqrt(Hz) (m/s^3/sqrt(Hz)): the units of
/// EuRoC's sensor.yaml noise densities and random walks.
struct AllanFit {
  bool white_noise_found = false;
  double white_noise_density = 0.0;  ///< N: the -1/2 line's deviation at tau = 1 s
  std::size_t white_noise_points = 0;
  bool bias_instability_found = false;
  double bias_instability = 0.0;     ///< B = min deviation / sqrt(2 ln 2 / pi) (= / 0.664)
  double bias_instability_tau_s = 0.0;  ///< where the minimum is
  bool random_walk_found = false;
  double random_walk = 0.0;          ///< K: the +1/2 line's deviation at tau = 3 s
  std::size_t random_walk_points = 0;
};

/// The overlapping Allan deviation of `values` (one axis, evenly sampled every
/// `sample_period_s`) at log-spaced cluster times from one sample up. Empty with fewer than 3
/// values. Preconditions: options.is_valid(), sample_period_s > 0, values finite.
std::vector<AllanPoint> allan_deviation(const std::vector<double>& values, double sample_period_s,
                                        const AllanOptions& options);

/// N, B and K read off a curve (see AllanFit and the comments in allan_deviation.cpp).
AllanFit fit_allan_noise(const std::vector<AllanPoint>& curve);

/// Both sensors, three axes each.
struct ImuAllanReport {
  double sample_period_s = 0.0;  ///< duration / (samples - 1)
  std::array<std::vector<AllanPoint>, 3> gyro;
  std::array<std::vector<AllanPoint>, 3> accel;
  std::array<AllanFit, 3> gyro_fit;
  std::array<AllanFit, 3> accel_fit;
};

/// Allan deviation and fits of every axis of a static recording. The sample period is the mean
/// step; the estimator assumes even sampling, so check the recording first (check_imu_data: no
/// gaps). Precondition: options.is_valid(), >= 3 samples with increasing stamps.
ImuAllanReport imu_allan_deviation(const std::vector<ImuSample>& samples, const AllanOptions& options);

/// The noise model the fits give, each density the root mean square over the axes where it was
/// found; a term found on no axis keeps `fallback`'s value.
ImuNoise noise_from_allan(const ImuAllanReport& report, const ImuNoise& fallback);

/// The report as JSON for `cairn imu --json` (curves and fits per axis).
nlohmann::json to_json(const ImuAllanReport& report);

}  // namespace cairn::inertial
