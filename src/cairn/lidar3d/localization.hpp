#pragma once
/// \file
/// Pure localisation in a saved 3D LiDAR map (saved_map.hpp, map_file.hpp; `cairn localize3d`,
/// issue 42): scans go in one at a time as into LidarSlam::add_scan; each returns the sensor's
/// pose in the map frame, a health state and how well the scan fits the map. The map is never
/// changed. The 2D localiser (slam2d/localization.hpp) is the model; what differs is how places
/// are proposed (Scan Context instead of branch and bound) and where odometry comes from.
///
/// Odometry: the scans themselves. A LidarOdometry with the map's sensor model (so every scan is
/// cropped, corrected and deskewed as the map's were) gives T_odom_sensor for every scan while
/// searching, the motion between scans that carries a hypothesis from one scan to the next. Its
/// points (last_frame_points, at half its voxel) are what is matched against the map. Once
/// tracking has matched two scans, it needs no odometry (lean tracking): each scan is predicted by
/// the localiser's own constant velocity and only prepared as the odometry would
/// (LidarOdometry::prepare_scan), since the odometry's registration and map update cost more than
/// the match against the map (KITTI key frames: 24 ms against 12; docs/lidar3d.md).
///
/// Matching a scan against the map at a guess: Generalized-ICP (gicp.hpp) of the scan, thinned
/// to `source_voxel_m` with covariances from its own half-voxel sampling, onto the map thinned
/// to `target_voxel_m` with covariances from all of the map's points (the configuration that did
/// best on the KITTI pairs, gicp.hpp), then fitness (the share of the scan's points with a map
/// point within max_correspondence_m) and inlier RMSE at GICP's last linearisation, and the
/// degeneracy of one point-to-plane linearisation at the result (registration.hpp) over at most
/// 800 of the scan's points spread through it.
/// From a place's descriptor guess, a point-to-plane ICP at `coarse_correspondence_m` first.
///
/// States:
///  - Searching (health `lost`, no pose given): at the start and after tracking was lost. Every
///    scan's Scan Context (Kim & Kim, IROS 2018) is compared with the map's keyframes
///    (`candidates` nearest ring keys, as LidarSlam's loop search, with the same lateral views);
///    up to `places_verified` distinct places (keyframes more than `separation_m` apart) with a
///    descriptor distance at most `max_descriptor_distance` are matched from the descriptor's
///    guess (the keyframe's pose with the descriptor's yaw) and from that guess moved half-way to
///    each neighbouring keyframe, the best score kept. A match is verified when it
///    converged, has fitness >= verification_min_fitness, inlier RMSE <= verification_max_rmse_m
///    and no degenerate direction. Each verified match that agrees with no hypothesis starts one:
///    T_map_odom = T_map_sensor T_odom_sensor^-1.
///  - Hypotheses are followed scan by scan through the odometry: each is matched at its
///    prediction T_map_odom T_odom_sensor; a match that passes verification and lies within
///    `agreement_m` / `agreement_rad` of the prediction supports it (one support per scan);
///    `hypothesis_max_misses` scans in a row without support drop it. A hypothesis is accepted
///    (tracking starts; a relocalisation is recorded with its evidence) when `confirmations`
///    distinct scans support it, the current one among them, and no other hypothesis is alive;
///    its pose is then matched again from starts `polish_offsets_m` away (the best score kept).
///    While two places keep explaining the scans (a garage's identical bays) the localiser stays
///    `lost`: a wrong relocalisation is the worst failure. When the odometry cannot carry a
///    hypothesis (it lost track on a scan, as it does over the first scans of a run whose scans
///    are metres apart, before it has a velocity), a verified place supports the hypothesis when
///    the scan, registered onto the hypothesis' last supporting scan from the motion between the
///    two places, ends within the agreement of that motion (the check the odometry's prediction
///    makes otherwise). Among several hypotheses, one that explains clearly less than the best
///    (`hypothesis_drop_deficit`) is dropped.
///  - Tracking (health `ok` or `degraded`): the scan is matched at its prediction (constant
///    velocity; through the odometry on the first scan after a relocalisation, or with
///    `odometry_while_tracking`); when that does not fit `ok`, again coarse to fine from the
///    prediction and from it turned by `retry_yaw_offsets_rad` (a turn between sparse scans). `ok`
///    when fitness >= ok_min_fitness and no direction is degenerate; `degraded` otherwise, with
///    the degenerate axis named. Fitness below tracking_min_fitness (or no convergence) is a
///    failure: the pose follows the odometry (`degraded`, dead reckoning), and `lost_after_failures`
///    failures in a row make it `lost`; the search then starts with the dead-reckoned pose as a
///    hypothesis without support (a prior, confirmed as any other). Every `check_every_n_scans`
///    scans the global search also runs while tracking: a verified place elsewhere that fits
///    better than the tracked pose by `rival_fitness_margin` ends tracking (a kidnapped robot
///    whose odometry did not notice). So does a matched pose that jumped farther from the last
///    poses' constant velocity than `max_acceleration_mps2` allows.
///
/// A searching scan costs one odometry step, one match per live hypothesis (at most
/// `max_hypotheses`), one descriptor query and at most `places_verified` coarse-to-fine matches; a
/// tracked scan its preparation and one match (more when retried), and the global search every
/// `check_every_n_scans` scans.

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/health.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/saved_map.hpp"

