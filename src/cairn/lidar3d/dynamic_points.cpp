#include "cairn/lidar3d/dynamic_points.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {
namespace {

/// The evidence about one map point, counted once per keyframe (the last keyframe that counted).
struct Evidence {
  int hits = 0;
  int see_through = 0;
  int last_hit = -1;
  int last_see_through = -1;
};

/// The map points by voxel, with their evidence.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3f>& points, double voxel_m)
      : points_(points), inverse_(1.0 / voxel_m), voxel_m_(voxel_m), evidence_(points.size()) {
    for (std::size_t i = 0; i < points.size(); ++i) cells_[voxel_of(points[i].cast<double>(), inverse_)].push_back(static_cast<std::uint32_t>(i));
  }

  /// A keyframe's point at `q_world` hits every map point within `radius` of it.
  void hit(const Eigen::Vector3d& q_world, double radius, int keyframe) {
    const Voxel center = voxel_of(q_world, inverse_);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(center + Voxel(dx, dy, dz));
          if (it == cells_.end()) continue;
          for (const std::uint32_t i : it->second) {
            Evidence& e = evidence_[i];
            if (e.last_hit == keyframe || (points_[i].cast<double>() - q_world).norm() > radius) continue;
            e.last_hit = keyframe;
            ++e.hits;
          }
        }
      }
    }
  }

  /// The ray from `origin` to `end` sees through every map point in the voxels it crosses that
  /// lies within `radius` of it and at least `margin` before its end (Amanatides & Woo's
  /// traversal, 1987).
  void see_through(const Eigen::Vector3d& origin, const Eigen::Vector3d& end, double radius, double margin, int keyframe) {
    const Eigen::Vector3d d = end - origin;
    const double length = d.norm();
    const double stop = length - margin;
    if (!(stop > 0.0)) return;
    const Eigen::Vector3d dir = d / length;
    Voxel v = voxel_of(origin, inverse_);
    Eigen::Vector3i step;
    Eigen::Vector3d t_max, t_delta;
    for (int a = 0; a < 3; ++a) {
      step[a] = dir[a] > 0.0 ? 1 : -1;
      const double boundary = (v[a] + (dir[a] > 0.0 ? 1 : 0)) * voxel_m_;
      t_max[a] = dir[a] != 0.0 ? (boundary - origin[a]) / dir[a] : std::numeric_limits<double>::infinity();
      t_delta[a] = dir[a] != 0.0 ? voxel_m_ / std::abs(dir[a]) : std::numeric_limits<double>::infinity();
    }
    for (double t = 0.0; t <= stop;) {
      visit(v, origin, dir, stop, radius, keyframe);
      int a = 0;
      if (t_max[1] < t_max[a]) a = 1;
      if (t_max[2] < t_max[a]) a = 2;
      t = t_max[a];
      v[a] += step[a];
      t_max[a] += t_delta[a];
    }
  }

  const Evidence& evidence(std::size_t i) const { return evidence_[i]; }

 private:
  void visit(const Voxel& v, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double stop, double radius, int keyframe) {
    const auto it = cells_.find(v);
    if (it == cells_.end()) return;
    for (const std::uint32_t i : it->second) {
      Evidence& e = evidence_[i];
      if (e.last_see_through == keyframe) continue;
      const Eigen::Vector3d op = points_[i].cast<double>() - origin;
      const double s = op.dot(dir);
      if (s < 0.0 || s > stop || (op - s * dir).norm() > radius) continue;
      e.last_see_through = keyframe;
      ++e.see_through;
    }
  }

  const std::vector<Eigen::Vector3f>& points_;
  double inverse_;
  double voxel_m_;
  std::unordered_map<Voxel, std::vector<std::uint32_t>, VoxelHash> cells_;
  std::vector<Evidence> evidence_;
};

/// The lowest map point of each 1 m column.
std::unordered_map<Voxel, float, VoxelHash> column_floors(const std::vector<Eigen::Vector3f>& points) {
  std::unordered_map<Voxel, float, VoxelHash> floors;
  for (const Eigen::Vector3f& p : points) {
    const Voxel column(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())), 0);
    const auto [it, inserted] = floors.try_emplace(column, p.z());
    if (!inserted) it->second = std::min(it->second, p.z());
  }
  return floors;
}

}  // namespace

bool DynamicPointOptions::is_valid(std::string* why) const {
  core::Problems p;
  p.require_positive(point_radius_m, "point_radius_m");
  p.require_positive(hit_radius_m, "hit_radius_m");
  p.require_positive(ray_voxel_m, "ray_voxel_m");
  p.require_positive(max_range_m, "max_range_m");
  if (!(end_margin_m >= 0.0)) p.add("end_margin_m must be >= 0");
  if (!(end_margin_fraction >= 0.0 && end_margin_fraction < 1.0)) p.add("end_margin_fraction must be in [0, 1)");
  if (!(ground_clearance_m >= 0.0)) p.add("ground_clearance_m must be >= 0");
  if (min_see_through < 1) p.add("min_see_through must be >= 1");
  p.require_positive(see_through_ratio, "see_through_ratio");
  return p.report(why);
}

std::vector<bool> find_dynamic_points(const std::vector<Eigen::Vector3f>& points_world,
                                      const std::vector<KeyframeRays>& keyframes, const DynamicPointOptions& options,
                                      DynamicPointSummary* summary) {
  const auto start = core::Clock::now();
  // Voxels as large as the hit radius, so a hit's neighbours lie in the 27 voxels around it.
  PointGrid grid(points_world, std::max({0.5, options.hit_radius_m, options.point_radius_m}));
  std::size_t rays = 0;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const KeyframeRays& kf = keyframes[k];
    const int id = static_cast<int>(k);
    const Eigen::Vector3d origin = kf.T_world_sensor.translation();
    for (const Eigen::Vector3d& p : *kf.points_sensor) grid.hit(kf.T_world_sensor * p, options.hit_radius_m, id);
    for (const Eigen::Vector3d& p : voxel_downsample(*kf.points_sensor, options.ray_voxel_m)) {
      const double range = p.norm();
      if (!(range <= options.max_range_m) || range == 0.0) continue;
      const Eigen::Vector3d q = kf.T_world_sensor * p;
      grid.see_through(origin, q, options.point_radius_m, options.end_margin_m + options.end_margin_fraction * range, id);
      ++rays;
    }
  }
  const std::unordered_map<Voxel, float, VoxelHash> floors = column_floors(points_world);
  std::vector<bool> dynamic(points_world.size(), false);
  DynamicPointSummary s;
  s.points = points_world.size();
  s.rays = rays;
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    const Evidence& e = grid.evidence(i);
    if (e.see_through < options.min_see_through || e.see_through < options.see_through_ratio * e.hits) continue;
    const Eigen::Vector3f& p = points_world[i];
    const float floor = floors.at(Voxel(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())), 0));
    if (static_cast<double>(p.z() - floor) <= options.ground_clearance_m) {
      ++s.ground_exempt;
      continue;
    }
    dynamic[i] = true;
    ++s.dynamic;
  }
  s.time_s = core::seconds_since(start);
  if (summary != nullptr) *summary = s;
  return dynamic;
}

}  // namespace cairn::lidar3d
