#pragma once
/// \file
/// 3D LiDAR SLAM: the odometry (odometry.hpp) plus keyframes, Scan Context loop candidates
/// (scan_context.hpp), geometric verification and a pose graph on cairn's back end with GNC.
/// One scan at a time goes in, as with the odometry; `finish()` runs the final GNC solve.
///
/// Structure (after SC-LIO-SAM / SC-A-LOAM, Kim & Kim IROS 2018, with cairn's back end):
///  - Keyframes: a scan becomes a keyframe when the odometry has moved `keyframe_distance_m` or
///    turned `keyframe_angle_rad` since the last one. It keeps its points as the odometry put
///    them into the map (sensor frame) and its Scan Context.
///  - Pose graph: one vertex per keyframe; consecutive keyframes joined by the odometry's relative
///    pose (a weak edge across a map-segment change, where the odometry was lost, so that a loop
///    closure can put the segments back together); accepted loop closures as edges.
///  - Loop closure, for each new keyframe: the Scan Context database proposes candidates
///    (`candidates` nearest ring keys, exclude_recent keyframes left out). Up to
///    `loop_places_verified` distinct places among those below the descriptor threshold
///    (candidates more than `loop_uniqueness_separation_m` apart) are verified, never trusted:
///      1. ICP of the keyframe's points against the candidate's neighbourhood (its keyframe and
///         `verification_neighbours` on either side, in the candidate's frame), started from the
///         descriptor's alignment (yaw and lateral view) and, separately, from the current
///         estimate of the relative pose; the better start wins;
///      2. fitness (share of points with a target point within the fine threshold) at least
///         `loop_min_fitness`, RMS at most `loop_max_rms_m`, and no degenerate direction;
///      3. odometry consistency: the verified relative pose may differ from the current
///         estimate's by at most `loop_gate_translation_m` + `loop_gate_drift_per_m` times the
///         path travelled between the two keyframes (rotation likewise), the drift odometry can
///         have accumulated (a look-alike place elsewhere fails here);
///      4. uniqueness: if two places pass 1-3 with fitnesses within
///         `loop_ambiguity_fitness_margin` and put the query more than the separation apart (a
///         garage's identical bays within what the odometry allows), the loop is ambiguous and
///         rejected; otherwise the best place that passed is accepted.
///    A false loop closure is the worst failure; every candidate is reported with the reason it
///    was accepted or rejected. Accepted loops trigger a least-squares solve of the graph; at
///    finish() GNC (backend/gnc.hpp) has the last word over all loop closures.
///  - GNSS (add_gnss): fixes as position factors on the keyframes once yaw is observable, solved
///    with the graph every few keyframes, at loop closures and at the end (gnss_anchoring.hpp).
///  - Scan poses: each scan keeps its odometry pose relative to the keyframe before it.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/pose_graph.hpp"
#include "cairn/lidar3d/gnss_anchoring.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/scan_context.hpp"

namespace cairn::lidar3d {

/// Scan Context as SLAM uses it: the reference's options plus query views from 2 and 4 m to either
/// side (Scan Context++-style; measured in tests/lidar3d/test_scan_context.cpp: a reverse revisit
/// from the opposite lane scores 0.61-0.66 without them and 0.118 with them, and the smallest
/// distance between the real KITTI key frames that are not revisits stays 0.300).
ScanContextOptions slam_scan_context_options();

struct LidarSlamOptions {
  LidarOdometryOptions odometry;
  ScanContextOptions scan_context = slam_scan_context_options();
  bool loop_closure = true;
  double keyframe_distance_m = 1.0;   ///< > 0
  double keyframe_angle_rad = 0.2;    ///< > 0
  /// Verification: keyframes on either side of the candidate whose points form the ICP target.
  int verification_neighbours = 3;
  double verification_coarse_threshold_m = 3.0;
  double verification_fine_threshold_m = 0.5;
  /// Voxel of the verification's target map, metres (source points: 1.5 times this).
  double verification_voxel_m = 0.5;
  double loop_min_fitness = 0.6;
  double loop_max_rms_m = 0.25;
  double loop_gate_translation_m = 3.0;
  double loop_gate_rotation_rad = 0.35;
  double loop_gate_drift_per_m = 0.05;          ///< metres of translation error per metre travelled
  double loop_gate_rotation_drift_per_m = 0.002;  ///< radians per metre travelled
  double loop_uniqueness_separation_m = 5.0;
  /// Distinct places (candidates below the descriptor threshold more than the separation apart)
  /// verified per keyframe, best descriptor distance first (>= 1).
  int loop_places_verified = 3;
  /// The second place is as good as the first unless its fitness is lower by more than this.
  double loop_ambiguity_fitness_margin = 0.05;
  /// Pose-graph noise (standard deviations).
  double odometry_translation_sigma_m = 0.05;
  double odometry_rotation_sigma_rad = 0.005;
  double segment_break_translation_sigma_m = 10.0;
  double segment_break_rotation_sigma_rad = 1.0;
  double loop_translation_sigma_m = 0.1;
  double loop_rotation_sigma_rad = 0.01;
  bool final_gnc = true;
  /// GNSS fixes as position factors on the keyframes (used only when add_gnss is called).
  GnssAnchoringOptions gnss;