namespace cairn::lidar3d {

struct Localizer3dOptions {
  /// Threads for the odometry and matching; 0 = all the machine has.
  int threads = 0;

  /// False (lean tracking): once two scans were matched, tracking predicts each scan from the
  /// localiser's own constant velocity and only prepares it (LidarOdometry::prepare_scan: crop,
  /// deskew by that velocity, subsample), skipping the odometry's registration and map update,
  /// which cost more than the match against the map itself (see docs/lidar3d.md). True: a whole
  /// odometry step per tracked scan, whose motion predicts the match.
  bool odometry_while_tracking = false;

  /// Matching (see the file comment), metres, each > 0.
  double source_voxel_m = 1.0;
  double target_voxel_m = 0.25;
  double max_correspondence_m = 1.0;
  double coarse_correspondence_m = 3.0;
  int max_iterations = 64;  ///< >= 1
  /// GICP has converged when a step moves by less than this in metres and in radians (> 0;
  /// GicpOptions' tolerances). On the KITTI key frames 5e-4 localises as 1e-4 does (median 4.01 cm,
  /// 0.102 deg either way) with 1-2 fewer iterations per match.
  double step_tolerance = 5e-4;
  /// GICP iterations of a tracked scan's first match, at its prediction (>= 1): one that has not
  /// converged by then goes to the retries (below) instead of spending max_iterations. On the
  /// KITTI key frames a match that converges there takes 2-14.
  int tracking_max_iterations = 20;
  /// GICP's first iterations of every match use every sparse_stride-th source point only
  /// (GicpOptions::sparse_stride, >= 1; 1: all points throughout); the last ones all of them.
  int sparse_stride = 4;

  /// Verification of a place (and of a hypothesis' support): fitness in [0, 1], RMSE in metres,
  /// and the smallest share of the surfaces constraining a translation direction
  /// (RegistrationResult::translation_degeneracy, in [0, 1/3]).
  double verification_min_fitness = 0.8;
  double verification_max_rmse_m = 0.35;
  double min_translation_degeneracy = 0.02;

  /// Tracking health: `ok` needs fitness >= ok_min_fitness and inlier RMSE <= ok_max_rmse_m (and
  /// no degenerate direction); fitness below tracking_min_fitness is a failure. In [0, 1],
  /// tracking <= ok; metres > 0.
  double ok_min_fitness = 0.9;
  double ok_max_rmse_m = 0.3;
  double tracking_min_fitness = 0.5;
  int lost_after_failures = 3;  ///< >= 1
  /// A tracked scan that does not fit `ok` (converged, fitness and RMSE) at its prediction is
  /// matched again coarse to fine from the prediction and from the prediction turned about the
  /// vertical by each of these (radians, finite), in the order of a quick count of the scan's
  /// points near the map there, until one fits `ok`; the best score wins.
  /// Between sparse scans in a turn constant velocity misjudges the yaw (KITTI key frames 3.5 m
  /// apart at an intersection: 10-12 degrees, where the match from the prediction fails).
  std::vector<double> retry_yaw_offsets_rad = {0.175, -0.175, 0.35, -0.35};

