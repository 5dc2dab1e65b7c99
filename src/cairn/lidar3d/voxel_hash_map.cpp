#include "cairn/lidar3d/voxel_hash_map.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <unordered_set>

namespace cairn::lidar3d {

Voxel voxel_of(const Eigen::Vector3d& point, double inverse_voxel_size) {
  return Voxel(static_cast<int>(std::floor(point.x() * inverse_voxel_size)),
               static_cast<int>(std::floor(point.y() * inverse_voxel_size)),
               static_cast<int>(std::floor(point.z() * inverse_voxel_size)));
}

std::vector<Eigen::Vector3d> voxel_downsample(const std::vector<Eigen::Vector3d>& points, double voxel_size_m) {
  const double inverse = 1.0 / voxel_size_m;
  std::unordered_set<Voxel, VoxelHash> seen;
  seen.reserve(points.size());
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size() / 4);
  for (const Eigen::Vector3d& p : points) {
    if (seen.insert(voxel_of(p, inverse)).second) out.push_back(p);
  }
  return out;
}

VoxelHashMap::VoxelHashMap(const VoxelHashMapOptions& options)
    : options_(options), inverse_voxel_size_(1.0 / options.voxel_size_m) {}

void VoxelHashMap::add_points(const std::vector<Eigen::Vector3d>& points_map) {
  const auto capacity = static_cast<std::size_t>(options_.max_points_per_voxel);
  std::vector<Block*> changed;
  for (const Eigen::Vector3d& p : points_map) {
    Block& block = voxels_[voxel_of(p, inverse_voxel_size_)];
    if (block.points.size() < capacity) {
      if (block.points.empty()) block.points.reserve(capacity);
      block.points.push_back(p);
      if (block.points.size() >= static_cast<std::size_t>(options_.min_points_for_normal) &&
          (changed.empty() || changed.back() != &block)) {
        changed.push_back(&block);
      }
    }
  }
  // A block may be listed more than once (points of a voxel need not be consecutive): refitting
  // twice gives the same normal.
  for (Block* block : changed) fit_normal(*block);
}

void VoxelHashMap::fit_normal(Block& block) const {
  const auto n = static_cast<double>(block.points.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : block.points) mean += p;
  mean /= n;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : block.points) covariance.noalias() += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance / n);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  block.normal = lambda(0) < options_.planarity_ratio * lambda(1) ? Eigen::Vector3d(eigen.eigenvectors().col(0))
                                                                  : Eigen::Vector3d::Zero();
  block.direction = lambda(1) < options_.linearity_ratio * lambda(2) ? Eigen::Vector3d(eigen.eigenvectors().col(2))
                                                                     : Eigen::Vector3d::Zero();
}

void VoxelHashMap::remove_far_from(const Eigen::Vector3d& origin_map, double max_distance_m) {
  const double max_squared = max_distance_m * max_distance_m;
  for (auto it = voxels_.begin(); it != voxels_.end();) {
    if (it->second.points.empty() || (it->second.points.front() - origin_map).squaredNorm() > max_squared) {
      it = voxels_.erase(it);
    } else {
      ++it;
    }
  }
}

bool VoxelHashMap::nearest(const Eigen::Vector3d& query_map, Eigen::Vector3d* nearest_map,
                           double* squared_distance, Eigen::Vector3d* normal, Eigen::Vector3d* direction) const {
  const Voxel center = voxel_of(query_map, inverse_voxel_size_);
  double best = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d* best_point = nullptr;
  const Block* best_block = nullptr;
  auto search = [&](const Voxel& voxel) {
    const auto it = voxels_.find(voxel);
    if (it == voxels_.end()) return;
    for (const Eigen::Vector3d& p : it->second.points) {
      const double d = (p - query_map).squaredNorm();
      if (d < best) {
        best = d;
        best_point = &p;
        best_block = &it->second;
      }
    }
  };
  // The query's own voxel first; a neighbour is then visited only if its box comes nearer to
  // the query than the best point so far. The result is the nearest point of the 27 voxels,
  // exactly as a search of all of them, with far fewer hash lookups once ICP has converged
  // (the neighbour is then usually centimetres away, the voxel faces decimetres).
  search(center);
  const double size = options_.voxel_size_m;
  const Eigen::Vector3d low = center.cast<double>() * size;
  // Squared distance from the query to the slab of the neighbour at offset -1, 0, +1 per axis.
  Eigen::Matrix<double, 3, 3> slab;
  for (int axis = 0; axis < 3; ++axis) {
    const double below = query_map(axis) - low(axis);
    const double above = low(axis) + size - query_map(axis);
    slab(axis, 0) = below * below;
    slab(axis, 1) = 0.0;
    slab(axis, 2) = above * above;
  }
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const double box = slab(0, dx + 1) + slab(1, dy + 1) + slab(2, dz + 1);
        if (box >= best) continue;
        search(Voxel(center.x() + dx, center.y() + dy, center.z() + dz));
      }
    }
  }
  if (best_point == nullptr) return false;
  *nearest_map = *best_point;
  *squared_distance = best;
  if (normal != nullptr) *normal = best_block->normal;
  if (direction != nullptr) *direction = best_block->direction;
  return true;
}

std::vector<Eigen::Vector3d> VoxelHashMap::points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(num_points());
  for (const auto& [voxel, block] : voxels_) out.insert(out.end(), block.points.begin(), block.points.end());
  return out;
}

std::size_t VoxelHashMap::num_points() const {
  std::size_t n = 0;
  for (const auto& [voxel, block] : voxels_) n += block.points.size();
  return n;
}

}  // namespace cairn::lidar3d
