#pragma once
/// \file
/// What a `cairn slam3d --imu` run writes besides the LiDAR outputs (docs/lidar3d.md,
/// "LiDAR-inertial"): the record of the fused states, kept while the scans are fed; its summary
/// (initialisation, per-scan consistency of the registrations with the IMU, final biases and
/// gravity); inertial_states.csv (one row per fused scan); inertial.png (velocity and biases over
/// time); and report.json's "inertial" section.

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cairn/lidar3d/inertial_fusion.hpp"
#include "cairn/lidar3d/inertial_input.hpp"
#include "cairn/viz/figure.hpp"

namespace cairn::lidar3d {

/// One run's IMU: its input, the fusion's options and, per processed scan, the fused state.
class InertialRun {
 public:
  /// `remap_forced`: prepare_for_inertial turned registration.remap_degenerate_directions on.
  InertialRun(InertialInput input, const InertialFusionOptions& options, bool remap_forced);

  /// Scan `sequence_index` was processed; `state` is its fused state, none when the IMU did not
  /// cover its sweep (it went through LidarSlam alone).
  void add_scan(std::size_t sequence_index, const std::optional<InertialScanState>& state);
  /// After the last scan: how the fusion was initialised (none when no scan was covered).
  void finish(const LidarInertialFusion& fusion);

  const InertialInput& input() const { return input_; }
  const InertialFusionOptions& options() const { return options_; }
  bool remap_forced() const { return remap_forced_; }
  /// The fused states in scan order, and the sequence index of each.
  const std::vector<InertialScanState>& states() const { return states_; }
  const std::vector<std::size_t>& state_scans() const { return state_scans_; }
  /// Sequence indices of the processed scans without a prediction.
  const std::vector<std::size_t>& scans_without_prediction() const { return without_prediction_; }
  const std::optional<InertialInitialization>& initialization() const { return initialization_; }

 private:
  InertialInput input_;
  InertialFusionOptions options_;
  bool remap_forced_ = false;
  std::vector<InertialScanState> states_;
  std::vector<std::size_t> state_scans_;
  std::vector<std::size_t> without_prediction_;
  std::optional<InertialInitialization> initialization_;
};

/// The run's IMU consistency in numbers.
struct InertialSummary {
  std::size_t fused_scans = 0;
  std::size_t scans_without_prediction = 0;
  /// Over the scans with a registration (imu_lidar_chi2 >= 0): how many, median and 90th
  /// percentile (linear interpolation) of the chi-square; 0 when none.
  std::size_t scans_with_chi2 = 0;
  double median_chi2 = 0.0;
  double p90_chi2 = 0.0;
  std::size_t scans_contradicting_imu = 0;
  std::size_t degenerate_scans_carried = 0;  ///< degenerate registrations the IMU carried
  std::size_t scans_without_lidar = 0;       ///< fused without a LiDAR factor (lost)
  /// Of the last fused state (zero when none).
  inertial::ImuBias final_bias;
  Vector3 final_gravity = Vector3::Zero();
  /// Sentences for the terminal: the IMU covering fewer scans than it missed (a clock offset?),
  /// scans it contradicted.
  std::vector<std::string> warnings;
};

InertialSummary summarize(const InertialRun& run);

/// inertial_states.csv: a header row, then per fused scan `scan,time_s,velocity_{x,y,z}_mps,
/// gyro_bias_{x,y,z}_rad_s,accel_bias_{x,y,z}_mps2,gravity_{x,y,z}_mps2,imu_lidar_chi2,
/// contradicts_imu,lidar_used,degenerate` (numbers in their shortest exact form, booleans 0/1;
/// vectors in the trajectory's world frame, biases in the IMU's).
void write_inertial_states_csv(std::ostream& out, const InertialRun& run);

/// inertial.png's content: velocity (x, y, z and speed), gyroscope bias and accelerometer bias
/// against time, one panel each.
viz::Figure inertial_figure(const InertialRun& run);

/// report.json's "inertial": the IMU's source and checks (inertial::to_json), the calibration and
/// extrinsic files, time offset and notes, the fusion's options, whether remapping was forced, the
/// initialisation, the summary's consistency numbers and the final biases and gravity.
nlohmann::json inertial_json(const InertialRun& run);

}  // namespace cairn::lidar3d