  bool is_valid(std::string* error) const;
};

/// One loop candidate and what became of it.
struct LoopCandidateRecord {
  int query_keyframe = 0;
  int candidate_keyframe = 0;
  double query_time_s = 0.0;
  double candidate_time_s = 0.0;
  double descriptor_distance = 0.0;
  double descriptor_yaw_rad = 0.0;
  double second_descriptor_distance = 0.0;  ///< of another place verified for the query, or 1
  double second_fitness = 0.0;              ///< best ICP fitness of another place that passed, or 0
  double fitness = 0.0;
  double rms_m = 0.0;
  double gate_translation_m = 0.0;  ///< |verified - estimated| relative translation
  double gate_limit_m = 0.0;
  double gate_rotation_rad = 0.0;
  core::SE3 T_candidate_query;      ///< verified relative pose (when ICP ran)
  bool accepted = false;
  bool rejected_by_gnc = false;
  /// "accepted", or why not: "icp fitness", "icp rms", "icp degenerate", "odometry gate",
  /// "ambiguous", "not the best place" (passed, but another place of the same query fitted better).
  std::string decision;
};

struct LidarSlamSummary {
  std::size_t keyframes = 0;
  std::size_t loop_queries = 0;
  std::size_t loops_accepted = 0;
  std::size_t loops_rejected_by_gnc = 0;
  std::size_t optimizations = 0;
  double loop_search_s = 0.0;
  double verification_s = 0.0;
  double optimization_s = 0.0;
  std::vector<LoopCandidateRecord> candidates;
};

struct SlamScanResult {
  OdometryScanResult odometry;
  /// The registered pose in the odometry's own frame (before loop closures moved it): what an
  /// external predictor such as the IMU fusion works in.
  core::SE3 T_odom_registered;
  bool keyframe = false;
};

class LidarSlam {
 public:
  /// Throws std::invalid_argument if the options are invalid.
  explicit LidarSlam(const LidarSlamOptions& options = {});
  ~LidarSlam();
  LidarSlam(const LidarSlam&) = delete;
  LidarSlam& operator=(const LidarSlam&) = delete;

  /// As LidarOdometry::add_scan, then keyframe and loop-closure work.
  SlamScanResult add_scan(const io::PointCloud& cloud, double time_s, const MotionPrior* prior = nullptr);
  /// The final GNC over the loop closures (if enabled), then the graph with its GNSS factors (when
  /// fixes were given). Call once after the last scan.
  void finish();

  /// A GNSS fix (gnss_anchoring.hpp), in time order, on the scans' clock: give each before the
  /// scans that follow it (it is placed once a scan at or after its time has been added). The
  /// first fix starts the GNSS anchoring with `options().gnss`.
  void add_gnss(const gnss::GnssFix& fix);
  /// Which way is up in the world (for GNSS: GnssAnchoring::set_world_up); LiDAR-inertial SLAM
  /// gives its gravity estimate after every scan. Default +z.
  void set_world_up(const Vector3& up_world);
  /// The GNSS anchoring, once a fix was given.
  const GnssAnchoring* gnss() const;

  /// T_world_sensor of every scan so far, after the latest pose-graph solve.
  std::vector<core::SE3> trajectory() const;
  /// The keyframes' poses at their registered instant (OdometryScanResult::T_world_registered),
  /// after the latest solve, and the index (in add_scan order) of the scan each was taken at.
  std::vector<core::SE3> keyframe_poses() const;
  std::vector<std::size_t> keyframe_scans() const;
  const LidarSlamSummary& summary() const { return summary_; }
  /// Keyframe `k`'s points as the odometry put them into its map (sensor frame, registered
  /// instant) and its map segment. Precondition: k < keyframe_poses().size().
  const std::vector<Eigen::Vector3d>& keyframe_points(std::size_t k) const;
  int keyframe_segment(std::size_t k) const;
  /// The pose graph as the latest solve saw it: keyframe vertices (vertex 0 fixed), odometry
  /// edges and the loop closures GNC kept, with their information; `is_loop`, if given, receives
  /// per edge whether it is a loop closure.
  io::PoseGraph3D pose_graph(std::vector<bool>* is_loop = nullptr) const;
  /// The odometry's front end in use (LidarOdometry::front_end).
  FrontEnd front_end() const;
  const LidarSlamOptions& options() const { return options_; }

 private:
  struct Impl;
  LidarSlamOptions options_;
  std::unique_ptr<Impl> impl_;
  LidarSlamSummary summary_;
};

}  // namespace cairn::lidar3d
