#include "cairn/gnss/local_frame.hpp"

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"

namespace cairn::gnss {

bool is_valid_geodetic(const GeodeticPosition& position, std::string* why) {
  core::Problems problems;
  if (!(position.latitude_deg >= -90.0 && position.latitude_deg <= 90.0)) {
    problems.add("latitude must be in [-90, 90] deg");
  }
  if (!(position.longitude_deg >= -180.0 && position.longitude_deg <= 180.0)) {
    problems.add("longitude must be in [-180, 180] deg");
  }
  if (!(position.altitude_m >= kMinAltitudeM && position.altitude_m <= kMaxAltitudeM)) {
    problems.add("altitude must be in [-1e5, 1e8] m");
  }
  return problems.report(why);
}

LocalFrame::LocalFrame(const GeodeticPosition& origin) : origin_(origin) {
  std::string why;
  CAIRN_ASSERT(is_valid_geodetic(origin, &why), "LocalFrame origin is not a valid geodetic position: check it with is_valid_geodetic");
  cartesian_ = std::make_shared<const GeographicLib::LocalCartesian>(origin.latitude_deg, origin.longitude_deg,
                                                                     origin.altitude_m, GeographicLib::Geocentric::WGS84());
}

std::optional<LocalFrame> LocalFrame::at_first_fix(const std::vector<GnssFix>& fixes) {
  for (const GnssFix& fix : fixes) {
    const GeodeticPosition position{fix.latitude_deg, fix.longitude_deg, fix.altitude_m};
    if (fix.status != kStatusNoFix && is_valid_geodetic(position, nullptr)) return LocalFrame(position);
  }
  return std::nullopt;
}

Vector3 LocalFrame::forward(const GeodeticPosition& position) const {
  Vector3 p_enu_m;
  cartesian_->Forward(position.latitude_deg, position.longitude_deg, position.altitude_m, p_enu_m.x(), p_enu_m.y(),
                      p_enu_m.z());
  return p_enu_m;
}

Vector3 LocalFrame::forward(const GnssFix& fix) const {
  return forward(GeodeticPosition{fix.latitude_deg, fix.longitude_deg, fix.altitude_m});
}

GeodeticPosition LocalFrame::reverse(const Vector3& p_enu_m) const {
  GeodeticPosition position;
  cartesian_->Reverse(p_enu_m.x(), p_enu_m.y(), p_enu_m.z(), position.latitude_deg, position.longitude_deg,
                      position.altitude_m);
  return position;
}

}  // namespace cairn::gnss
