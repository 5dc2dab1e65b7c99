#pragma once
/// \file
/// The local map of the 3D LiDAR odometry: points in a hash of voxels, as KISS-ICP keeps it
/// (Vizzo et al., "KISS-ICP: In Defense of Point-to-Point ICP", RA-L 2023, Sec. III-C;
/// kiss_icp/core/VoxelHashMap.cpp). Each voxel holds at most `max_points_per_voxel` points (the
/// first ones that arrived), voxels far from the sensor are dropped, and a nearest-neighbour query
/// visits the 27 voxels around the query point, so a neighbour up to one voxel edge away is
/// always found and farther ones sometimes.
///
/// Also the voxel grid subsampling of the same paper (one point per voxel, the first one in
/// input order, "VoxelDownsample" in kiss_icp/core/Preprocessing.cpp).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace cairn::lidar3d {

/// Integer voxel coordinates: floor(p / voxel_size).
using Voxel = Eigen::Vector3i;

Voxel voxel_of(const Eigen::Vector3d& point, double inverse_voxel_size);

struct VoxelHash {
  /// The spatial hash of Teschner et al. 2003 (as KISS-ICP): x*73856093 ^ y*19349669 ^ z*83492791.
  std::size_t operator()(const Voxel& v) const {
    const auto x = static_cast<std::uint32_t>(v.x()), y = static_cast<std::uint32_t>(v.y()),
               z = static_cast<std::uint32_t>(v.z());
    return static_cast<std::size_t>(x * 73856093u ^ y * 19349669u ^ z * 83492791u);
  }
};

/// One point per occupied voxel of edge `voxel_size_m` (> 0): the first of `points` that falls
/// into it, so the result keeps the input's order and is deterministic.
std::vector<Eigen::Vector3d> voxel_downsample(const std::vector<Eigen::Vector3d>& points, double voxel_size_m);

/// A voxel's points are planar when it holds at least `min_points_for_normal` of them and the
/// smallest eigenvalue of their covariance is below `planarity_ratio` times the middle one; its
/// normal is then the eigenvector of the smallest (the plane fit of point-to-plane ICP, Chen &
/// Medioni 1992, and of LOAM's planar features, Zhang & Singh 2014, here per voxel). Its points
/// are linear when the middle eigenvalue is below `linearity_ratio` times the largest; the line's
/// direction is then the eigenvector of the largest (LOAM's edge line, Sec. V-B: "the largest
/// eigenvalue larger than 3 times the second"). Both are refit whenever a voxel gains points.
struct VoxelHashMapOptions {
  /// Voxel edge, metres (> 0). KISS-ICP's default is max_range / 100 = 1 m for a 100 m sensor.
  double voxel_size_m = 1.0;
  /// Points kept per voxel (>= 1); KISS-ICP's default 20.
  int max_points_per_voxel = 20;
  int min_points_for_normal = 5;
  double planarity_ratio = 0.1;
  double linearity_ratio = 1.0 / 3.0;
};

class VoxelHashMap {
 public:
  explicit VoxelHashMap(const VoxelHashMapOptions& options = {});

  /// Adds points given in the map frame; a voxel that is full ignores further points.
  void add_points(const std::vector<Eigen::Vector3d>& points_map);
  /// Drops every voxel whose first point lies farther than `max_distance_m` from `origin_map`.
  void remove_far_from(const Eigen::Vector3d& origin_map, double max_distance_m);
  void clear() { voxels_.clear(); }

  /// The nearest stored point to `query_map` among the 27 voxels around it. Returns false (and
  /// leaves the outputs alone) when those voxels are empty. `normal`, if given, receives the unit
  /// normal of the nearest point's voxel, or zero when that voxel is not planar; `direction` its
  /// line direction, or zero when it is not linear (see VoxelHashMapOptions).
  bool nearest(const Eigen::Vector3d& query_map, Eigen::Vector3d* nearest_map, double* squared_distance,
               Eigen::Vector3d* normal = nullptr, Eigen::Vector3d* direction = nullptr) const;

  /// Every stored point, voxel by voxel (order of the hash table).
  std::vector<Eigen::Vector3d> points() const;
  std::size_t num_voxels() const { return voxels_.size(); }
  std::size_t num_points() const;
  bool empty() const { return voxels_.empty(); }
  const VoxelHashMapOptions& options() const { return options_; }

 private:
  struct Block {
    std::vector<Eigen::Vector3d> points;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();     ///< zero when not planar
    Eigen::Vector3d direction = Eigen::Vector3d::Zero();  ///< zero when not linear
  };
  void fit_normal(Block& block) const;
  VoxelHashMapOptions options_;
  double inverse_voxel_size_;
  std::unordered_map<Voxel, Block, VoxelHash> voxels_;
};

}  // namespace cairn::lidar3d
