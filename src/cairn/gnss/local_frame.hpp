#pragma once
/// \file
/// A local east-north-up (ENU) frame tangent to the WGS84 ellipsoid at an origin
/// (`LocalFrame`): geodetic latitude, longitude and ellipsoidal height to metres east, north and
/// up of the origin, and back. GeographicLib's LocalCartesian does the work (geodetic -> ECEF ->
/// rotation into the tangent plane, exact, no small-area approximation; Karney, GeographicLib
/// docs "LocalCartesian"); GeographicLib stays out of this header, so users of cairn::gnss need
/// not find it.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/types.hpp"
#include "cairn/gnss/gnss_fix.hpp"

namespace GeographicLib {
class LocalCartesian;
}

namespace cairn::gnss {

/// A geodetic WGS84 position.
struct GeodeticPosition {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double altitude_m = 0.0;  ///< above the ellipsoid
};

/// True when latitude is in [-90, 90], longitude in [-180, 180] and altitude in
/// [kMinAltitudeM, kMaxAltitudeM], all finite; otherwise false with the reason in `why`.
bool is_valid_geodetic(const GeodeticPosition& position, std::string* why);
/// The altitudes cairn accepts: below the deepest land depression with margin, above any orbit
/// a GNSS receiver flies in (so the ENU coordinates stay far from overflow).
inline constexpr double kMinAltitudeM = -1.0e5;
inline constexpr double kMaxAltitudeM = 1.0e8;

class LocalFrame {
 public:
  /// The ENU frame at `origin`. Precondition: is_valid_geodetic(origin) (the readers check every
  /// fix; an origin from a flag or config is checked with is_valid_geodetic first).
  explicit LocalFrame(const GeodeticPosition& origin);
  /// The ENU frame at the first fix of `fixes` whose status is not kStatusNoFix and whose
  /// position is valid (the readers keep only such fixes); nothing when there is none.
  static std::optional<LocalFrame> at_first_fix(const std::vector<GnssFix>& fixes);

  const GeodeticPosition& origin() const { return origin_; }
  /// Metres (east, north, up) of `position` from the origin.
  Vector3 forward(const GeodeticPosition& position) const;
  /// The fix's antenna position in this frame, metres.
  Vector3 forward(const GnssFix& fix) const;
  /// The geodetic position of the point `p_enu_m` (east, north, up from the origin).
  GeodeticPosition reverse(const Vector3& p_enu_m) const;

 private:
  GeodeticPosition origin_;
  std::shared_ptr<const GeographicLib::LocalCartesian> cartesian_;  ///< immutable, so copies share it
};

}  // namespace cairn::gnss
