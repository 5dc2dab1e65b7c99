#include "cairn/sim/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cairn/sim/ray_cast.hpp"

namespace cairn::sim {

bool LidarOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  if (beams < 1 || beams > 10000) problems << "beams must be in [1, 10000] (found " << beams << "); ";
  if (!(angle_increment_rad > 0.0) || !std::isfinite(angle_increment_rad)) {
    problems << "angle_increment_rad must be > 0 (found " << angle_increment_rad << "); ";
  }
  if (!std::isfinite(angle_min_rad)) problems << "angle_min_rad must be finite; ";
  if (!(max_range_m > 0.0) || !std::isfinite(max_range_m)) problems << "max_range_m must be > 0 (found " << max_range_m << "); ";
  if (!(range_sigma_m >= 0.0) || !std::isfinite(range_sigma_m)) problems << "range_sigma_m must be >= 0 (found " << range_sigma_m << "); ";
  if (!(dropout_probability >= 0.0 && dropout_probability <= 1.0)) {
    problems << "dropout_probability must be in [0, 1] (found " << dropout_probability << "); ";
  }
  if (range_decimals < -1 || range_decimals > 9) problems << "range_decimals must be in [-1, 9] (found " << range_decimals << "); ";
  if (!std::isfinite(forward_offset_m)) problems << "forward_offset_m must be finite; ";
  if (!(period_s > 0.0) || !std::isfinite(period_s)) problems << "period_s must be > 0 (found " << period_s << "); ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

std::vector<double> ideal_scan(const World& world, const core::SE2& T_world_laser, const LidarOptions& options,
                               double time_s) {
  std::vector<double> ranges(static_cast<std::size_t>(options.beams), options.max_range_m);
  const std::vector<Circle> walkers = world.walkers_at(time_s);
  const Vector2 origin = T_world_laser.translation();
  for (int i = 0; i < options.beams; ++i) {
    const double angle = T_world_laser.angle() + options.beam_angle(i);
    const Vector2 direction(std::cos(angle), std::sin(angle));
    if (const auto hit = cast_lidar_ray(world, origin, direction, options.max_range_m, walkers)) {
      ranges[static_cast<std::size_t>(i)] = hit->range_m;
    }
  }
  return ranges;
}

double round_range(double range_m, int decimals) {
  if (decimals < 0) return range_m;
  const double scale = std::pow(10.0, decimals);  // exact for 0..9 decimals
  return std::round(range_m * scale) / scale;
}

std::vector<double> add_scan_noise(const std::vector<double>& ideal, const LidarOptions& options, Random& random) {
  std::vector<double> ranges(ideal.size());
  for (std::size_t i = 0; i < ideal.size(); ++i) {
    const bool dropout = random.bernoulli(options.dropout_probability);
    const double noise = random.gaussian(options.range_sigma_m);
    double reading = options.max_range_m;
    if (!dropout && ideal[i] < options.max_range_m) {
      reading = std::max(0.0, ideal[i] + noise);
      if (reading >= options.max_range_m) reading = options.max_range_m;
    }
    ranges[i] = round_range(reading, options.range_decimals);
  }
  return ranges;
}

}  // namespace cairn::sim
