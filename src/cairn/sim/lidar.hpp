#pragma once
/// \file
/// A planar scanning LiDAR: `beams` rays from the laser origin at angles
/// angle_min_rad + i * angle_increment_rad (i = 0 .. beams-1) in the laser frame (x forward,
/// y left, counter-clockwise positive: the CARMEN and ROS LaserScan convention), cast exactly
/// against the world (ray_cast.hpp). The scan is taken at one instant (no motion distortion).
///
/// Noise model per beam, in this order:
///  1. no surface within max_range_m: the reading is max_range_m (CARMEN's "no return");
///  2. dropout: with probability dropout_probability the reading is max_range_m;
///  3. otherwise reading = true range + range_sigma_m * n, n ~ N(0, 1); a reading pushed to or
///     beyond max_range_m is reported as max_range_m, one pushed below 0 as 0;
///  4. the reading is rounded to range_decimals decimals (3 = 1 mm, the SICK LMS resolution;
///     -1 keeps full precision).
/// Every beam draws one uniform and one Gaussian variate, whatever happened to it.

#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

struct LidarOptions {
  /// Number of beams, in [1, 10000]. 180 at 1 degree is the SICK LMS setting of the Freiburg logs.
  int beams = 180;
  /// Angle of beam 0 in the laser frame, rad.
  double angle_min_rad = -std::numbers::pi / 2;
  /// Angle between neighbouring beams, rad (> 0).
  double angle_increment_rad = std::numbers::pi / 180;
  /// Largest range, metres (> 0); misses and dropouts read exactly this.
  double max_range_m = 30.0;
  /// Standard deviation of the Gaussian range noise, metres (>= 0).
  double range_sigma_m = 0.01;
  /// Probability that a beam returns nothing (reads max_range_m), in [0, 1].
  double dropout_probability = 0.01;
  /// Decimals the readings are rounded to (0..9), or -1 for none.
  int range_decimals = 3;
  /// The laser sits this far ahead of the body origin on the body's x axis, metres (CARMEN's
  /// robot_frontlaser_offset). T_body_laser = (offset, 0, 0).
  double forward_offset_m = 0.0;
  /// Time between scans, seconds: a multiple of the trajectory's sample period.
  double period_s = 0.1;

  bool is_valid(std::string* why) const;
  core::SE2 T_body_laser() const { return core::SE2(forward_offset_m, 0.0, 0.0); }
  double beam_angle(int i) const { return angle_min_rad + i * angle_increment_rad; }
};

/// Exact ranges (no noise): max_range_m where no surface lies within range. Walkers are placed
/// where they are at `time_s`.
std::vector<double> ideal_scan(const World& world, const core::SE2& T_world_laser, const LidarOptions& options,
                               double time_s = 0.0);

/// Applies the noise model (steps 2-4 of the file comment) to an ideal scan.
std::vector<double> add_scan_noise(const std::vector<double>& ideal, const LidarOptions& options, Random& random);

/// Rounds `range_m` to `decimals` decimals (-1: unchanged), as the sensor does.
double round_range(double range_m, int decimals);

}  // namespace cairn::sim
