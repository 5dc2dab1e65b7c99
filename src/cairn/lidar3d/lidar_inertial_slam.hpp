#pragma once
/// \file
/// LiDAR-inertial SLAM: LidarSlam driven by the IMU (inertial_fusion.hpp). Per scan:
///  1. predict: the IMU integrated from the latest fused state over the sweep (motion_prior.hpp);
///  2. register: LidarSlam::add_scan with that prediction (registration from the IMU's pose, every
///     point deskewed by its own time), keyframes and loop closures as without an IMU;
///  3. fuse: the registered pose joins the sliding-window factor graph with the IMU factors;
///  4. health: a registration the IMU contradicts is `degraded` (and named so).
/// Without IMU samples covering a sweep the scan goes through LidarSlam alone (constant velocity).

#include <optional>
#include <vector>

#include "cairn/lidar3d/inertial_fusion.hpp"
#include "cairn/lidar3d/slam.hpp"

namespace cairn::lidar3d {

struct LidarInertialScan {
  SlamScanResult slam;
  /// The fused state, when the IMU covered the scan.
  std::optional<InertialScanState> inertial;
};

class LidarInertialSlam {
 public:
  /// `slam` must outlive this object. Throws std::invalid_argument for invalid options.
  LidarInertialSlam(LidarSlam& slam, const InertialFusionOptions& options);

  /// IMU samples in the body frame on the scans' clock, strictly increasing.
  void add_imu(const inertial::ImuSample& sample) { fusion_.add_imu(sample); }
  /// Processes one scan (as LidarSlam::add_scan) with the IMU's prediction, then fuses it.
  LidarInertialScan add_scan(const io::PointCloud& cloud, double time_s);

  const LidarInertialFusion& fusion() const { return fusion_; }
  /// Every fused state so far, in scan order (scans the IMU did not cover have none).
  const std::vector<InertialScanState>& states() const { return states_; }

 private:
  LidarSlam& slam_;
  LidarInertialFusion fusion_;
  std::vector<InertialScanState> states_;
};

}  // namespace cairn::lidar3d
