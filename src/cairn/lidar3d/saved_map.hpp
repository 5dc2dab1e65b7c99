#pragma once
/// \file
/// A finished 3D LiDAR map as `cairn slam3d --save-map` keeps it for reuse (`cairn localize3d`,
/// issue 42): the global map's points with their surface normals at the final, optimised poses,
/// the keyframes with their poses and Scan Context descriptors, the pose graph over them, and the
/// sensor model (how scans were cropped, corrected and deskewed, and the voxel they were matched
/// at), so a localiser treats new scans exactly as the map's were. make_saved_map() fills it from
/// a finished run; map_file.hpp writes and reads it (the 2D map of slam2d/saved_map.hpp is the
/// model).
///
/// Frames: every pose is T_world_sensor in the map's world frame (the frame of trajectory.tum of
/// `cairn slam3d`, not the ENU frame of trajectory_enu.tum), at the keyframe's registered instant
/// (the sweep's middle).

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/scan_context.hpp"

namespace cairn::lidar3d {

class LidarSlam;
class SlamRun;

/// How the map's scans were turned into points (LidarOdometryOptions' preprocessing and map
/// voxel): a localiser must treat its scans the same way.
struct SavedSensorModel {
  /// kDense or kLoamFeatures: what the mapping odometry actually used (never kAuto).
  FrontEnd front_end = FrontEnd::kDense;
  bool rings_from_kitti_order = false;
  double min_range_m = 0.0;
  double max_range_m = 100.0;
  DeskewMode deskew = DeskewMode::kPointTimes;
  double vertical_angle_correction_rad = 0.0;
  double sweep_period_s = 0.1;
  /// The odometry's voxel v (registration subsamples at 1.5 v, the map at 0.5 v).
  double voxel_size_m = 1.0;
  int max_points_per_voxel = 20;
};

struct SavedKeyframe3D {
  double time_s = 0.0;        ///< the scan's stamp, seconds (the run's clock)
  std::size_t scan = 0;       ///< index of the scan in the mapping run's sequence
  core::SE3 T_world_sensor;   ///< optimised, at the registered instant
  int segment = 0;            ///< map segment of the odometry (SLAM may have joined segments)
  /// Scan Context (scan_context.hpp) of the keyframe's points, `rings` x `sectors` of
  /// SavedMap3D::scan_context; entries >= 0. The ring and sector keys are recomputed from it.
  Eigen::MatrixXf scan_context;
};

/// An edge of the pose graph: odometry between consecutive keyframes, or an accepted loop closure.
struct SavedEdge3D {
  int from = 0;
  int to = 0;
  core::SE3 T_from_to;
  /// Information of the left perturbation (translation, rotation); symmetric positive definite.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  bool loop = false;
};

struct SavedMap3D {
  SavedSensorModel sensor;
  /// The descriptor's geometry and search settings the keyframes' Scan Contexts were made with.
  ScanContextOptions scan_context;
  /// The global map: the keyframes' points as the odometry registered them (range-cropped,
  /// corrected, deskewed, at half the odometry's voxel) at the optimised keyframe poses, one point
  /// per voxel of `map_voxel_m` (outputs.hpp's GlobalMap), world frame; and per point the unit
  /// normal of the plane through its neighbourhood (estimate_normals at the odometry's voxel), or
  /// zero where it is not planar. Same size. (map.ply holds the raw keyframe scans at the map
  /// voxel instead: denser, not deskewed.)
  double map_voxel_m = 0.25;
  std::vector<Eigen::Vector3f> points_world;
  std::vector<Eigen::Vector3f> normals_world;
  std::vector<SavedKeyframe3D> keyframes;
  std::vector<SavedEdge3D> edges;
  /// The mapping run's options (lidar3d::configuration().json, serialised), for the record.
  std::string configuration_json;
  /// Where the map came from (the scans as given), for the report; may be empty.
  std::string source;
};

/// The normal of each of `points` (world frame): the normal of the plane fitted to the points of
/// its voxel of edge `voxel_m` when they are planar, else zero (VoxelHashMap's rule: at least 5
/// points, smallest covariance eigenvalue below 0.1 times the middle one), every point of the
/// voxel taken.
std::vector<Eigen::Vector3f> estimate_normals(const std::vector<Eigen::Vector3f>& points, double voxel_m);

/// The map of a finished run (LidarSlam::finish and SlamRun::finish called): the keyframes'
/// points with normals, the keyframes at their optimised poses with their Scan Contexts, the pose
/// graph, the sensor model of `slam.options().odometry` with the front end it used. With `keep`
/// (one flag per keyframe), only the flagged keyframes and their points enter the map, renumbered
/// in order, with the edges between two kept keyframes (a map of part of a run, e.g. to localise
/// the other scans of the same run in it).
SavedMap3D make_saved_map(const LidarSlam& slam, const SlamRun& run, const std::string& configuration_json,
                          const std::string& source, const std::vector<bool>* keep = nullptr);

}  // namespace cairn::lidar3d
