#pragma once
/// \file
/// Points seen on something that moved, found by free-space carving over the keyframes (issue 42,
/// "maps without moving objects"): a map point is dynamic when the laser of other keyframes passed
/// through where it lies: something stood there once and was gone later (or earlier). This is the
/// free-space update of occupancy mapping (OctoMap: Hornung et al., Autonomous Robots 2013), done
/// per point rather than per voxel, in the spirit of Removert's "seen through" test (Kim & Kim,
/// IROS 2020), with the voxel traversal of Amanatides & Woo (Eurographics 1987) to visit the points
/// near each ray, and a ground exemption as ERASOR's (Lim, Oh & Myung, RA-L 2021) keeps the road.
///
/// For every keyframe, rays go from its sensor to its points (one per `ray_voxel_m` voxel, within
/// `max_range_m`). A map point p is *seen through* by that keyframe when one of its rays passes
/// within `point_radius_m` of p and ends at least `end_margin_m` + `end_margin_fraction` x range
/// beyond it (a ray grazing a surface near its end is not evidence: a ray to the ground 20 m away
/// runs within 0.3 m of the ground over its last metres); p is *hit* by the keyframe when one of
/// its points lies within hit_radius_m of p. p is dynamic when at least `min_see_through`
/// keyframes saw through it and `see_through_ratio` times as many as hit it, unless it lies within
/// `ground_clearance_m` of the lowest map point of its 1 m column (the ground under a car that
/// drove by is seen through at grazing angles, and is static).

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"

namespace cairn::lidar3d {

struct DynamicPointOptions {
  double point_radius_m = 0.25;      ///< > 0
  /// A keyframe hits a map point when any of its points (all of them, not only the rays') lies
  /// within this distance: near the spacing of the keyframes' points (the odometry keeps one per
  /// half voxel, 0.5 m), or surfaces seen by many keyframes count few hits; not much more, or the
  /// road next to a car's lowest points counts as hitting them. > 0.
  double hit_radius_m = 0.4;
  double ray_voxel_m = 1.0;          ///< > 0
  double max_range_m = 40.0;         ///< > 0
  double end_margin_m = 1.0;         ///< >= 0
  double end_margin_fraction = 0.1;  ///< in [0, 1)
  double ground_clearance_m = 0.3;   ///< >= 0
  int min_see_through = 2;           ///< >= 1
  /// ... and at least this many times as many as hit it (> 0).
  double see_through_ratio = 1.0;
  bool is_valid(std::string* why) const;
};

/// A keyframe's rays: its points in its sensor frame and the sensor's pose.
struct KeyframeRays {
  const std::vector<Eigen::Vector3d>* points_sensor = nullptr;
  core::SE3 T_world_sensor;
};

struct DynamicPointSummary {
  std::size_t points = 0;
  std::size_t dynamic = 0;
  std::size_t rays = 0;
  std::size_t ground_exempt = 0;  ///< points that would be dynamic but lie on the ground
  double time_s = 0.0;
};

/// One flag per point of `points_world`: seen on something that moved (see the file comment).
/// Preconditions: options.is_valid(), every KeyframeRays::points_sensor non-null.
std::vector<bool> find_dynamic_points(const std::vector<Eigen::Vector3f>& points_world,
                                      const std::vector<KeyframeRays>& keyframes, const DynamicPointOptions& options,
                                      DynamicPointSummary* summary = nullptr);

}  // namespace cairn::lidar3d