  /// Searching: descriptor candidates (Scan Context's nearest ring keys, > 0), the largest
  /// descriptor distance verified (in [0, 1]), distinct places verified per scan (>= 1) and what
  /// makes places distinct (> 0).
  int candidates = 10;
  double max_descriptor_distance = 0.35;
  int places_verified = 3;
  double separation_m = 5.0;
  /// Hypotheses: scans that must support one before it is accepted (>= 1), agreement of a
  /// support with the prediction (> 0), misses in a row that drop one (>= 1), live ones at most
  /// (>= 1; a verified place that would start one more is ignored and counted).
  int confirmations = 2;
  double agreement_m = 1.0;
  double agreement_rad = 0.05;
  int hypothesis_max_misses = 2;
  int max_hypotheses = 6;
  /// Among several hypotheses, one whose score (fitness less inlier RMSE over
  /// max_correspondence_m) falls short of the best one's by this much, summed over the last
  /// `hypothesis_drop_window_scans` scans, is dropped: its place explains clearly less of what the
  /// sensor sees (slam2d's rule). > 0; >= 1.
  double hypothesis_drop_deficit = 0.3;
  int hypothesis_drop_window_scans = 5;

  /// Tracking check: the global search every this many tracked scans (>= 1) and on every tracked
  /// scan that is not `ok`, and how much better (score) a verified place must fit to correct the
  /// tracked pose or end tracking, in [0, 1].
  int check_every_n_scans = 10;
  double rival_score_margin = 0.15;
  /// Tracking: a matched pose farther than jump_margin_m + a t^2 / 2 (a = max_acceleration_mps2,
  /// t the time since the last scan) from the last two poses' constant velocity ends tracking:
  /// the scans jumped (> 0; >= 0).
  double max_acceleration_mps2 = 20.0;
  double jump_margin_m = 1.0;
  /// Before a relocalisation is accepted, the hypothesis' pose is matched again from starts moved
  /// by each of these along the sensor's x and y axes (metres, finite; empty: none), and the best
  /// score wins.
  std::vector<double> polish_offsets_m = {-3.0, -1.5, 1.5, 3.0};

