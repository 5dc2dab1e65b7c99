#include "cairn/lidar3d/slam_run.hpp"

#include <cmath>

#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {

SlamRun::SlamRun(const LidarOdometryOptions& odometry, double map_voxel_m)
    : min_range_m_(odometry.min_range_m),
      max_range_m_(odometry.max_range_m),
      vertical_angle_correction_rad_(odometry.vertical_angle_correction_rad),
      global_map_(map_voxel_m) {}

void SlamRun::add_scan(std::size_t sequence_index, const io::PointCloud& cloud, const SlamScanResult& result, double read_s) {
  read_times_s_.push_back(read_s);
  if (result.keyframe) {
    std::vector<Eigen::Vector3d> points;
    points.reserve(cloud.size());
    const double max2 = max_range_m_ * max_range_m_, min2 = min_range_m_ * min_range_m_;
    const double cos_correction = std::cos(vertical_angle_correction_rad_), sin_correction = std::sin(vertical_angle_correction_rad_);
    for (const Eigen::Vector3f& p : cloud.points) {
      const double r2 = p.cast<double>().squaredNorm();
      if (r2 < min2 || r2 > max2) continue;
      // Corrected as the odometry corrects them (KITTI's 0.205 deg), or map.ply's far points bend.
      points.push_back(vertical_angle_correction_rad_ != 0.0 ? correct_vertical_angle(p.cast<double>(), cos_correction, sin_correction)
                                                             : Eigen::Vector3d(p.cast<double>()));
    }
    keyframe_points_.push_back(voxel_downsample(points, global_map_.voxel_size_m()));
  }
  scans_.push_back(result.odometry);
  sequence_indices_.push_back(sequence_index);
}

void SlamRun::add_skipped(const std::string& file, const std::string& error) { skipped_.push_back({file, error}); }

void SlamRun::finish(const LidarSlam& slam) {
  const std::vector<core::SE3> final_poses = slam.trajectory();
  for (std::size_t i = 0; i < scans_.size(); ++i) scans_[i].T_world_sensor = final_poses[i];
  // The stored points are the raw scans (not deskewed): placed at their scans' stamp poses.
  const std::vector<std::size_t> keyframe_scans = slam.keyframe_scans();
  for (std::size_t i = 0; i < keyframe_scans.size() && i < keyframe_points_.size(); ++i) {
    global_map_.add_scan(keyframe_points_[i], scans_[keyframe_scans[i]].T_world_sensor);
  }
}

void SlamRun::remove_dynamic_points(const LidarSlam& slam, const DynamicPointOptions& options) {
  const std::vector<bool> flags = find_dynamic_points(global_map_.points(), keyframe_rays(slam), options, &dynamic_summary_);
  dynamic_points_ = global_map_.remove(flags);
  dynamic_options_ = options;
}

std::vector<KeyframeRays> keyframe_rays(const LidarSlam& slam) {
  std::vector<KeyframeRays> rays;
  const std::vector<core::SE3> poses = slam.keyframe_poses();
  for (std::size_t k = 0; k < poses.size(); ++k) rays.push_back({&slam.keyframe_points(k), poses[k]});
  return rays;
}

HealthCounts SlamRun::health_counts() const {
  HealthCounts counts;
  for (const OdometryScanResult& r : scans_) {
    (r.health == Health::kOk ? counts.ok : r.health == Health::kDegraded ? counts.degraded : counts.lost)++;
    counts.unusable_point_times += r.point_times_unusable ? 1 : 0;
  }
  return counts;
}

std::vector<core::SE3> SlamRun::poses() const {
  std::vector<core::SE3> poses;
  poses.reserve(scans_.size());
  for (const OdometryScanResult& r : scans_) poses.push_back(r.T_world_sensor);
  return poses;
}

std::vector<core::SE3> SlamRun::ground_truth_of_scans(const std::vector<core::SE3>& ground_truth) const {
  std::vector<core::SE3> used;
  if (ground_truth.empty()) return used;
  for (std::size_t index : sequence_indices_) used.push_back(ground_truth[index]);
  return used;
}

std::optional<TrajectoryErrors> SlamRun::errors_against(const std::vector<core::SE3>& ground_truth) const {
  const std::vector<core::SE3> used = ground_truth_of_scans(ground_truth);
  if (used.size() < 2) return std::nullopt;
  return evaluate_trajectory(used, poses());
}

}  // namespace cairn::lidar3d
