#include "cairn/slam2d/range_scan.hpp"

#include <cmath>
#include <cstdint>
#include <unordered_set>

namespace cairn::slam2d {
namespace {
std::uint64_t voxel_key(const Eigen::Vector2d& p, double size) {
  const auto i = static_cast<std::int64_t>(std::floor(p.x() / size));
  const auto j = static_cast<std::int64_t>(std::floor(p.y() / size));
  return (static_cast<std::uint64_t>(i) << 32) ^ (static_cast<std::uint64_t>(j) & 0xffffffffULL);
}
}  // namespace

std::vector<Eigen::Vector2d> voxel_filter(const std::vector<Eigen::Vector2d>& points, double size) {
  if (size <= 0.0) return points;
  std::unordered_set<std::uint64_t> seen;
  seen.reserve(points.size() * 2);
  std::vector<Eigen::Vector2d> kept;
  kept.reserve(points.size());
  for (const auto& p : points) {
    if (seen.insert(voxel_key(p, size)).second) kept.push_back(p);
  }
  return kept;
}

ScanPoints preprocess_scan(const io::LaserScan& scan, const ScanFilterOptions& options) {
  ScanPoints out;
  double max_range = options.max_range_m;
  if (scan.geometry.max_range_m && *scan.geometry.max_range_m < max_range) max_range = *scan.geometry.max_range_m;
  std::vector<Eigen::Vector2d> hits;
  hits.reserve(scan.ranges_m.size());
  for (std::size_t k = 0; k < scan.ranges_m.size(); ++k) {
    const double r = scan.ranges_m[k];
    const double a = scan.geometry.start_angle_rad + static_cast<double>(k) * scan.geometry.angular_resolution_rad;
    const Eigen::Vector2d direction(std::cos(a), std::sin(a));
    if (std::isfinite(r) && r >= options.min_range_m && r < max_range) {
      hits.push_back(r * direction);
      ++out.raw_returns;
    } else if (!(r < options.min_range_m)) {
      ++out.no_returns;
      if (options.missing_ray_length_m > 0.0) out.misses.push_back(options.missing_ray_length_m * direction);
    }
  }
  out.hits = voxel_filter(hits, options.voxel_size_m);
  double size = std::max(options.voxel_size_m, 1e-3);
  out.matching = out.hits;
  while (size * 2.0 <= options.adaptive_max_voxel_size_m) {
    auto coarser = voxel_filter(out.hits, size * 2.0);
    if (static_cast<int>(coarser.size()) < options.adaptive_min_points) break;
    out.matching = std::move(coarser);
    size *= 2.0;
  }
  return out;
}

}  // namespace cairn::slam2d
