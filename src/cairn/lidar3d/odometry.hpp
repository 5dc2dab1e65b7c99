#pragma once
/// \file
/// 3D LiDAR odometry: scan-to-local-map registration after KISS-ICP (Vizzo et al., "KISS-ICP: In
/// Defense of Point-to-Point ICP -- Simple, Accurate, and Robust Registration If Done the Right
/// Way", RA-L 2023), driven by the scans' timestamps, with degeneracy awareness (Zhang, Kaess &
/// Singh, ICRA 2016) and a health state. One scan at a time goes in; `add_scan` returns its pose
/// at once, so a live robot drives it as `cairn slam3d` does with a folder of scans.
///
/// Per scan (KISS-ICP Sec. III, with the differences marked *):
///  1. Motion prediction, constant velocity. * KISS-ICP repeats the last frame-to-frame motion;
///     here the last motion is a velocity (the twist log(T_{k-2}^-1 T_{k-1}) per second of
///     timestamp difference) applied over the new timestamp difference, so scans that arrive at
///     irregular intervals (key frames, dropped scans) are predicted as well as regular ones.
///  2. Deskew (Sec. III-A): point p taken at time tau is moved to the sweep's middle tau_mid with
///     exp(xi (tau - tau_mid)) p, xi the velocity of step 1, and registered there; the pose
///     reported is moved on to the instant of the scan's timestamp tau_0 with the new velocity
///     (KISS-ICP's PR #421 makes the same distinction). tau comes from the file's per-point
///     time field, counted from the timestamp, tau_0 = 0, tau_mid the middle of the scan's time
///     range (DeskewMode::kPointTimes, the default: scans without one are used as they are), or
///     from the point's azimuth as KISS-ICP's KITTI-raw loader does (kAzimuth):
///     tau = (pi - atan2(y, x)) / (2 pi) P, P = `sweep_period_s`, a sweep that starts facing
///     backward and turns clockwise (io/point_cloud.hpp), with tau_0 = tau_mid = P/2, facing
///     forward, where KITTI stamps its scans. Registering at the middle matters: there the
///     deskew moves the points by zero on average, so an error of the velocity does not move
///     the registered pose and feed back into the next velocity. Scans a driver has already motion-compensated
///     (KITTI's "sync" and odometry scans, see docs/lidar3d.md) must not be deskewed again.
///  3. Range crop [min_range_m, max_range_m]; voxel subsampling at 0.5 v for the map and again at
///     1.5 v for registration (Sec. III-B), v = `voxel_size_m`.
///  4. Adaptive threshold (Sec. III-C, eq. 3-4): sigma = RMS of the model errors
///     ||t|| + 2 r_max sin(theta / 2) of the deviations T_pred^-1 T_est seen so far above
///     `min_motion_m`, `initial_threshold_m` before any; correspondences up to 3 sigma, Geman-McClure
///     kernel scale sigma / 3.
///  5. Registration to the voxel-hash local map (registration.hpp), then the scan's map points
///     join the map and voxels beyond max_range_m of the sensor leave it.
///  6. * Health: `degraded` when a direction of the registration is degenerate (named, e.g. x
///     along a straight tunnel; the prediction carries it), fewer than
///     `degraded_min_correspondence_fraction` of the points found a map neighbour, or the
///     registration reached its iteration limit; `lost` when registration fails (fewer than
///     `lost_min_correspondence_fraction` matched), when its fit says the pose is not trustworthy
///     (dense front end: inlier RMS above `lost_max_rms_voxels` voxels while fewer than
///     `lost_rms_max_correspondence_fraction` of the points matched -- a scan registered the
///     wrong way round, as after a gap in the recording), or the scan has fewer than
///     `min_scan_points` points in range. A lost scan
///     takes the predicted pose and * starts a new map segment: the local map is cleared and
///     rebuilt from that scan (or, if it had too few points, from the next one), so the next scans match again instead of
///     staying lost (the segments are joined only by the motion prediction until loop closure can
///     merge them).

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/health.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/loam_features.hpp"
#include "cairn/lidar3d/motion_prior.hpp"
#include "cairn/lidar3d/registration.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {

enum class DeskewMode {
  kOff,
  /// With the file's per-point times where the scan has them, none otherwise.
  kPointTimes,
  /// With times from each point's azimuth (a spinning sensor), whatever the file holds.
  kAzimuth,
};
std::string_view to_string(DeskewMode mode);

/// What a scan is registered with (step 5).
enum class FrontEnd {
  /// kLoamFeatures when the first scan carries a ring per point (or rings_from_kitti_order is
  /// set), kDense otherwise; decided once, at the first scan.
  kAuto,
  /// Every point (subsampled at 1.5 v) against the voxel-hash map: KISS-ICP's way, with the
  /// residual of `registration.metric`.
  kDense,
  /// LOAM's features (loam_features.hpp): sharp edge points against a map of lines, flat points
  /// against a map of planes (register_features). Needs per-point rings. Degenerate directions
  /// are always solved from the prediction here (RegistrationOptions::remap_degenerate_directions
  /// is forced on): nothing else pulls along them, and measured it never did worse (docs/lidar3d.md).
  kLoamFeatures,
};
std::string_view to_string(FrontEnd front_end);

struct LidarOdometryOptions {
  /// Default kAuto, by measurement (docs/lidar3d.md, "Front ends"): LOAM's features did better
  /// on every simulated run (VLP-16 and HDL-64 models, street, garage, tunnel), the dense front
  /// end on the real KITTI key frames (end-point drift, ATE, t_err), whose preset sets kDense.
  FrontEnd front_end = FrontEnd::kAuto;
  LoamFeatureOptions loam;
  /// Scans without a ring field get rings from KITTI's point order
  /// (io::recover_kitti_ring_and_time); only the LOAM front end uses rings. Set by the kitti preset.
  bool rings_from_kitti_order = false;
  /// Points beyond this range are dropped; also the map's radius and r_max of the model error.
  /// KISS-ICP's default 100 m.
  double max_range_m = 100.0;
  /// Points nearer than this are dropped (the vehicle itself), metres. KISS-ICP's default 0.
  double min_range_m = 0.0;
  /// Motion compensation of each sweep (step 2).
  DeskewMode deskew = DeskewMode::kPointTimes;
  /// Elevation added to every point, radians: p is turned by this angle about p x z, toward +z.
  /// KITTI's HDL-64E scans need 0.205 deg (about 3.578e-3 rad; found by IMLS-SLAM, Deschaud ICRA
  /// 2018, Sec. IV-B, as 0.22 deg, and applied as 0.205 deg by KISS-ICP's KITTI loaders): the
  /// intrinsic calibration KITTI used leaves the rings bent slightly down, so the ground seen
  /// from the next scan looks tilted. 0 (default) for other sensors; `cairn slam3d --preset
  /// kitti` sets it.
  double vertical_angle_correction_rad = 0.0;
  /// Duration of one sweep, seconds (> 0): 0.1 for a 10 Hz spinning LiDAR.
  double sweep_period_s = 0.1;
  /// Voxel edge v of the map, metres (> 0). KISS-ICP: max_range / 100.
  double voxel_size_m = 1.0;
  int max_points_per_voxel = 20;  ///< KISS-ICP's default
  double initial_threshold_m = 2.0;  ///< sigma before any motion sample (KISS-ICP)
  double min_motion_m = 0.1;         ///< deviations below this do not update sigma (KISS-ICP)
  RegistrationOptions registration;
  /// Threads for preprocessing and registration; 0 = all the machine has.
  int threads = 0;

  /// A scan with fewer points in range than this (a blinded or disconnected sensor) is `lost`
  /// without registration and adds nothing to the map (>= 0).
  int min_scan_points = 100;
  double degraded_min_correspondence_fraction = 0.5;
  double lost_min_correspondence_fraction = 0.2;
  /// Dense front end: a registration whose inlier residual RMS exceeds this many voxel sizes
  /// while fewer than `lost_rms_max_correspondence_fraction` of its points matched is `lost`, not
  /// `degraded` (> 0). Measured (docs/lidar3d.md, "Health"): on the 109 real KITTI key-frame
  /// registrations RMS <= 0.49 voxel with >= 88 % matched; four scans of the same street
  /// registered about 180 deg wrong gave RMS 0.94-1.05 voxel with 30-67 % matched.
  double lost_max_rms_voxels = 0.75;
  double lost_rms_max_correspondence_fraction = 0.8;  ///< in [0, 1]; 0 = the RMS test is off

