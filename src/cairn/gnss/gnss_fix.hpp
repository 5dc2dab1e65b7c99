#pragma once
/// \file
/// One GNSS position fix as cairn uses it (`GnssFix`): geodetic WGS84 position, the receiver's
/// position covariance in the local east-north-up frame at the fix, and sensor_msgs/NavSatFix's
/// status. The readers (gnss_reader.hpp) and the simulated receiver (sim/gnss_receiver.hpp)
/// produce it; local_frame.hpp turns it into metres.

#include "cairn/core/time.hpp"
#include "cairn/core/types.hpp"

namespace cairn::gnss {

/// sensor_msgs/NavSatStatus's status values.
inline constexpr int kStatusNoFix = -1;  ///< unable to fix position (such fixes are dropped on reading)
inline constexpr int kStatusFix = 0;     ///< unaugmented fix
inline constexpr int kStatusSbasFix = 1; ///< with satellite-based augmentation
inline constexpr int kStatusGbasFix = 2; ///< with ground-based augmentation (RTK, DGPS)

struct GnssFix {
  core::Timestamp stamp;
  double latitude_deg = 0.0;   ///< WGS84, [-90, 90], north positive
  double longitude_deg = 0.0;  ///< WGS84, [-180, 180], east positive
  double altitude_m = 0.0;     ///< above the WGS84 ellipsoid (NavSatFix's convention)
  /// Position covariance in east-north-up at the fix, m^2 (NavSatFix's position_covariance,
  /// which REP 145 defines in ENU); meaningful only when covariance_known.
  Matrix3 covariance_enu_m2 = Matrix3::Zero();
  /// False when the receiver gave none (NavSatFix type 0, or a CSV without covariance columns):
  /// the factor then uses GnssFactorOptions' default sigmas.
  bool covariance_known = false;
  int status = kStatusFix;  ///< kStatusFix, kStatusSbasFix or kStatusGbasFix (no-fix records are dropped)
};

}  // namespace cairn::gnss
