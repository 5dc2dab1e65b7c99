#pragma once
/// \file
/// A range-bearing sensor for point landmarks with known identities (the data association is
/// given, as in the Victoria Park / EKF-SLAM literature). The sensor sits at the body origin.
///
/// A landmark at true range r and bearing b (from the body x axis, counter-clockwise, in
/// (-pi, pi]) is observed when r <= max_range_m, |b| <= field_of_view_rad / 2, nothing in the
/// world blocks the line of sight (if `occlusion`), and a uniform draw is below
/// detection_probability. The observation is
///   range~   = r + range_sigma_m * n1
///   bearing~ = wrap(b + bearing_sigma_rad * n2),       n1, n2 ~ N(0, 1) independent.
/// Each landmark in range and view draws one uniform and two Gaussian variates.

#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

struct RangeBearingOptions {
  /// Farthest landmark seen, metres (> 0).
  double max_range_m = 10.0;
  /// Full field of view centred on the body x axis, rad, in (0, 2 pi].
  double field_of_view_rad = 2.0 * std::numbers::pi;
  /// Noise standard deviations, metres and radians (>= 0).
  double range_sigma_m = 0.05;
  double bearing_sigma_rad = 0.01;
  /// Probability that a visible landmark is reported, in [0, 1].
  double detection_probability = 0.95;
  /// Whether walls and circles hide landmarks behind them.
  bool occlusion = true;
  /// Time between observations, seconds: a multiple of the trajectory's sample period.
  double period_s = 0.1;

  bool is_valid(std::string* why) const;
};

struct LandmarkObservation {
  core::Timestamp stamp;
  std::int64_t landmark_id = 0;
  double range_m = 0.0;
  double bearing_rad = 0.0;
};

/// Observations of every landmark of `world` seen from T_world_body, in landmark order.
std::vector<LandmarkObservation> observe_landmarks(const World& world, const core::SE2& T_world_body,
                                                   core::Timestamp stamp, const RangeBearingOptions& options,
                                                   Random& random);

}  // namespace cairn::sim
