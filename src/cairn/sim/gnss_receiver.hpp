#pragma once
/// \file
/// A simulated GNSS receiver (`simulate_gnss_receiver`): fixes at a fixed rate from a
/// ground-truth trajectory T_world_body, at the antenna (lever arm), with Gaussian noise of given
/// sigmas, dropout windows without fixes, no fix where the antenna does not see the sky (an
/// optional predicate, e.g. inside a tunnel), and a fraction of outliers (jumps of a given size range
/// in uniformly random 3D directions), written as WGS84 latitude / longitude / altitude around a
/// configurable origin through gnss::LocalFrame. Returns the exact truth of every fix: its true
/// antenna position and whether it is an outlier.

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/core/types.hpp"
#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/gnss/local_frame.hpp"

namespace cairn::sim {

struct GnssReceiverOptions {
  double rate_hz = 5.0;  ///< fixes per second, > 0
  /// Noise of a good fix, metres, >= 0 (the fix's reported covariance is diag(h^2, h^2, v^2)).
  double sigma_horizontal_m = 0.5;
  double sigma_vertical_m = 1.0;
  Vector3 lever_arm_body_m = Vector3::Zero();  ///< the antenna in the body frame
  /// The simulator's world in the ENU frame at `origin` (identity: world = ENU).
  core::SE3 T_enu_world;
  /// Where the ENU frame is on Earth (is_valid_geodetic). Default: an open field near Zurich.
  gnss::GeodeticPosition origin{47.3769, 8.5417, 408.0};
  /// Windows without fixes, seconds from the trajectory's first stamp, [start, end), start < end.
  std::vector<std::pair<double, double>> dropouts_s;
  /// Whether the antenna at `p_world_m` (the trajectory's world frame) sees the sky; an epoch
  /// where it does not gives no fix. Empty (default): the sky is always visible.
  std::function<bool(const Vector3& p_world_m)> sky_visible;
  /// Fraction of fixes that are outliers, [0, 1], and their jump size, metres, 0 <= min <= max.
  double outlier_fraction = 0.0;
  double outlier_min_m = 10.0;
  double outlier_max_m = 50.0;
  /// Whether fixes carry the covariance (as NavSatFix type 2), or none (type 0).
  bool report_covariance = true;
  std::uint64_t seed = 1;
  bool is_valid(std::string* why) const;
};

struct SimulatedGnss {
  std::vector<gnss::GnssFix> fixes;
  std::vector<Vector3> p_enu_true_m;  ///< true antenna position of each fix, ENU
  std::vector<Vector3> p_enu_measured_m;  ///< what the fix says, ENU (before the lat/lon round trip)
  std::vector<bool> outlier;          ///< per fix: a jump
  std::size_t dropped_in_dropouts = 0;  ///< epochs that fell in a dropout window
  std::size_t blocked_without_sky = 0;  ///< other epochs whose antenna did not see the sky (sky_visible)
};

/// Fixes every 1 / rate_hz seconds from stamps.front() to stamps.back(), the true pose at each
/// epoch interpolated between ground-truth poses (translation linearly, rotation by slerp). An
/// epoch in a dropout window is counted there even when the sky is hidden too. Every epoch draws
/// the same variates whether it gives a fix or not.
/// Preconditions: options.is_valid(), stamps strictly increasing, one pose per stamp, >= 2 poses.
SimulatedGnss simulate_gnss_receiver(const std::vector<core::Timestamp>& stamps,
                                     const std::vector<core::SE3>& T_world_body, const GnssReceiverOptions& options);

}  // namespace cairn::sim
