#pragma once
/// \file
/// What a user says about an IMU beyond its samples (the IMU-to-body extrinsic, a constant time
/// offset, the sensor's saturation limits), the checks `cairn imu` reports on a recording (rate,
/// gaps, saturation, per-axis statistics), and turning IMU-frame samples into body-frame ones.

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

/// Largest |time offset| an IMU input accepts, s: a shifted stamp must stay within the +-9.2e9 s a
/// stamp can hold (kMaxAbsImuStampNs).
inline constexpr double kMaxAbsTimeOffsetS = 9.2e9;

struct ImuInputOptions {
  /// Added to every IMU stamp: t_body = t_imu + time_offset_s (s). Finite, |offset| <= 9.2e9 s
  /// (an IMU stamping since boot may need the epoch); applied rounded to the ns.
  double time_offset_s = 0.0;
  /// The IMU in the body frame: p_body = T_body_imu * p_imu. Identity: the body is the IMU.
  core::SE3 T_body_imu;
  /// |angular rate| at which the gyroscope saturates, rad/s; 0 = unknown (then saturation is
  /// guessed, see check_imu_data). >= 0. ADIS16448: 1000 deg/s = 17.45 rad/s.
  double gyro_saturation_rad_s = 0.0;
  /// |specific force| at which the accelerometer saturates, m/s^2; 0 = unknown. >= 0.
  /// ADIS16448: 18 g = 176.5 m/s^2.
  double accel_saturation_mps2 = 0.0;
  /// A gap is a step between samples longer than gap_factor x the median step. > 1; 1.5 flags
  /// one missing sample (a step of 2x) while a jitter of +-25 % passes.
  double gap_factor = 1.5;

  bool is_valid(std::string* why) const;
};

/// A step between two consecutive samples longer than gap_factor x the median step.
struct ImuGap {
  core::Timestamp before;  ///< stamp of the sample before the gap
  core::Timestamp after;   ///< stamp of the sample after it
  double dt_s = 0.0;       ///< after - before
};

/// Consecutive samples at saturation on one axis of one sensor.
struct ImuSaturationRun {
  bool gyro = true;  ///< false: accelerometer
  int axis = 0;      ///< 0 x, 1 y, 2 z
  core::Timestamp first;
  core::Timestamp last;
  std::size_t samples = 0;
  double value = 0.0;         ///< the reading (rad/s or m/s^2) of the run's first sample
  bool from_limit = true;     ///< true: |value| >= the given limit; false: guessed (limit unknown)
};

struct ImuDataReport {
  std::size_t samples = 0;
  core::Timestamp first_stamp;
  core::Timestamp last_stamp;
  double duration_s = 0.0;     ///< last - first
  double median_dt_s = 0.0;    ///< median step between samples (0 with < 2 samples)
  double median_rate_hz = 0.0; ///< 1 / median_dt_s
  double mean_rate_hz = 0.0;   ///< (samples - 1) / duration_s
  double min_dt_s = 0.0;
  double max_dt_s = 0.0;
  std::size_t non_increasing_steps = 0;  ///< steps with dt <= 0 (readers refuse them; 0 from a reader)
  double gap_factor = 0.0;               ///< the option used
  std::vector<ImuGap> gaps;              ///< in time order
  double gap_time_s = 0.0;               ///< sum of the gaps' dt_s
  bool gyro_limit_known = false;
  bool accel_limit_known = false;
  std::size_t gyro_saturated_samples = 0;   ///< samples with at least one gyro axis at saturation
  std::size_t accel_saturated_samples = 0;  ///< samples with at least one accel axis at saturation
  std::vector<ImuSaturationRun> saturation; ///< in time order per sensor and axis
  Vector3 gyro_mean_rad_s = Vector3::Zero();
  Vector3 gyro_std_rad_s = Vector3::Zero();  ///< sample standard deviation (n - 1)
  Vector3 accel_mean_mps2 = Vector3::Zero();
  Vector3 accel_std_mps2 = Vector3::Zero();
};

/// Counts, rates, gaps, saturation and per-axis mean / standard deviation of `samples` (IMU frame,
/// stamps as recorded; the time offset and extrinsic do not change any of these).
///
/// Saturation: with a known limit, a sample is saturated on an axis when |value| >= limit. With an
/// unknown limit (0) it is guessed: a run of >= 3 consecutive identical readings equal to the
/// axis' largest (or smallest) value over the recording, since a clipped sensor repeats its
/// full-scale value while a live one dithers. The guess misses a sensor whose clipped output
/// jitters, and can flag a quantised, very quiet axis; give the limit when it is known.
/// Precondition: options.is_valid().
ImuDataReport check_imu_data(const std::vector<ImuSample>& samples, const ImuInputOptions& options);

/// The samples in the body frame: stamps shifted by time_offset_s; gyro_body = R_body_imu * gyro,
/// accel_body = R_body_imu * accel. This is exact for the angular rate (a rigid body has one), but
/// for the specific force only when the IMU sits at the body origin: an accelerometer at
/// r = t_body_imu measures, besides the body origin's acceleration, dw/dt x r + w x (w x r)
/// (the lever-arm terms), which are ignored here. They matter when |w|^2 |r| or |dw/dt| |r|
/// approach the accelerometer's noise: r = 0.1 m at 1 rad/s gives 0.1 m/s^2, more than three
/// times the ADIS16448's white noise per sample at 200 Hz (0.028 m/s^2). Then keep the samples in the IMU frame and estimate the IMU's
/// pose (compose with T_body_imu afterwards), as preintegration does. Throws std::out_of_range
/// when a shifted stamp leaves +-9.2e9 s. Precondition: options.is_valid().
std::vector<ImuSample> apply_imu_input(const std::vector<ImuSample>& samples, const ImuInputOptions& options);

/// The report as JSON for `cairn imu --json`: stamps as integer nanoseconds (`*_ns`, exact), durations
/// in seconds, vectors as [x, y, z].
nlohmann::json to_json(const ImuDataReport& report);

}  // namespace cairn::inertial
