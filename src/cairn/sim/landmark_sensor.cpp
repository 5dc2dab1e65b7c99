#include "cairn/sim/landmark_sensor.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cairn/sim/ray_cast.hpp"

namespace cairn::sim {

bool RangeBearingOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  if (!(max_range_m > 0.0) || !std::isfinite(max_range_m)) problems << "max_range_m must be > 0; ";
  if (!(field_of_view_rad > 0.0 && field_of_view_rad <= 2.0 * std::numbers::pi)) {
    problems << "field_of_view_rad must be in (0, 2 pi] (found " << field_of_view_rad << "); ";
  }
  if (!(range_sigma_m >= 0.0) || !std::isfinite(range_sigma_m)) problems << "range_sigma_m must be >= 0; ";
  if (!(bearing_sigma_rad >= 0.0) || !std::isfinite(bearing_sigma_rad)) problems << "bearing_sigma_rad must be >= 0; ";
  if (!(detection_probability >= 0.0 && detection_probability <= 1.0)) {
    problems << "detection_probability must be in [0, 1] (found " << detection_probability << "); ";
  }
  if (!(period_s > 0.0) || !std::isfinite(period_s)) problems << "period_s must be > 0; ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

std::vector<LandmarkObservation> observe_landmarks(const World& world, const core::SE2& T_world_body,
                                                   core::Timestamp stamp, const RangeBearingOptions& options,
                                                   Random& random) {
  std::vector<LandmarkObservation> observations;
  const core::SE2 T_body_world = T_world_body.inverse();
  for (const auto& landmark : world.landmarks) {
    const Vector2 p_body = T_body_world * landmark.position;
    const double range = p_body.norm();
    const double bearing = std::atan2(p_body.y(), p_body.x());
    if (range > options.max_range_m || std::abs(bearing) > 0.5 * options.field_of_view_rad) continue;
    if (options.occlusion) {
      // The post at the landmark itself must not hide it: stop short of its surface.
      double margin = 1e-6;
      for (const auto& circle : world.circles) {
        if ((circle.center - landmark.position).norm() < 1e-9) margin = std::max(margin, circle.radius_m + 1e-6);
      }
      if (!line_of_sight(world, T_world_body.translation(), landmark.position, margin)) continue;
    }
    const bool detected = random.bernoulli(options.detection_probability);
    const double range_noise = random.gaussian(options.range_sigma_m);
    const double bearing_noise = random.gaussian(options.bearing_sigma_rad);
    if (!detected) continue;
    observations.push_back({stamp, landmark.id, range + range_noise, core::wrap_angle(bearing + bearing_noise)});
  }
  return observations;
}

}  // namespace cairn::sim
