#pragma once
/// \file
/// LOAM's feature points (Zhang & Singh, "LOAM: Lidar Odometry and Mapping in Real-time", RSS 2014,
/// Sec. V-A): per ring, the smoothness of each point over its neighbours along the ring,
///   c_i = || sum_{j in S, j != i} (p_j - p_i) || / (|S| ||p_i||)        (eq. 1)
/// (S: `neighbours` points on either side); each ring is cut into `sectors_per_ring` sectors of
/// equal point count, and in each the points of largest c above `edge_curvature` become edge
/// points and those of smallest c below `plane_curvature` planar points, never two picks within
/// `neighbours` points of each other. Points next to a depth jump (an occluded edge) or on a
/// surface nearly parallel to the beam are unreliable and never picked (Sec. V-A, Fig. 4).
/// As A-LOAM: "sharp" (few per sector, matched against the map) and "less sharp" (more, added to
/// the map) edges; "flat" and "less flat" (every non-edge point, subsampled) planes.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace cairn::lidar3d {

struct LoamFeatureOptions {
  /// True when usable; otherwise false with every problem in *why (neighbours and sectors index
  /// into a ring, so both are bounded).
  bool is_valid(std::string* why) const;
  int neighbours = 5;               ///< |S| / 2 of eq. 1 (LOAM: 5)
  int sectors_per_ring = 6;         ///< LOAM: 6
  int sharp_per_sector = 2;         ///< LOAM: 2
  int less_sharp_per_sector = 20;   ///< A-LOAM: 20
  int flat_per_sector = 4;          ///< LOAM: 4
  double edge_curvature = 0.1;      ///< A-LOAM's threshold on c
  double plane_curvature = 0.1;
  /// A neighbour more than this fraction of the range nearer or farther marks a depth jump.
  double depth_jump_ratio = 0.1;
  double less_flat_voxel_m = 0.2;   ///< subsampling of the less-flat points (A-LOAM: 0.2 m)
};

struct LoamFeatures {
  std::vector<Eigen::Vector3d> sharp;
  std::vector<Eigen::Vector3d> less_sharp;  ///< includes sharp
  std::vector<Eigen::Vector3d> flat;
  std::vector<Eigen::Vector3d> less_flat;   ///< includes flat, subsampled
};

/// Features of one scan. `ring[i]` is the laser of `points[i]`; within a ring the points are put
/// in azimuth order first, so any storage order works. Rings with fewer than 2 neighbours + 1
/// points give nothing. Precondition: equal sizes.
LoamFeatures extract_loam_features(const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint16_t>& ring,
                                   const LoamFeatureOptions& options = {});

}  // namespace cairn::lidar3d
