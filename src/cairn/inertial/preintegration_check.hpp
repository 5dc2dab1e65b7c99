#pragma once
/// \file
/// Checks an IMU's noise model against ground truth, as a user calibrating an IMU would: over
/// windows of a few seconds, preintegrate the real IMU from a ground-truth state (pose, velocity,
/// biases) and compare the predicted state at the window's end with the ground truth there.
/// Reports the rotation, velocity and position errors (median, 90th percentile) and the NEES of the
/// 9-dof residual (r_R, r_v, r_p) against the preintegrated covariance (Forster et al., T-RO 2017,
/// eq. 62): for a noise model that fits, and ground truth much better than the IMU, NEES averages
/// 9 (Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and Navigation", 2001,
/// Sec. 5.4.2). The ground truth's own error adds to the residual, so a NEES above 9 can mean either
/// optimistic noise densities or a ground truth too coarse for the window (say which by varying
/// --window: IMU noise grows with the window, ground-truth error does not).

#include <string>
#include <vector>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::inertial {

struct PreintegrationCheckOptions {
  /// Window length, seconds (> 0): each window runs from one ground-truth state to the state nearest
  /// window_s later (within half the states' spacing).
  double window_s = 1.0;
  /// Start a window at every `stride`-th ground-truth state (>= 1).
  int stride = 1;
  ImuNoise noise;
  /// Magnitude of gravity along the world's -z, m/s^2 (> 0).
  double gravity_mps2 = kStandardGravity;
  /// Poses are interpolated from `poses` at the states' stamps when neighbours lie within this
  /// (seconds, > 0); otherwise the state's own pose is used.
  double max_pose_gap_s = 0.02;
  bool is_valid(std::string* why) const;
};

/// One window's prediction against the ground truth at its end.
struct WindowError {
  double start_s = 0.0;
  double duration_s = 0.0;
  double rotation_error_deg = 0.0;
  double velocity_error_mps = 0.0;
  double position_error_m = 0.0;
  double nees = 0.0;  ///< r^T Sigma^-1 r, 9 dof
};

struct ErrorSpread {
  double median = 0.0, p90 = 0.0, mean = 0.0, max = 0.0;
};

struct PreintegrationCheck {
  std::vector<WindowError> windows;
  int windows_skipped = 0;  ///< IMU not covering the window, or no ground-truth state at its end
  ErrorSpread rotation_deg, velocity_mps, position_m, nees;
  /// Whether the poses came from `poses` (interpolated) for every window end, or from the states.
  int poses_from_states = 0;
};

/// Precondition: options.is_valid(); samples and states sorted by stamp. `poses` may be empty (the
/// states' own poses are used).
PreintegrationCheck check_preintegration(const std::vector<ImuSample>& samples,
                                         const std::vector<GroundTruthState>& states, const io::Trajectory& poses,
                                         const PreintegrationCheckOptions& options);

/// Median, 90th percentile (nearest rank), mean and max of `values` (empty: zeros).
ErrorSpread spread_of(std::vector<double> values);

}  // namespace cairn::inertial
