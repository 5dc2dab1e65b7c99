#pragma once
/// \file
/// GNSS withheld to measure dead reckoning (issue 38: "IMU + wheel odometry + GPS fused with 60 s
/// of GPS withheld: the error at the moment GPS returns is reported against the withheld fixes, and
/// is smaller than wheel odometry's alone"). `withhold_fixes` splits a recording's fixes at a time
/// interval; after a run on the kept ones, `compare_with_withheld` sets the estimator's prediction
/// (NavigationState::predicted: no measurement from the gap or after it) and the wheel odometry's
/// own poses, aligned to the fused vehicle pose at the gap's start, against the withheld fixes and
/// the first fix back. Horizontal errors only (a consumer receiver's altitude wanders by tens of
/// metres).

#include <optional>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/navigation/gnss_inertial_odometry.hpp"

namespace cairn::navigation {

struct WithheldFixes {
  std::vector<gnss::GnssFix> kept;      ///< outside [from_s, to_s): given to the estimator
  std::vector<gnss::GnssFix> withheld;  ///< inside: the reference
};

/// Splits `fixes` at [from_s, to_s) (the fixes' own stamps, seconds).
WithheldFixes withhold_fixes(const std::vector<gnss::GnssFix>& fixes, double from_s, double to_s);

/// One withheld fix against both estimates, horizontal, metres.
struct WithheldFixError {
  double time_s = 0.0;
  double fused_m = 0.0;
  std::optional<double> wheel_m;  ///< without wheel odometry poses: none
};

struct WithheldComparison {
  double from_s = 0.0;
  double to_s = 0.0;
  std::vector<WithheldFixError> fixes;  ///< every withheld fix, in time order
  /// The first kept fix at or after to_s: the moment GPS returns (none when the gap runs to the end).
  std::optional<WithheldFixError> first_fix_back;
  double fused_rms_m = 0.0;
  std::optional<double> wheel_rms_m;
};

/// The vehicle's pose at t_s from the final (predicted false) or predicted estimates: the state at
/// or before t_s, moved along its velocity, times T_imu_vehicle. Precondition: states not empty.
core::SE3 vehicle_pose_at(const std::vector<NavigationState>& states, double t_s, bool predicted, const core::SE3& T_imu_vehicle);

/// The wheel odometry's own vehicle pose at t_s: linear in position between its messages, the
/// nearer message's rotation. Precondition: at least two poses.
core::SE3 wheel_pose_at(const io::Trajectory& T_odom_vehicle, double t_s);

/// Both estimates against the withheld fixes and the first fix back, in the ENU frame at
/// `enu_origin` (the estimator's, NavigationSummary::enu_origin). `wheel_poses` (T_odom_vehicle,
/// may be empty) is rotated about the vertical and shifted onto the fused vehicle pose at from_s.
/// Throws std::invalid_argument when there are no states or no withheld fix.
WithheldComparison compare_with_withheld(const std::vector<NavigationState>& states, const WithheldFixes& split,
                                         double from_s, double to_s, const gnss::GeodeticPosition& enu_origin,
                                         const core::SE3& T_imu_vehicle, const io::Trajectory& wheel_poses);

}  // namespace cairn::navigation
