#include "cairn/sim/lidar_3d.hpp"

#include <cmath>
#include <sstream>

#include "cairn/sim/ray_cast_3d.hpp"

namespace cairn::sim {

bool Lidar3DOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  if (rings < 2 || rings > 128) problems << "rings must be in [2, 128]; ";
  if (!(elevation_min_rad < elevation_max_rad) || elevation_min_rad < -std::numbers::pi / 2 ||
      elevation_max_rad > std::numbers::pi / 2) {
    problems << "need -pi/2 <= elevation_min_rad < elevation_max_rad <= pi/2; ";
  }
  if (columns < 1 || columns > 4000) problems << "columns must be in [1, 4000]; ";
  if (!(period_s > 0.0)) problems << "period_s must be > 0; ";
  if (!(max_range_m > 0.0)) problems << "max_range_m must be > 0; ";
  if (!(range_sigma_m >= 0.0)) problems << "range_sigma_m must be >= 0; ";
  if (!(dropout_probability >= 0.0 && dropout_probability <= 1.0)) problems << "dropout_probability must be in [0, 1]; ";
  if (!(mount_height_m > 0.0)) problems << "mount_height_m must be > 0; ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

std::vector<LidarPoint> spin_scan(const World3D& world, double scan_start_s,
                                  const std::function<core::SE3(double)>& T_world_lidar_at,
                                  const Lidar3DOptions& options, Random& random) {
  std::vector<LidarPoint> points;
  // Only objects within reach of the sensor during this revolution (1 m slack for its motion).
  const core::SE3 T_start = T_world_lidar_at(scan_start_s);
  const World3D local = nearby(world, T_start.translation().head<2>(), options.max_range_m + 1.0);
  std::vector<double> cos_elevation(static_cast<std::size_t>(options.rings));
  std::vector<double> sin_elevation(static_cast<std::size_t>(options.rings));
  for (int r = 0; r < options.rings; ++r) {
    cos_elevation[static_cast<std::size_t>(r)] = std::cos(options.elevation(r));
    sin_elevation[static_cast<std::size_t>(r)] = std::sin(options.elevation(r));
  }
  for (int c = 0; c < options.columns; ++c) {
    const double offset = options.period_s * c / options.columns;
    const core::SE3 T_world_lidar = T_world_lidar_at(scan_start_s + offset);
    const double azimuth = -std::numbers::pi + 2.0 * std::numbers::pi * c / options.columns;
    const double ca = std::cos(azimuth);
    const double sa = std::sin(azimuth);
    for (int r = 0; r < options.rings; ++r) {
      const auto ri = static_cast<std::size_t>(r);
      const Vector3 direction_lidar(cos_elevation[ri] * ca, cos_elevation[ri] * sa, sin_elevation[ri]);
      const Vector3 direction_world = T_world_lidar.so3() * direction_lidar;
      const bool dropout = random.bernoulli(options.dropout_probability);
      const double noise = random.gaussian(options.range_sigma_m);
      const auto hit = cast_ray(local, T_world_lidar.translation(), direction_world, options.max_range_m);
      if (!hit || dropout) continue;
      const double range = *hit + noise;
      if (range <= 0.0 || range >= options.max_range_m) continue;
      points.push_back({range * direction_lidar, offset, r});
    }
  }
  return points;
}

}  // namespace cairn::sim