  /// False with the reason when an option is out of range.
  bool is_valid(std::string* error) const;
};

/// `p` (sensor frame) with the vertical-angle correction (LidarOdometryOptions::
/// vertical_angle_correction_rad): turned by `correction_rad` about p x z, toward +z.
Eigen::Vector3d correct_vertical_angle(const Eigen::Vector3d& p, double correction_rad);
/// The same with the correction's cosine and sine given (a whole scan shares one angle).
Eigen::Vector3d correct_vertical_angle(const Eigen::Vector3d& p, double cos_correction, double sin_correction);

/// Named starting configurations: "default" (KISS-ICP's defaults with point-to-plane
/// registration and deskew from per-point times where the files have them) and "kitti" (for
/// KITTI's HDL-64E scans: the 0.205 deg vertical-angle correction, no deskew since KITTI's
/// published scans are already motion-compensated). Throws std::invalid_argument for another name.
LidarOdometryOptions preset_options(std::string_view name);

using core::Health;  // ok / degraded / lost (core/health.hpp)
using core::to_string;

/// Seconds spent per stage on one scan.
struct OdometryStageTimes {
  double preprocess_s = 0.0;  ///< deskew, crop, subsampling
  double register_s = 0.0;
  double map_s = 0.0;         ///< map update
  double total_s = 0.0;
};

struct OdometryScanResult {
  double time_s = 0.0;
  /// The sensor at the scan's timestamp.
  core::SE3 T_world_sensor;
  /// The instant of T_world_registered (the sweep's middle; the stamp when not deskewed), seconds.
  double registered_time_s = 0.0;
  /// The sensor at the sweep's middle, where the scan was registered: the frame of
  /// LidarOdometry::last_frame_points(). Equals T_world_sensor when the scan was not deskewed
  /// or its stamp is the middle (KITTI).
  core::SE3 T_world_registered;
  Health health = Health::kOk;
  /// Map segment (0, then one more after each lost scan).
  int segment = 0;
  /// Empty unless the registration had a degenerate direction: its sensor axis (name_direction).
  std::string degenerate_axis;
  RegistrationResult registration;
  double threshold_sigma_m = 0.0;   ///< adaptive threshold used (step 4)
  std::size_t points_read = 0;
  std::size_t points_in_range = 0;
  /// The file's per-point times could not be offsets within one sweep of the stamp (their span
  /// or size exceeds two sweep periods: absolute times, another unit), so the scan was not
  /// deskewed.
  bool point_times_unusable = false;
  std::size_t map_points_added = 0;  ///< after 0.5 v subsampling
  std::size_t local_map_points = 0;  ///< after the update
  OdometryStageTimes times;
};

class LidarOdometry {
 public:
  /// Throws std::invalid_argument if the options are invalid.
  explicit LidarOdometry(const LidarOdometryOptions& options = {});
  // add_scan throws std::invalid_argument for the LOAM front end when the scan has no rings.
  ~LidarOdometry();
  LidarOdometry(const LidarOdometry&) = delete;
  LidarOdometry& operator=(const LidarOdometry&) = delete;

  /// Processes one scan taken at `time_s` (seconds, any origin, strictly increasing; throws
  /// std::invalid_argument otherwise). The first scan defines the world frame (identity pose).
  /// With a `prior` (motion_prior.hpp; it must cover the sweep) the prediction is the prior's pose
  /// at the registration instant, every point is deskewed by the prior's pose at its own time, and
  /// the first scan takes the prior's pose (an IMU's gravity-aligned frame) instead of the identity.
  OdometryScanResult add_scan(const io::PointCloud& cloud, double time_s, const MotionPrior* prior = nullptr);

