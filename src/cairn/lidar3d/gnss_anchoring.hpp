#pragma once
/// \file
/// GNSS in the 3D LiDAR SLAM's keyframe pose graph, after LIO-SAM (Shan et al., "LIO-SAM:
/// Tightly-coupled Lidar Inertial Odometry via Smoothing and Mapping", IROS 2020, Sec. III-E, "GPS
/// factor"): a fix becomes a position factor on the keyframe it falls after, so the graph that
/// closes loops also holds the trajectory to the fixes and bounds its drift; GNSS factors are
/// added only once yaw is observable, and the odometry between the fixes carries dropouts.
///
/// Placing a fix: its time lies between two scans; the odometry pose there (interpolated between
/// them) puts the antenna (`lever_arm_body_m`, in the LiDAR's frame) at a point a_k fixed in the
/// frame of the keyframe k the scans hang from, so the fix constrains that keyframe's pose:
///
///     e = T_enu_world * (T_world_k * a_k) - p_enu,   r = S e,   S^T S = Sigma_fix^-1
///
/// with Cauchy's kernel (gnss/gnss_factor.hpp says why: a 10-50 m jump pulls almost nothing).
///
/// The world-to-ENU transform: the SLAM's world is its first keyframe's frame; which way is up in
/// it comes from set_world_up (LiDAR-inertial SLAM gives the IMU fusion's gravity estimate: a world
/// whose initial tilt was wrong, as after a start in motion, is not level), default +z.
/// gnss::align_world_to_enu fits yaw and translation to the placed fixes, levelled by R_level (up
/// to +z), once the path has spread `alignment.min_spread_m` (gnss/gnss_yaw.hpp); from then on
/// T_enu_world is a variable of the graph (yaw and translation free, roll and pitch held by a prior
/// of `world_tilt_sigma_rad` at R_level's), so a heading the short first stretch got slightly
/// wrong is refined by the whole path instead of bending the graph. The first keyframe stays
/// fixed: it holds the world's gauge.
///
/// Each solve has two stages, as graduated non-convexity does in two steps (Yang et al., "Graduated
/// Non-Convexity for Robust Spatial Perception", RA-L 2020): Huber's kernel first, convex, so that
/// a run of fixes after a dropout pulls a drifted trajectory back however far it drifted (Cauchy
/// alone, started 26 m away, would call them all outliers), then Cauchy's from there, which lets
/// the isolated jumps go. Odometry edges across a stretch the registration could not see are loose
/// along the blind direction (`degenerate_edge_sigma_m`) in this graph, so that it can bend there.
///
/// Outliers are reported after every solve: a used fix whose e^T Sigma^-1 e exceeds the
/// chi-square(3) quantile `outlier_probability` is an outlier (its kernel weight is then small).

#include <optional>
#include <string>
#include <vector>

#include "cairn/backend/problem.hpp"
#include "cairn/gnss/gnss_factor.hpp"
#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/gnss/gnss_yaw.hpp"
#include "cairn/gnss/local_frame.hpp"

