#include "cairn/lidar3d/voxel_hash_map.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_set>

namespace cairn::lidar3d {

Voxel voxel_of(const Eigen::Vector3d& point, double inverse_voxel_size) {
  return Voxel(static_cast<int>(std::floor(point.x() * inverse_voxel_size)),
               static_cast<int>(std::floor(point.y() * inverse_voxel_size)),
               static_cast<int>(std::floor(point.z() * inverse_voxel_size)));
}

namespace {

/// A voxel's coordinates packed into 63 bits (21 per axis, offset to be non-negative), plus one so
/// that 0 marks an empty slot; false when a coordinate lies outside [-2^20, 2^20) voxels.
bool pack_voxel(const Eigen::Vector3d& point, double inverse_voxel_size, std::uint64_t* key) {
  constexpr double kLimit = 1048576.0;  // 2^20
  const double x = std::floor(point.x() * inverse_voxel_size), y = std::floor(point.y() * inverse_voxel_size),
               z = std::floor(point.z() * inverse_voxel_size);
  if (!(x >= -kLimit && x < kLimit && y >= -kLimit && y < kLimit && z >= -kLimit && z < kLimit)) return false;
  const auto u = [&](double c) { return static_cast<std::uint64_t>(c + kLimit); };
  *key = ((u(x) << 42) | (u(y) << 21) | u(z)) + 1;
  return true;
}

/// voxel_downsample with a node-based set: for coordinates pack_voxel cannot hold.
std::vector<Eigen::Vector3d> voxel_downsample_any(const std::vector<Eigen::Vector3d>& points, double inverse) {
  std::unordered_set<Voxel, VoxelHash> seen;
  seen.reserve(points.size());
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size() / 4);
  for (const Eigen::Vector3d& p : points) {
    if (seen.insert(voxel_of(p, inverse)).second) out.push_back(p);
  }
  return out;
}

}  // namespace

// One open-addressing table of packed voxel keys (linear probing, grown to stay at most half
// full): a scan of 120,000 points is subsampled several times faster than with
// std::unordered_set, whose node per voxel dominated the localiser's preparation of a scan
// (measured on the KITTI key frames). The table starts small: a scan has far fewer voxels than
// points, and zeroing a table sized for the points cost more than the subsampling.
std::vector<Eigen::Vector3d> voxel_downsample(const std::vector<Eigen::Vector3d>& points, double voxel_size_m) {
  const double inverse = 1.0 / voxel_size_m;
  std::vector<std::uint64_t> table(1024, 0);
  std::uint64_t mask = table.size() - 1;
  int shift = 64 - 10;  // Fibonacci hashing: the product's top log2(size) bits, which every key bit reaches
  const auto slot_of = [&](std::uint64_t key) {
    std::uint64_t slot = (key * 0x9E3779B97F4A7C15ull) >> shift;
    while (table[slot] != 0 && table[slot] != key) slot = (slot + 1) & mask;
    return slot;
  };
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size() / 8);
  for (const Eigen::Vector3d& p : points) {
    std::uint64_t key = 0;
    if (!pack_voxel(p, inverse, &key)) return voxel_downsample_any(points, inverse);
    const std::uint64_t slot = slot_of(key);
    if (table[slot] != 0) continue;
    table[slot] = key;
    out.push_back(p);
    if (2 * out.size() > table.size()) {
      std::vector<std::uint64_t> old(table.size() * 2, 0);
      old.swap(table);
      mask = table.size() - 1;
      --shift;
      for (const std::uint64_t k : old) {
        if (k != 0) table[slot_of(k)] = k;
      }
    }
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