  /// One scan prepared as add_scan prepares it (steps 2-3: point times, crop, vertical-angle
  /// correction, deskew to the sweep's middle, subsampling at 0.5 v), without registering it or
  /// changing the odometry: what a localiser tracking against a saved map matches in place of a
  /// whole odometry step (localization.hpp). `velocity_per_s` is the sensor's twist per second
  /// (core::SE3::log of the motion over one second, translation first) that deskews the points;
  /// zero leaves them as taken. No LOAM features are extracted, so no rings are needed. Throws
  /// std::invalid_argument for a non-finite time.
  struct PreparedScan {
    std::vector<Eigen::Vector3d> frame_sensor;  ///< as last_frame_points(): sensor frame at the sweep's middle
    double registered_time_s = 0.0;             ///< the sweep's middle (the stamp when not deskewed)
    /// The motion from the sweep's middle to the stamp by `velocity_per_s` (identity when the
    /// stamp is the middle): T_world_stamp = T_world_registered * T_registered_stamp.
    core::SE3 T_registered_stamp;
    bool point_times_unusable = false;          ///< as OdometryScanResult's
  };
  PreparedScan prepare_scan(const io::PointCloud& cloud, double time_s, const Eigen::Matrix<double, 6, 1>& velocity_per_s) const;

  const VoxelHashMap& local_map() const { return map_; }
  /// The last scan's points as they went into the map (corrected, deskewed, cropped, subsampled at
  /// 0.5 v), in its sensor frame at the sweep's middle; empty for a scan with too few points.
  const std::vector<Eigen::Vector3d>& last_frame_points() const { return last_frame_sensor_; }
  const LidarOdometryOptions& options() const { return options_; }
  std::size_t scans() const { return poses_.size(); }
  /// The front end in use: options().front_end, or what kAuto chose at the first scan (kAuto
  /// before it).
  FrontEnd front_end() const { return front_end_; }

 private:
  struct Arena;
  /// What the stages of one add_scan call share (odometry.cpp).
  struct ScanWork;

  // The stages of add_scan, in the order it calls them (steps 1-6 of the file comment).
  void choose_point_times(const io::PointCloud& cloud, ScanWork& work, OdometryScanResult& result) const;
  void choose_front_end(const io::PointCloud& cloud);
  const std::vector<std::uint16_t>* rings_of(const io::PointCloud& cloud, const ScanWork& work,
                                             std::vector<std::uint16_t>& recovered_rings) const;
  void crop_and_correct(const io::PointCloud& cloud, ScanWork& work) const;
  void sweep_instants(ScanWork& work) const;
  void predict(ScanWork& work) const;
  void preprocess(ScanWork& work) const;
  void deskew_to_sweep_middle(ScanWork& work) const;
  void deskew_with_prior(ScanWork& work) const;
  double adaptive_threshold() const;
  void register_to_map(ScanWork& work, OdometryScanResult& result);
  RegistrationResult register_loam(const ScanWork& work) const;
  RegistrationResult register_dense(const ScanWork& work) const;
  void assess_health(ScanWork& work, OdometryScanResult& result) const;
  void update_model_error(const ScanWork& work);
  void start_segment_if_lost(const ScanWork& work, OdometryScanResult& result);
  void report_pose(const ScanWork& work, OdometryScanResult& result) const;
  void update_map(ScanWork& work, OdometryScanResult& result);
  void update_loam_maps(ScanWork& work, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, OdometryScanResult& result);
  void update_dense_map(const ScanWork& work, const Eigen::Vector3d& t, OdometryScanResult& result);
  void record(const ScanWork& work);

  LidarOdometryOptions options_;
  std::unique_ptr<Arena> arena_;
  VoxelHashMap map_;
  VoxelHashMap edge_map_;   ///< LOAM front end: less-sharp points
  VoxelHashMap plane_map_;  ///< LOAM front end: less-flat points
  std::vector<Eigen::Vector3d> last_frame_sensor_;
  std::vector<core::SE3> poses_;
  std::vector<double> times_;   ///< of poses_: the sweep middles
  std::vector<double> stamps_;  ///< the scans' timestamps
  double model_error_sse_ = 0.0;
  std::size_t model_error_samples_ = 0;
  int segment_ = 0;
  FrontEnd front_end_ = FrontEnd::kAuto;
};

}  // namespace cairn::lidar3d
