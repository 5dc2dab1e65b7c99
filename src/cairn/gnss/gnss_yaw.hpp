#pragma once
/// \file
/// The initial alignment of a gravity-aligned world (odometry) frame to the ENU frame of the
/// fixes (`align_world_to_enu`): yaw about the shared up axis and a 3D translation (4 DoF), fitted
/// in closed form to matched positions p_enu_i ~= R_z(yaw) p_world_i + t. Roll and pitch are
/// known (both frames have z up, docs/conventions.md and inertial/imu_types.hpp), so this is
/// Umeyama's fit (Umeyama, IEEE TPAMI 13(4), 1991, eqs. 34-42) restricted to rotations about z,
/// whose optimum is (Horn 1987, 2D case):
///
///     yaw = atan2(sum_i (x_i cross y_i)_z, sum_i x_i . y_i),   t = mean(p_enu) - R_z mean(p_world)
///
/// x_i, y_i the horizontal parts of p_world_i and p_enu_i about their centroids.
///
/// Why motion: one position fixes no heading; yaw is observable only once the robot has moved.
/// Linearising the fit, its yaw variance is sigma_h^2 / sum_i |x_i|^2 (sigma_h the horizontal
/// noise of a fix): it shrinks with the spread of the path about its centroid. The fit is refused
/// until the RMS horizontal spread reaches min_spread_m (default 10 m: with a 2.5 m consumer fix
/// and 25 fixes this predicts 2.5 / (10 sqrt(25)) = 0.05 rad = 2.9 deg, enough to start a fusion
/// that then refines it; with 100 fixes, 1.4 deg). A straight line suffices: yaw and translation
/// need spread, not turns. Gross outliers (GNSS jumps) are removed by a few trimmed refits.

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"

namespace cairn::gnss {

struct YawAlignmentOptions {
  /// Least RMS horizontal distance of the world positions from their centroid, metres, > 0.
  double min_spread_m = 10.0;
  /// Least number of position pairs kept after trimming, >= 2.
  std::size_t min_pairs = 5;
  /// Trimmed refits: after each fit, pairs whose horizontal residual exceeds
  /// max(outlier_factor * 1.4826 * median residual, min_outlier_threshold_m) are dropped and the
  /// fit refitted on the rest, at most trim_iterations times (the residual is a 2D norm, whose
  /// median is 1.18 sigma_h, so the default gate is ~5 sigma_h). outlier_factor > 0, threshold > 0,
  /// iterations >= 0.
  double outlier_factor = 3.0;
  double min_outlier_threshold_m = 1.0;
  int trim_iterations = 3;
  bool is_valid(std::string* why) const;
};

enum class YawAlignmentStatus {
  kOk,
  kTooFewPairs,     ///< fewer than min_pairs (before or after trimming)
  kTooLittleMotion  ///< spread below min_spread_m: yaw not yet observable
};

struct YawAlignment {
  YawAlignmentStatus status = YawAlignmentStatus::kTooFewPairs;
  std::string message;
  core::SE3 T_enu_world;  ///< R_z(yaw), t: p_enu = T_enu_world * p_world
  double yaw_rad = 0.0;
  double spread_m = 0.0;        ///< RMS horizontal distance of the kept world positions from their centroid
  double rms_residual_m = 0.0;  ///< RMS horizontal residual of the kept pairs
  /// Predicted standard deviation of yaw: rms_residual / sqrt(sum |x_i|^2) (file comment).
  double yaw_sigma_rad = 0.0;
  std::size_t pairs_used = 0;
  std::size_t pairs_rejected = 0;  ///< trimmed as outliers
  bool ok() const { return status == YawAlignmentStatus::kOk; }
};

/// Fits T_enu_world to the pairs (p_world[i], p_enu[i]) (same size, precondition). Never throws:
/// a refusal comes back as a status with a message.
YawAlignment align_world_to_enu(const std::vector<Vector3>& p_world, const std::vector<Vector3>& p_enu,
                                const YawAlignmentOptions& options = {});

}  // namespace cairn::gnss
