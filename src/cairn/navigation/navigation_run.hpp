#pragma once
/// \file
/// One navigation run from a recording (`cairn navigate`'s pipeline, usable from C++): the bag's
/// three streams read (`read_navigation_bag`: sensor_msgs/Imu, nav_msgs/Odometry, sensor_msgs/
/// NavSatFix), optionally a stretch of GNSS withheld to measure dead reckoning against it
/// (withheld_gnss.hpp), the estimator run in time order (`run_navigation`). Outputs:
/// navigation_outputs.hpp.

#include <optional>
#include <string>
#include <vector>

#include "cairn/gnss/gnss_reader.hpp"
#include "cairn/navigation/gnss_inertial_odometry.hpp"
#include "cairn/navigation/wheel_odometry_reader.hpp"
#include "cairn/navigation/withheld_gnss.hpp"

namespace cairn::navigation {

struct NavigationRecording {
  std::vector<inertial::ImuSample> imu;
  WheelOdometryRecording wheels;
  std::vector<gnss::GnssFix> fixes;
  gnss::GnssReadReport gnss_report;  ///< fixes without a fix or with NaN, dropped and counted
};

/// Reads the topics of the bag at `bag_path` (any format bag::Bag opens); an empty topic means the
/// bag's only topic of that message type; `with_gnss` false reads no fixes (IMU and wheels alone).
/// Throws io::ParseError naming the bag and topic when a topic is missing or ambiguous or a
/// message is bad (the readers' messages), or when the IMU topic has no sample.
NavigationRecording read_navigation_bag(const std::string& bag_path, const std::string& imu_topic,
                                        const std::string& wheel_topic, const std::string& gnss_topic, bool with_gnss = true);

/// The recording's first `seconds` after the IMU's first sample (every stream cut there; wheel
/// poses with the speeds). Precondition: seconds > 0.
NavigationRecording first_seconds(const NavigationRecording& recording, double seconds);

/// GNSS withheld over [from_s, to_s), seconds after the IMU's first sample.
struct GnssWithholding {
  double from_s = 0.0;
  double to_s = 0.0;
};

struct NavigationRun {
  std::vector<NavigationState> states;
  std::vector<GnssFixResult> fix_results;  ///< the fixes the estimator was given
  NavigationSummary summary;
  double start_s = 0.0;                     ///< the IMU's first stamp
  std::optional<WithheldFixes> split;       ///< with a withholding
  std::optional<WithheldComparison> withheld;
  /// Why a withholding gave no comparison (no fix in it, GNSS never aligned), else empty.
  std::string withheld_note;
};

/// Runs GnssInertialOdometry over the recording in time order, with `withholding`'s fixes held
/// back and compared afterwards. Throws std::invalid_argument for invalid options or a withholding
/// with to_s <= from_s.
NavigationRun run_navigation(const NavigationRecording& recording, const GnssInertialOdometryOptions& options,
                             const std::optional<GnssWithholding>& withholding = std::nullopt);

}  // namespace cairn::navigation
