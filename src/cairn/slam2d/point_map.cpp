#include "cairn/slam2d/point_map.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::slam2d {

PointMap::PointMap(const PointMapOptions& options) : options_(options) {
  CAIRN_ASSERT(options.cell_size_m > 0.0 && options.normal_radius_m > 0.0, "invalid PointMapOptions");
}

std::uint64_t PointMap::key(std::int64_t i, std::int64_t j) {
  return (static_cast<std::uint64_t>(i) << 32) ^ (static_cast<std::uint64_t>(j) & 0xffffffffULL);
}

std::uint64_t PointMap::key(const Eigen::Vector2d& p) const {
  return key(static_cast<std::int64_t>(std::floor(p.x() / options_.cell_size_m)),
             static_cast<std::int64_t>(std::floor(p.y() / options_.cell_size_m)));
}

void PointMap::build(const std::vector<Eigen::Vector2d>& points) {
  points_.clear();
  cells_.clear();
  points_.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    cells_[key(p)].push_back(static_cast<std::uint32_t>(points_.size()));
    points_.push_back(MapPoint{p, Eigen::Vector2d::Zero(), false});
  }
  const double radius2 = options_.normal_radius_m * options_.normal_radius_m;
  const int reach = static_cast<int>(std::ceil(options_.normal_radius_m / options_.cell_size_m));
  for (auto& point : points_) {
    const auto ci = static_cast<std::int64_t>(std::floor(point.position.x() / options_.cell_size_m));
    const auto cj = static_cast<std::int64_t>(std::floor(point.position.y() / options_.cell_size_m));
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
    int count = 0;
    for (int di = -reach; di <= reach; ++di) {
      for (int dj = -reach; dj <= reach; ++dj) {
        const auto it = cells_.find(key(ci + di, cj + dj));
        if (it == cells_.end()) continue;
        for (const std::uint32_t k : it->second) {
          const Eigen::Vector2d& q = points_[k].position;
          if ((q - point.position).squaredNorm() > radius2) continue;
          sum += q;
          outer += q * q.transpose();
          ++count;
        }
      }
    }
    if (count < options_.normal_min_neighbours) continue;
    const Eigen::Vector2d mean = sum / count;
    const Eigen::Matrix2d covariance = outer / count - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
    const double largest = eigen.eigenvalues()(1);
    if (!(largest > 0.0) || eigen.eigenvalues()(0) > options_.normal_max_eigenvalue_ratio * largest) continue;
    point.normal = eigen.eigenvectors().col(0).normalized();
    point.has_normal = true;
  }
}

const MapPoint* PointMap::nearest(const Eigen::Vector2d& query, double max_distance_m) const {
  // Only the cells the disc of radius max_distance_m touches (1 to 4 of the 3 x 3 around the
  // query when the radius is below half a cell, as in ICP's final iterations).
  const double r = std::min(max_distance_m, options_.cell_size_m);
  const double c = options_.cell_size_m;
  const auto i_low = static_cast<std::int64_t>(std::floor((query.x() - r) / c));
  const auto i_high = static_cast<std::int64_t>(std::floor((query.x() + r) / c));
  const auto j_low = static_cast<std::int64_t>(std::floor((query.y() - r) / c));
  const auto j_high = static_cast<std::int64_t>(std::floor((query.y() + r) / c));
  const MapPoint* best = nullptr;
  double best_d2 = max_distance_m * max_distance_m;
  for (std::int64_t i = i_low; i <= i_high; ++i) {
    for (std::int64_t j = j_low; j <= j_high; ++j) {
      const auto it = cells_.find(key(i, j));
      if (it == cells_.end()) continue;
      for (const std::uint32_t k : it->second) {
        const double d2 = (points_[k].position - query).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best = &points_[k];
        }
      }
    }
  }
  return best;
}

}  // namespace cairn::slam2d
