#pragma once
/// \file
/// The record of one run of LidarSlam over a scan sequence, kept while the scans are fed: each
/// processed scan's result and its index in the sequence, the files skipped as unreadable, the
/// time to read each file, and the keyframes' points at the map's voxel. After the last scan,
/// `finish` moves every scan to its final (loop-corrected) pose and assembles the global map
/// there. What the run's outputs (run_outputs.hpp) and report (report.hpp) are made of.

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/dynamic_points.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/slam.hpp"

namespace cairn::lidar3d {

/// A scan file that could not be read, and the reader's message.
struct SkippedScan {
  std::string file;
  std::string error;
};

/// Processed scans by health, and those whose per-point times were unusable.
struct HealthCounts {
  std::size_t ok = 0;
  std::size_t degraded = 0;
  std::size_t lost = 0;
  std::size_t unusable_point_times = 0;  ///< OdometryScanResult::point_times_unusable
};

class SlamRun {
 public:
  /// A keyframe's points are kept between the odometry's `min_range_m` and `max_range_m` (from the
  /// sensor), with its vertical-angle correction, at `map_voxel_m` (> 0; throws std::invalid_argument otherwise), the voxel of the
  /// global map.
  SlamRun(const LidarOdometryOptions& odometry, double map_voxel_m);

  /// Scan `sequence_index` of the sequence, read in `read_s` seconds, gave `result`.
  void add_scan(std::size_t sequence_index, const io::PointCloud& cloud, const SlamScanResult& result, double read_s);
  void add_skipped(const std::string& file, const std::string& error);
  /// After the last scan (and LidarSlam::finish, unless the run was cut short): every scan takes
  /// its pose from `slam.trajectory()`, and the keyframes' points go into the global map at their
  /// scans' poses.
  void finish(const LidarSlam& slam);
  /// After finish: the global map's points seen on something that moved (dynamic_points.hpp, the
  /// keyframes' points as rays) leave it for dynamic_points(); later saved maps leave out theirs
  /// too (make_saved_map). Precondition: options.is_valid().
  void remove_dynamic_points(const LidarSlam& slam, const DynamicPointOptions& options);

  /// The processed scans in order; poses final after finish().
  const std::vector<OdometryScanResult>& scans() const { return scans_; }
  /// Index in the sequence of each processed scan.
  const std::vector<std::size_t>& sequence_indices() const { return sequence_indices_; }
  const std::vector<SkippedScan>& skipped() const { return skipped_; }
  /// Seconds to read each processed scan's file.
  const std::vector<double>& read_times_s() const { return read_times_s_; }
  /// Empty before finish().
  const GlobalMap& global_map() const { return global_map_; }
  /// The points remove_dynamic_points took out of the global map, and what it found; empty /
  /// unset when it was not called.
  const std::vector<Eigen::Vector3f>& dynamic_points() const { return dynamic_points_; }
  const std::optional<DynamicPointOptions>& dynamic_options() const { return dynamic_options_; }
  const DynamicPointSummary& dynamic_summary() const { return dynamic_summary_; }
  double map_voxel_m() const { return global_map_.voxel_size_m(); }

  HealthCounts health_counts() const;
  /// T_world_sensor of each processed scan.
  std::vector<core::SE3> poses() const;
  /// The poses of `ground_truth` (one per scan of the sequence, or none) of the processed scans.
  std::vector<core::SE3> ground_truth_of_scans(const std::vector<core::SE3>& ground_truth) const;
  /// evaluate_trajectory of the processed scans against their ground truth; empty when fewer than
  /// 2 processed scans have one.
  std::optional<TrajectoryErrors> errors_against(const std::vector<core::SE3>& ground_truth) const;

 private:
  double min_range_m_;
  double max_range_m_;
  double vertical_angle_correction_rad_;
  std::vector<OdometryScanResult> scans_;
  std::vector<std::size_t> sequence_indices_;
  std::vector<SkippedScan> skipped_;
  std::vector<double> read_times_s_;
  /// Sensor frame, raw (not deskewed), at the map's voxel: drawn at the final poses of their scans.
  std::vector<std::vector<Eigen::Vector3d>> keyframe_points_;
  GlobalMap global_map_;
  std::vector<Eigen::Vector3f> dynamic_points_;
  std::optional<DynamicPointOptions> dynamic_options_;
  DynamicPointSummary dynamic_summary_;
};

/// The keyframes of `slam` as rays for find_dynamic_points (their points as the odometry
/// registered them, at their latest poses); valid while `slam` lives.
std::vector<KeyframeRays> keyframe_rays(const LidarSlam& slam);

}  // namespace cairn::lidar3d