  /// False with every problem when an option is out of range.
  bool is_valid(std::string* why) const;
};

enum class Localization3dState { kSearching, kTracking };
std::string_view to_string(Localization3dState state);

/// One scan's result.
struct Localization3dResult {
  std::size_t scan = 0;       ///< index in add_scan order
  double time_s = 0.0;
  Localization3dState state = Localization3dState::kSearching;
  core::Health health = core::Health::kLost;
  /// Whether T_map_sensor holds a pose (tracking); false while searching: the localiser does not
  /// guess.
  bool localised = false;
  /// The sensor at the scan's stamp, map frame.
  core::SE3 T_map_sensor;
  /// Tracking, but this scan's match failed: the pose follows the odometry.
  bool dead_reckoning = false;
  bool relocalised = false;   ///< this scan accepted a relocalisation
  /// The scan's match against the map (tracking, or the accepted hypothesis'); zero when none.
  double fitness = 0.0;
  double inlier_rmse_m = 0.0;
  double translation_degeneracy = 0.0;
  std::string degenerate_axis;  ///< empty unless a direction was degenerate
  /// Whether an odometry step ran on this scan (false in lean tracking); its health when it did.
  bool odometry_step = true;
  core::Health odometry_health = core::Health::kOk;
  int live_hypotheses = 0;
  /// Why the health is what it is, in words ("tracking", "fitness 0.52 below 0.7", ...).
  std::string reason;
  /// Seconds: the odometry step (in lean tracking the scan's preparation alone) with the scan's
  /// matching cloud, matching against the map (tracking and hypotheses), the global search
  /// (descriptor and verification), and the whole call.
  double odometry_s = 0.0;
  double tracking_s = 0.0;
  double search_s = 0.0;
  double total_s = 0.0;
};

/// One place proposed by the descriptor and what its verification found.
struct LocalizationAttempt3d {
  std::size_t scan = 0;
  int keyframe = 0;               ///< the map keyframe proposed
  double descriptor_distance = 0.0;
  double descriptor_yaw_rad = 0.0;
  bool while_tracking = false;    ///< a tracking check
  double fitness = 0.0;
  double inlier_rmse_m = 0.0;
  double translation_degeneracy = 0.0;
  core::SE3 T_map_sensor;         ///< after matching
  /// "verified" (then "new hypothesis", "supports hypothesis N", "ignored: max_hypotheses",
  /// "agrees with tracking", "rival: ends tracking", "rival: fits worse than tracking") or why
  /// not: "not converged", "fitness", "rmse", "degenerate".
  std::string decision;
};

struct Relocalisation3d {
  std::size_t scan = 0;
  double time_s = 0.0;
  core::SE3 T_map_sensor;
  std::size_t searching_since_scan = 0;
  bool from_prior = false;        ///< the dead-reckoned pose after a tracking loss was confirmed
  std::vector<std::size_t> support_scans;  ///< the scans that supported it, oldest first
  std::size_t rival_hypotheses = 0;        ///< other hypotheses that died during the search
};

struct Localizer3dSummary {
  std::size_t scans = 0, scans_ok = 0, scans_degraded = 0, scans_lost = 0, scans_localised = 0;
  std::optional<std::size_t> first_localised_scan;
  std::size_t descriptor_queries = 0;
  std::size_t places_matched = 0;      ///< attempts
  std::size_t places_verified = 0;
  std::size_t hypotheses = 0, hypotheses_dropped = 0, hypotheses_ignored = 0;
  std::size_t scans_ambiguous = 0;     ///< a hypothesis had its support but another was alive
  std::size_t tracking_failures = 0;
  std::size_t tracking_checks = 0;
  std::size_t tracking_contradicted = 0;
  std::size_t tracking_corrections = 0;  ///< a verified place nearby fitted clearly better
  std::size_t implausible_jumps = 0;     ///< tracking ended: the scans jumped (Localizer3dOptions::max_acceleration_mps2)
  std::vector<LocalizationAttempt3d> attempts;
  std::vector<Relocalisation3d> relocalisations;
  /// Map: keyframes, points, points of the matching target. Setup: seconds to build it.
  std::size_t map_keyframes = 0, map_points = 0, target_points = 0;
  double setup_s = 0.0;
  double total_s = 0.0;
  double max_scan_s = 0.0;
  double max_search_s = 0.0;           ///< slowest global search of one scan
};

class Localizer3d {
 public:
  /// Builds the matching structures of `map` (kept, never changed). Throws std::invalid_argument
  /// for invalid options or a map without points or keyframes.
  explicit Localizer3d(SavedMap3D map, const Localizer3dOptions& options = {});
  ~Localizer3d();
  Localizer3d(const Localizer3d&) = delete;
  Localizer3d& operator=(const Localizer3d&) = delete;

  /// Localises one scan taken at `time_s` (strictly increasing; std::invalid_argument otherwise).
  Localization3dResult add_scan(const io::PointCloud& cloud, double time_s);

  const SavedMap3D& map() const;
  const Localizer3dSummary& summary() const { return summary_; }
  Localization3dState state() const;
  const Localizer3dOptions& options() const { return options_; }
  /// The odometry options the map's sensor model gives (what every scan is preprocessed with).
  static LidarOdometryOptions odometry_options(const SavedSensorModel& sensor, int threads);

 private:
  struct Impl;
  Localizer3dOptions options_;
  std::unique_ptr<Impl> impl_;
  Localizer3dSummary summary_;
};

}  // namespace cairn::lidar3d
