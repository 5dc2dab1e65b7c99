#include "cairn/slam2d/point_map.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

namespace {
std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}
}  // namespace

const PointMap::Cell* PointMap::find(std::uint64_t cell_key) const {
  if (table_.empty()) return nullptr;
  const std::size_t mask = table_.size() - 1;
  for (std::size_t slot = mix(cell_key) & mask;; slot = (slot + 1) & mask) {
    const Cell& cell = table_[slot];
    if (cell.end == 0) return nullptr;
    if (cell.key == cell_key) return &cell;
  }
}

void PointMap::build(const std::vector<Eigen::Vector2d>& points) {
  points_.clear();
  order_.clear();
  table_.clear();
  points_.reserve(points.size());
  std::vector<std::uint64_t> keys;
  keys.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    keys.push_back(key(p));
    points_.push_back(MapPoint{p, Eigen::Vector2d::Zero(), false});
  }
  if (points_.empty()) return;
  // Group the point indices by cell, keeping insertion order within a cell (a stable sort), and
  // index the groups by an open-addressing table: one allocation instead of one per cell.
  order_.resize(points_.size());
  for (std::uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
  std::stable_sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
  std::size_t cells = 0;
  for (std::size_t i = 0; i < order_.size(); ++i)
    if (i == 0 || keys[order_[i]] != keys[order_[i - 1]]) ++cells;
  std::size_t size = 16;
  while (size < 2 * cells) size *= 2;
  table_.assign(size, Cell{});
  const std::size_t mask = size - 1;
  for (std::size_t begin = 0; begin < order_.size();) {
    std::size_t end = begin + 1;
    while (end < order_.size() && keys[order_[end]] == keys[order_[begin]]) ++end;
    const std::uint64_t cell_key = keys[order_[begin]];
    std::size_t slot = mix(cell_key) & mask;
    while (table_[slot].end != 0) slot = (slot + 1) & mask;
    table_[slot] = Cell{cell_key, static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end)};
    begin = end;
  }
  // Normals cell by cell: the points of a cell share their candidate neighbours (the cells within
  // `reach`), gathered once per cell in the same order a per-point scan would visit them, so the
  // sums and the normals are exactly those of the per-point search. The sums are kept as the
  // five distinct scalars of (sum q, sum q q^T).
  const double radius2 = options_.normal_radius_m * options_.normal_radius_m;
  const int reach = static_cast<int>(std::ceil(options_.normal_radius_m / options_.cell_size_m));
  // Cells in parallel (each point's normal is written by one task only: deterministic).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, table_.size(), 64), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<std::uint32_t> candidates;
    for (std::size_t slot = range.begin(); slot != range.end(); ++slot) {
      const Cell& cell = table_[slot];
      if (cell.end == 0) continue;
      const MapPoint& first = points_[order_[cell.begin]];
      const auto ci = static_cast<std::int64_t>(std::floor(first.position.x() / options_.cell_size_m));
      const auto cj = static_cast<std::int64_t>(std::floor(first.position.y() / options_.cell_size_m));
      candidates.clear();
      for (int di = -reach; di <= reach; ++di) {
        for (int dj = -reach; dj <= reach; ++dj) {
          if (const Cell* other = find(key(ci + di, cj + dj)))
            candidates.insert(candidates.end(), order_.begin() + other->begin, order_.begin() + other->end);
        }
      }
      for (std::uint32_t o = cell.begin; o < cell.end; ++o) {
        MapPoint& point = points_[order_[o]];
        double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0;
        int count = 0;
        for (const std::uint32_t k : candidates) {
          const Eigen::Vector2d& q = points_[k].position;
          if ((q - point.position).squaredNorm() > radius2) continue;
          sx += q.x();
          sy += q.y();
          sxx += q.x() * q.x();
          sxy += q.x() * q.y();
          syy += q.y() * q.y();
          ++count;
        }
        if (count < options_.normal_min_neighbours) continue;
        const Eigen::Vector2d mean = Eigen::Vector2d(sx, sy) / count;
        Eigen::Matrix2d outer;
        outer << sxx, sxy, sxy, syy;
        const Eigen::Matrix2d covariance = outer / count - mean * mean.transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
        const double largest = eigen.eigenvalues()(1);
        if (!(largest > 0.0) || eigen.eigenvalues()(0) > options_.normal_max_eigenvalue_ratio * largest) continue;
        point.normal = eigen.eigenvectors().col(0).normalized();
        point.has_normal = true;
      }
    }
  });
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
      const Cell* cell = find(key(i, j));
      if (cell == nullptr) continue;
      for (std::uint32_t o = cell->begin; o < cell->end; ++o) {
        const std::uint32_t k = order_[o];
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
