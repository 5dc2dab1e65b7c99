#include "cairn/sim/lidar_3d.hpp"

#include <algorithm>
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

bool apply_lidar3d_model(std::string_view model, Lidar3DOptions& options) {
  constexpr double kDegree = std::numbers::pi / 180.0;
  if (model == "vlp16") {
    const Lidar3DOptions defaults;
    options.rings = defaults.rings;
    options.elevation_min_rad = defaults.elevation_min_rad;
    options.elevation_max_rad = defaults.elevation_max_rad;
    options.columns = defaults.columns;
    options.max_range_m = defaults.max_range_m;
    return true;
  }
  if (model == "hdl64") {
    options.rings = 64;
    options.elevation_min_rad = -24.8 * kDegree;
    options.elevation_max_rad = 2.0 * kDegree;
    options.columns = 2000;
    options.max_range_m = 120.0;
    return true;
  }
  return false;
}

std::vector<LidarPoint> spin_scan(const World3D& world, double scan_start_s,
                                  const std::function<core::SE3(double)>& T_world_lidar_at,
                                  const Lidar3DOptions& options, Random& random) {
  std::vector<LidarPoint> points;
  // The sensor's pose at every column's firing time, and how far it moves in the revolution.
  std::vector<core::SE3> T_world_lidar_columns;
  T_world_lidar_columns.reserve(static_cast<std::size_t>(options.columns));
  double motion_radius_m = 0.0;
  for (int c = 0; c < options.columns; ++c) {
    T_world_lidar_columns.push_back(T_world_lidar_at(scan_start_s + options.period_s * c / options.columns));
    motion_radius_m = std::max(motion_radius_m, (T_world_lidar_columns.back().translation().head<2>() -
                                                 T_world_lidar_columns.front().translation().head<2>()).norm());
  }
  // Only objects within reach of the sensor during this revolution (1 m slack for its motion),
  // sorted by azimuth so each ray tests only those in its direction (ray_cast_3d.hpp).
  const Vector2 start_xy = T_world_lidar_columns.front().translation().head<2>();
  const World3D local = nearby(world, start_xy, options.max_range_m + 1.0);
  const AzimuthIndex index(local, start_xy, motion_radius_m + 1e-6);
  std::vector<double> cos_elevation(static_cast<std::size_t>(options.rings));
  std::vector<double> sin_elevation(static_cast<std::size_t>(options.rings));
  for (int r = 0; r < options.rings; ++r) {
    cos_elevation[static_cast<std::size_t>(r)] = std::cos(options.elevation(r));
    sin_elevation[static_cast<std::size_t>(r)] = std::sin(options.elevation(r));
  }
  std::vector<Box> moving_now;
  for (int c = 0; c < options.columns; ++c) {
    const double offset = options.period_s * c / options.columns;
    const core::SE3& T_world_lidar = T_world_lidar_columns[static_cast<std::size_t>(c)];
    moving_now.clear();
    for (const auto& mover : world.moving_boxes) moving_now.push_back(mover.at(scan_start_s + offset));
    const double azimuth = -std::numbers::pi + 2.0 * std::numbers::pi * c / options.columns;
    const double ca = std::cos(azimuth);
    const double sa = std::sin(azimuth);
    for (int r = 0; r < options.rings; ++r) {
      const auto ri = static_cast<std::size_t>(r);
      const Vector3 direction_lidar(cos_elevation[ri] * ca, cos_elevation[ri] * sa, sin_elevation[ri]);
      const Vector3 direction_world = T_world_lidar.so3() * direction_lidar;
      const bool dropout = random.bernoulli(options.dropout_probability);
      const double noise = random.gaussian(options.range_sigma_m);
      auto hit = index.cast(T_world_lidar.translation(), direction_world, options.max_range_m);
      for (const Box& box : moving_now) {
        const auto t = intersect(T_world_lidar.translation(), direction_world, box);
        if (t && *t <= hit.value_or(options.max_range_m)) hit = t;
      }
      if (!hit || dropout) continue;
      const double range = *hit + noise;
      if (range <= 0.0 || range >= options.max_range_m) continue;
      points.push_back({range * direction_lidar, offset, r});
    }
  }
  return points;
}

}  // namespace cairn::sim
