#pragma once
/// \file
/// `cairn imu`'s job, for people who calibrate IMUs (the reports allan_variance_ros and imu_utils
/// give, plus a check against ground truth): Options -> analyse_imu -> ImuAnalysis -> outputs
/// (imu_analysis_outputs.hpp). Stages: the data's checks (rates, gaps, saturation:
/// imu_input.hpp), static initialisation (static_initialization.hpp) compared with the ground
/// truth's biases and attitude when given, the Allan deviation with its noise fits
/// (allan_deviation.hpp; meaningful for a static recording only), the preintegration check over
/// windows (preintegration_check.hpp) with the noise model in use, and the initialisation while
/// moving on windows of the ground truth (inertial_initialization.hpp).

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cairn/inertial/allan_deviation.hpp"
#include "cairn/inertial/imu_input.hpp"
#include "cairn/inertial/inertial_initialization.hpp"
#include "cairn/inertial/preintegration_check.hpp"
#include "cairn/inertial/static_initialization.hpp"

namespace cairn::inertial {

struct ImuAnalysisOptions {
  ImuInputOptions input;
  StaticInitializationOptions initialization;
  bool allan = true;
  AllanOptions allan_options;
  /// The noise model (check.noise) is the one the preintegration check uses.
  PreintegrationCheckOptions check;
  /// With a ground truth: the initialisation while moving (inertial_initialization.hpp) on its
  /// windows, unless off.
  bool moving_initialization = true;
  MovingInitializationCheckOptions moving;
  bool is_valid(std::string* why) const;
};

/// Static initialisation against the ground truth's state in the middle of its window.
struct InitializationVsTruth {
  double truth_time_s = 0.0;
  Vector3 true_gyro_bias_rad_s = Vector3::Zero();
  double gyro_bias_error_rad_s = 0.0;  ///< |estimated - true|
  double gravity_angle_error_deg = 0.0;  ///< between the estimated and true gravity directions in the body frame
};

struct ImuAnalysis {
  ImuDataReport data;
  StaticInitialization initialization;
  std::optional<InitializationVsTruth> initialization_vs_truth;
  std::optional<ImuAllanReport> allan;
  std::optional<PreintegrationCheck> check;
  std::optional<MovingInitializationCheck> moving_initialization;
  ImuNoise noise;  ///< the model the check used
};

/// Precondition: options.is_valid(); samples sorted (as the readers return them). `states` and
/// `poses` may be empty (no comparison, no check); poses without states are not used.
ImuAnalysis analyse_imu(const std::vector<ImuSample>& samples, const std::vector<GroundTruthState>& states,
                        const io::Trajectory& poses, const ImuAnalysisOptions& options);

nlohmann::json to_json(const ImuAnalysis& analysis);

}  // namespace cairn::inertial
