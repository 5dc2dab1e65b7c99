#include "cairn/lidar3d/lidar_inertial_slam.hpp"

namespace cairn::lidar3d {

LidarInertialSlam::LidarInertialSlam(LidarSlam& slam, const InertialFusionOptions& options)
    : slam_(slam), fusion_(options) {}

LidarInertialScan LidarInertialSlam::add_scan(const io::PointCloud& cloud, double time_s) {
  // The sweep lies within one period either side of the stamp (per-point times from the stamp, or
  // a KITTI-style sweep centred on it).
  const double period_s = slam_.options().odometry.sweep_period_s;
  const std::optional<MotionPrior> prior = fusion_.predict_sweep(time_s - period_s, time_s + period_s);
  LidarInertialScan scan;
  scan.slam = slam_.add_scan(cloud, time_s, prior ? &*prior : nullptr);
  if (!prior) return scan;
  InertialScanState state = fusion_.fuse(scan.slam.odometry, scan.slam.T_odom_registered);
  OdometryScanResult& odometry = scan.slam.odometry;
  if (state.contradicts_imu && odometry.health == Health::kOk) odometry.health = Health::kDegraded;
  slam_.set_world_up(-state.gravity_world);  // the odometry's world is the SLAM's (its first keyframe's)
  states_.push_back(state);
  scan.inertial = std::move(state);
  return scan;
}

}  // namespace cairn::lidar3d