namespace cairn::lidar3d {

struct GnssAnchoringOptions {
  /// The antenna in the LiDAR's frame (lever_arm_body_m), sigmas for fixes without a covariance,
  /// the floor on a fix's sigma, the kernel. Its T_enu_world is not used (the alignment sets it).
  gnss::GnssFactorOptions factor;
  /// When yaw counts as observable (the path's RMS spread) and the trimmed fit.
  gnss::YawAlignmentOptions alignment;
  /// A fix is placed between two scans only when one of them is at most this far in time (s, > 0).
  double max_fix_gap_s = 0.2;
  /// After the alignment, the graph with its GNSS factors is solved every this many new keyframes
  /// (>= 1), at every loop closure and at the end.
  int solve_every_keyframes = 10;
  /// Roll and pitch of the world in ENU (rad, > 0): how level the SLAM's world is (with an IMU:
  /// its initialisation's accuracy, default 0.01 rad; without one, how level the LiDAR sits).
  double world_tilt_sigma_rad = 0.01;
  /// Odometry edges between keyframes where a scan's registration could not see a translation
  /// direction get this sigma along it (m, > 0) in the graph solved with the fixes: after a blind
  /// stretch (a tunnel) the fixes must be able to move what the IMU alone carried.
  double degenerate_edge_sigma_m = 1.0;
  /// A used fix beyond this chi-square(3) quantile after a solve is reported as an outlier, (0, 1).
  double outlier_probability = 0.999;
  bool is_valid(std::string* why) const;
};

/// What became of one fix.
struct GnssFixResult {
  double time_s = 0.0;
  Vector3 p_enu_m = Vector3::Zero();  ///< the fix's antenna in the ENU frame at the first fix
  Matrix3 covariance_enu_m2 = Matrix3::Identity();  ///< what the factor uses
  int keyframe = -1;                  ///< the keyframe it constrains (-1: not placed)
  Vector3 antenna_keyframe_m = Vector3::Zero();  ///< a_k: the antenna at the fix's time, keyframe frame
  std::string not_placed;             ///< why, when keyframe is -1 (empty while pending)
  bool used = false;                  ///< a factor of the latest solve
  double chi2 = -1.0;                 ///< e^T Sigma^-1 e after the latest solve (-1 before)
  bool outlier = false;               ///< chi2 beyond the outlier quantile
  Vector3 error_enu_m = Vector3::Zero();  ///< the estimated antenna minus the fix, after the latest solve
};

struct GnssAnchoringSummary {
  std::size_t fixes = 0, placed = 0, used = 0, outliers = 0;
  bool aligned = false;
  gnss::YawAlignment alignment;       ///< the fit that started the GNSS factors (before: the last refusal)
  double alignment_time_s = 0.0;      ///< the fix time at which it succeeded
  std::optional<gnss::GeodeticPosition> enu_origin;  ///< the first fix: the ENU frame's origin
  core::SE3 T_enu_world;              ///< after the latest solve
  std::size_t solves = 0;
  double solve_s = 0.0;
  double outlier_chi2 = 0.0;          ///< the threshold
};

class GnssAnchoring {
 public:
  /// Throws std::invalid_argument for invalid options.
  explicit GnssAnchoring(const GnssAnchoringOptions& options);

  /// Fixes in time order (a fix earlier than the previous one is refused: std::invalid_argument).
  void add_fix(const gnss::GnssFix& fix);

  /// Places the pending fixes up to the latest scan: `scan_time_s[i]`, `T_odom_scan[i]` (the
  /// odometry pose at the scan's stamp) and `scan_keyframe[i]` (the keyframe the scan hangs from,
  /// -1 before the first) for every scan so far, and per keyframe its odometry pose.
  void place_fixes(const std::vector<double>& scan_time_s, const std::vector<core::SE3>& T_odom_scan,
                   const std::vector<int>& scan_keyframe, const std::vector<core::SE3>& T_odom_keyframe);

  /// The world's up direction (any non-zero vector; normalised), for the alignment and the tilt prior.
  void set_world_up(const Vector3& up_world);

  /// After the last scan: the fixes still waiting lie after it (not placed, and said so).
  void finish();

  /// Tries the alignment (until it succeeds) with the keyframes' world poses; true once aligned.
  bool try_align(const std::vector<core::SE3>& T_world_keyframe);
  bool aligned() const { return summary_.aligned; }
  /// Whether a solve is due after `keyframes` keyframes (solve_every_keyframes since the last).
  bool solve_due(std::size_t keyframes) const;

  /// Solves `graph` (its poses, edges and fixed pose) with the GNSS factors of the placed fixes and
  /// T_enu_world as a variable; writes the solved poses into graph.T_world_pose and updates every
  /// fix's result. Precondition: aligned().
  void solve(backend::Problem3D& graph);

  const std::vector<GnssFixResult>& fixes() const { return fixes_; }
  const GnssAnchoringSummary& summary() const { return summary_; }
  const GnssAnchoringOptions& options() const { return options_; }

 private:
  GnssAnchoringOptions options_;
  std::optional<gnss::LocalFrame> frame_;
  std::vector<GnssFixResult> fixes_;
  std::size_t next_to_place_ = 0;
  std::size_t keyframes_at_last_solve_ = 0;
  Vector3 up_world_ = Vector3::UnitZ();
  core::SE3 T_enu_level_;  ///< the alignment's fit in the levelled world (yaw and translation)
  core::SO3 level_rotation() const;
  void evaluate_fixes(const backend::Problem3D& graph, const std::vector<std::size_t>& used);
  GnssAnchoringSummary summary_;
};

}  // namespace cairn::lidar3d
