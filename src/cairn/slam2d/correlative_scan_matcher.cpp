#include "cairn/slam2d/correlative_scan_matcher.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::slam2d {

MatchResult match_exhaustive(const ProbabilityGrid& grid, const std::vector<Eigen::Vector2d>& points_sensor,
                             const core::SE2& initial, const CorrelativeMatcherOptions& options) {
  CAIRN_ASSERT(!points_sensor.empty(), "match_exhaustive needs at least one point");
  CAIRN_ASSERT(options.linear_search_window_m >= 0.0 && options.angular_search_window_rad >= 0.0,
               "search windows must be >= 0");
  const double r = grid.resolution();
  double d_max = 0.0;
  for (const auto& p : points_sensor) d_max = std::max(d_max, p.norm());
  // Hess 2016, eq. (7).
  const double angular_step = d_max > r ? std::acos(1.0 - r * r / (2.0 * d_max * d_max)) : 0.1;
  const int angular_steps = static_cast<int>(std::ceil(options.angular_search_window_rad / angular_step));
  const int linear_steps = static_cast<int>(std::ceil(options.linear_search_window_m / r));
  MatchResult best;
  best.T_map_sensor = initial;
  best.score = -1.0;
  best.angular_step_rad = angular_step;
  std::vector<Eigen::Vector2d> rotated(points_sensor.size());
  for (int a = -angular_steps; a <= angular_steps; ++a) {
    const core::SO2 R = initial.so2() * core::SO2(a * angular_step);
    for (std::size_t k = 0; k < points_sensor.size(); ++k) rotated[k] = R * points_sensor[k];
    for (int ix = -linear_steps; ix <= linear_steps; ++ix) {
      for (int iy = -linear_steps; iy <= linear_steps; ++iy) {
        const Eigen::Vector2d t = initial.translation() + Eigen::Vector2d(ix * r, iy * r);
        double sum = 0.0;
        for (const auto& p : rotated) sum += grid.probability(p + t);
        const double score = sum / static_cast<double>(rotated.size());
        ++best.candidates;
        if (score > best.score) {
          best.score = score;
          best.T_map_sensor = core::SE2(R, t);
        }
      }
    }
  }
  return best;
}

}  // namespace cairn::slam2d
