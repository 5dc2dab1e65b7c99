#pragma once
/// \file
/// A spinning multi-ring LiDAR (Velodyne-style). The head turns counter-clockwise at
/// 1 / period_s revolutions per second; column c (of `columns`) fires at
/// t = t_scan + period_s * c / columns, all rings at once, at azimuth -pi + 2 pi c / columns
/// (the first column looks backwards, as a Velodyne's packet boundary), ring r at elevation
/// elevation_min_rad + r (elevation_max_rad - elevation_min_rad) / (rings - 1). Each ray is cast
/// from the sensor's pose **at its own firing time**, and the point is reported in the sensor
/// frame at that time with its time offset: a moving robot therefore distorts the scan exactly
/// as a real spinning sensor does, and de-skewing can be checked against the truth.
///
/// Moving boxes (World3D::moving_boxes) are placed at each column's firing time.
///
/// Noise: no return within max range or a dropout (probability dropout_probability): no point;
/// otherwise range = true range + range_sigma_m * n, n ~ N(0, 1). Every ray draws one uniform
/// and one Gaussian variate.

#include <functional>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/world_3d.hpp"

namespace cairn::sim {

struct Lidar3DOptions {
  /// Rings, in [2, 128], and their elevations, rad (VLP-16: 16 rings over -15..+15 degrees).
  int rings = 16;
  double elevation_min_rad = -15.0 * std::numbers::pi / 180.0;
  double elevation_max_rad = 15.0 * std::numbers::pi / 180.0;
  /// Columns per revolution, in [1, 4000].
  int columns = 360;
  /// Time of one revolution = time between scans, seconds.
  double period_s = 0.1;
  double max_range_m = 60.0;
  double range_sigma_m = 0.02;
  double dropout_probability = 0.005;
  /// Height of the sensor above the body origin, metres (T_body_lidar = (0, 0, h), no rotation).
  double mount_height_m = 1.8;

  bool is_valid(std::string* why) const;
  double elevation(int ring) const {
    return elevation_min_rad + ring * (elevation_max_rad - elevation_min_rad) / (rings - 1);
  }
};

struct LidarPoint {
  /// In the sensor frame at the firing time, metres.
  Vector3 position = Vector3::Zero();
  /// Seconds after the scan's start time.
  double time_offset_s = 0.0;
  int ring = 0;
};

/// Sets rings, elevations, columns and max range to those of a sensor model, leaving the rest:
///  - "vlp16" (the defaults above): 16 rings over -15..+15 deg, 360 columns (1 deg), 60 m.
///  - "hdl64" (a Velodyne HDL-64E as in KITTI): 64 rings evenly spaced over -24.8..+2 deg (the
///    real sensor's two laser blocks are spaced unevenly), 2000 columns (0.18 deg), 120 m.
/// Returns false (options untouched) for any other name.
bool apply_lidar3d_model(std::string_view model, Lidar3DOptions& options);

/// One revolution starting at `scan_start_s`. `T_world_lidar_at(t)` gives the sensor pose at
/// any time of the revolution (the simulator interpolates its ground truth).
std::vector<LidarPoint> spin_scan(const World3D& world, double scan_start_s,
                                  const std::function<core::SE3(double)>& T_world_lidar_at,
                                  const Lidar3DOptions& options, Random& random);

}  // namespace cairn::sim
