#pragma once
/// \file
/// What `cairn slam3d` writes besides the trajectory: the voxelised global map, a top-down
/// picture of map and trajectory coloured by health, and the trajectory's errors against a
/// ground truth (docs/lidar3d.md). run_outputs.hpp writes them, with the trajectory and
/// report.json, for a whole run (slam_run.hpp).

#include <Eigen/Core>
#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {

/// The global map: one point per voxel of `voxel_size_m` (the first to arrive), in the world
/// frame, with the number of scans that hit each voxel.
class GlobalMap {
 public:
  explicit GlobalMap(double voxel_size_m);
  /// Adds the points of one scan (sensor frame) at `T_world_sensor`.
  void add_scan(const std::vector<Eigen::Vector3d>& points_sensor, const core::SE3& T_world_sensor);
  std::vector<Eigen::Vector3f> points() const;
  /// Takes out the points whose flag is set (one flag per point, in points() order) and returns
  /// them; their voxels stay taken (a later scan does not refill them).
  std::vector<Eigen::Vector3f> remove(const std::vector<bool>& flags);
  std::size_t size() const { return points_.size(); }
  double voxel_size_m() const { return voxel_size_m_; }

 private:
  double voxel_size_m_;
  double inverse_;
  std::vector<Eigen::Vector3f> points_;
  std::unordered_map<Voxel, std::size_t, VoxelHash> voxels_;
};

/// Errors of an estimated trajectory against a ground truth of the same scans (paired by index),
/// each trajectory taken relative to its first pose.
struct TrajectoryErrors {
  std::size_t poses = 0;
  double path_length_m = 0.0;       ///< of the ground truth
  double end_point_error_m = 0.0;   ///< |t_gt(end) - t_est(end)|, both relative to the first pose
  double end_point_error_percent = 0.0;
  /// Relative pose error between consecutive scans, RMSE (evo_rpe -r trans_part / angle_deg,
  /// delta 1 frame).
  double rpe_translation_rmse_m = 0.0;
  double rpe_rotation_rmse_deg = 0.0;
  /// Absolute trajectory error after SE(3) Umeyama alignment, translation RMSE (evo_ape -a).
  /// Empty when the alignment is undetermined (a straight-line trajectory fixes no rotation
  /// about its line); `ate_note` then says why.
  std::optional<double> ate_rmse_m;
  std::string ate_note;
  /// KITTI devkit t_err (%) and r_err (deg/100 m) over 100..800 m segments, when the
  /// trajectory is long enough for one.
  std::optional<double> kitti_translation_percent;
  std::optional<double> kitti_rotation_deg_per_100m;
};

/// Throws std::invalid_argument when the sizes differ or are below 2, std::runtime_error when the
/// RPE fails.
TrajectoryErrors evaluate_trajectory(const std::vector<core::SE3>& ground_truth, const std::vector<core::SE3>& estimate);

/// A PNG: the map seen from above (points shaded by height), the trajectory coloured by health
/// (blue ok, orange degraded, red lost; a gap where a new map segment starts) and, if given, the
/// ground truth aligned by SE(3) Umeyama in grey; legend and scale bar.
/// The longer side is at most `max_side_px` pixels (>= 200).
std::vector<unsigned char> render_top_down(const std::vector<Eigen::Vector3f>& map_points,
                                           const std::vector<OdometryScanResult>& scans,
                                           const std::vector<core::SE3>& ground_truth, int max_side_px = 1600);

}  // namespace cairn::lidar3d
