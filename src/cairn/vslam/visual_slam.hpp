#pragma once
/// \file
/// Stereo and RGB-D visual SLAM after ORB-SLAM2 (Mur-Artal & Tardos, "ORB-SLAM2: an Open-Source SLAM
/// System for Monocular, Stereo and RGB-D Cameras", T-RO 2017), fed one frame at a time:
///
/// * tracking (Sec. III-B/C, ORB-SLAM2 Tracking.cc): ORB features, stereo matches (or depth), the
///   previous frame's map points projected with a constant-velocity prediction and matched in a
///   radius, motion-only bundle adjustment (4 rounds of 10 iterations, Huber at the chi^2 95 %
///   thresholds 5.991 / 7.815, outliers dropped between rounds), then the local map (the points of
///   the keyframes that share points with the frame) projected and matched, and a second motion-only
///   BA; when the prediction finds too few matches, brute-force descriptor matching against the
///   reference keyframe's points replaces it (ORB-SLAM2 uses bag-of-words there);
/// * keyframes (NeedNewKeyFrame, stereo rules): when the frame tracks fewer than 75 % of the
///   reference keyframe's points or too few close points; a keyframe creates map points from its
///   stereo/depth points (every close one, at least the 100 nearest);
/// * local mapping (LocalMapping.cc; its bundle adjustment in its own thread for stereo and RGB-D,
///   VisualSlamOptions::local_mapping_thread): map-point culling (found / visible < 0.25,
///   or seen by too few keyframes after two keyframes), local bundle adjustment on the least-squares
///   engine (backend/least_squares.hpp; keyframe poses and points, points eliminated by Schur,
///   the covisible keyframes free, the others that see their points fixed; 5 iterations, outliers
///   removed, 10 more), outlier observations erased; keyframe culling (KeyFrameCulling: a covisible
///   keyframe whose close points other keyframes already see is removed, VisualSlamOptions::keyframe_culling).
///
/// Poses are T_world_camera, world = the first frame's camera (x right, y down, z forward).
/// What is not in this version: docs/vslam.md, "Not in this version".

#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "cairn/core/health.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/inertial/imu_types.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/vslam/saved_map.hpp"

namespace cairn::vslam {

/// Stereo-inertial and RGB-D-inertial tracking (issue 40, its first part; ORB-SLAM3, Campos et
/// al., T-RO 2021, Sec. V and VII; docs/vslam.md "With an IMU"). On when `enabled` and the
/// caller feeds VisualSlam::add_imu. Once the keyframes span `initialisation_window_s`, the
/// inertial-only MAP estimate of Campos et al. (ICRA 2020; inertial/inertial_initialization.hpp)
/// gives gravity's direction in the visual world, the keyframes' velocities and the biases (and,
/// with one camera, the scale: the map segment is then rescaled to metres), and is run again
/// over the last `refinement_window_s` at every keyframe (with one camera watching the scale). From then on the IMU,
/// preintegrated from the last frame's state (Forster et al., T-RO 2017), predicts each frame's
/// pose in place of the constant-velocity model, and a frame the images do not track (blank,
/// blurred, texture-less) takes that prediction: `degraded`, not lost, for up to `max_carried_s`.
struct VisualInertialOptions {
  bool enabled = false;
  /// The camera (left, or the RGB-D camera) in the IMU's frame: EuRoC's cam0 sensor.yaml T_BS.
  core::SE3 T_body_camera;
  inertial::ImuNoise noise;  ///< EuRoC's ADIS16448 by default
  double gravity_mps2 = inertial::kStandardGravity;
  /// Keyframes over at least this long before the first initialisation (ORB-SLAM3: 2 s); >= 1.
  double initialisation_window_s = 2.0;
  /// Every keyframe re-estimates gravity, velocities and biases over the keyframes of its last
  /// this-many seconds (ORB-SLAM3 refines at 5 s and 15 s, then keeps the estimates in its
  /// visual-inertial local BA); >= initialisation_window_s.
  double refinement_window_s = 3.0;
  /// A frame the images do not track takes the IMU's prediction for at most this long after the
  /// last tracked frame (ORB-SLAM3's RECENTLY_LOST lasts 5 s); then it is lost. >= 0.
  double max_carried_s = 1.5;
  /// A tracked frame whose visual pose is farther than this from the IMU's prediction is
  /// `degraded` (the images or the IMU are wrong: a look-alike, a moving scene, a bad reading);
  /// the distances are the prediction's, so they must cover its error over one frame. > 0.
  double disagreement_m = 0.1;
  double disagreement_deg = 3.0;
  /// Monocular: every estimate after the first also estimates the map's scale; when it is more
  /// than this fraction off 1 (the map's unit is no longer the metre the first estimate made
  /// it: the scale has drifted or collapsed), the frames are `degraded` and the IMU stops
  /// predicting until an estimate agrees again. In (0, 1).
  double max_scale_drift = 0.25;
  /// ... judged only over windows whose keyframes accelerate by at least this much (RMS, m/s^2):
  /// the IMU sees the scale through acceleration alone. >= 0.
  double min_scale_excitation_mps2 = 0.3;
  /// The IMU in the local bundle adjustment (ORB-SLAM3 LocalInertialBA): the newest keyframes of
  /// the local window get velocities and biases, joined by IMU and bias random walk factors.
  bool local_ba = true;
  /// A loop within the map the IMU initialised is corrected in 4 DoF: yaw about gravity and
  /// position (ORB-SLAM3 OptimizeEssentialGraph4DoF); roll and pitch, which gravity makes
  /// observable, are kept. Off: as without an IMU (SE(3), monocular Sim(3)).
  bool four_dof_loops = true;
  /// The IMU in the motion-only BA of a tracked frame (ORB-SLAM3 PoseInertialOptimizationLastFrame):
  /// the IMU's factor from the last frame's state, whose covariance the last frame's optimisation
  /// gave, else these sigmas (pose position, rotation; velocity). > 0.
  bool pose_optimisation = true;
  double pose_sigma_m = 0.01;
  double pose_sigma_deg = 0.2;
  double velocity_sigma_mps = 0.1;
  bool is_valid(std::string* why) const;
};

struct VisualSlamOptions {
  vision::OrbOptions orb;  ///< ORB-SLAM2: 2000 features for KITTI, 1000 for TUM (cairn vslam sets this)
  vision::StereoOptions stereo;
  /// Points nearer than this many baselines are "close" (ORB-SLAM2's ThDepth: 35 for KITTI, 40
  /// for TUM; in RGB-D the virtual baseline counts).
  double close_depth_baselines = 35.0;
  int min_new_points = 100;              ///< a new keyframe creates at least this many points (nearest first)
  double motion_search_radius_px = 7.0;  ///< TrackWithMotionModel's th for stereo, x level scale
  /// ... and for RGB-D. ORB-SLAM2 uses 15 for every non-stereo sensor; on TUM fr1/desk at every
  /// 4th frame (the only RGB-D data here) 15 kept 61 of 149 frames tracked, 7 kept 114
  /// (2026-11-25, docs/vslam.md): the wider radius let in wrong matches that held the keyframe
  /// rule back until the map no longer covered the view.
  double motion_search_radius_rgbd_px = 7.0;
  double motion_search_radius_mono_px = 15.0;  ///< ORB-SLAM2's th for monocular
  double local_search_radius_px = 1.0;   ///< SearchLocalPoints' th (x 2.5 or 4 by viewing angle, x level scale)
  int max_descriptor_distance = 100;     ///< ORB-SLAM's TH_HIGH
  double local_match_ratio = 0.8;        ///< best / second best at the same level
  double reference_match_ratio = 0.7;    ///< brute-force fallback against the reference keyframe
  int min_motion_matches = 20;           ///< fewer: widen the radius, then the fallback
  int degraded_below_inliers = 50;       ///< `degraded` below (ORB-SLAM2 needs 30 to stay tracking)
  int lost_below_inliers = 15;           ///< `lost` below (the seed: ORB-SLAM3 fails below ~15)
  double keyframe_tracked_ratio = 0.75;  ///< new keyframe when inliers < this x the reference keyframe's points
  int keyframe_close_tracked = 100;      ///< ... or fewer tracked close points than this
  int keyframe_close_untracked = 70;     ///<     while more untracked close points than this
  int keyframe_max_frames = 10;          ///< and at least one keyframe per this many frames (the frame rate)
  /// Monocular only: also a keyframe once the camera has turned more than this fraction of the
  /// horizontal field of view since the last keyframe (0 = off). cairn's, not ORB-SLAM2's (DSO
  /// makes keyframes on a change of the field of view, Engel et al., PAMI 2018, Sec. 3.1). A
  /// monocular map only grows by triangulation between keyframes; turning fast between two of
  /// them, the view's new side has no points, the matches shrink to a strip at one edge, a
  /// strip of wall at one depth cannot tell a turn from a sideways step, and a wrong pose that
  /// becomes a keyframe triangulates wrong depths: on the synthetic loop route looking 45
  /// degrees left of the travel the scale collapsed to 0.013 of itself with every frame `ok`
  /// (measured 2026-11-25, docs/vslam.md).
  double monocular_keyframe_turn_fov = 0.2;
  int max_local_ba_keyframes = 20;       ///< covisible keyframes optimised (most shared points first)
  int min_covisible_points = 15;         ///< keyframes sharing fewer points are not covisible
  int local_map_keyframes = 40;          ///< keyframes whose points make the local map
  double chi2_mono = 5.991;              ///< 2 DOF, 95 %
  double chi2_stereo = 7.815;            ///< 3 DOF, 95 %
  bool local_ba = true;
  /// Local mapping in its own thread (ORB-SLAM3's LocalMapping beside Tracking): a keyframe's
  /// local bundle adjustment runs in the background while the next frame is read and its ORB
  /// extracted, and is joined (then keyframe culling and loop closing) before that frame is
  /// tracked; deterministic. Off: all of it within the keyframe's frame, as before. Stereo and
  /// RGB-D only: a monocular map, grown by triangulation alone, is tracked against the adjusted
  /// keyframe (on the synthetic 45-degree route with an IMU, the thread let the scale drift to
  /// 0.56 of itself, ATE 0.83 m, against 0.98 and 0.056 m; docs/vslam.md).
  bool local_mapping_thread = true;
  /// New points triangulated between a new keyframe and this many of its most covisible ones
  /// (ORB-SLAM2 CreateNewMapPoints: 10 for stereo/RGB-D); 0 = only stereo/depth creates points.
  /// Off by default, measured (2026-11-25, docs/vslam.md): with 10, KITTI's per-frame rotation
  /// error fell from 0.107 (0.096 since) to 0.045 degrees but its scale moved from 0.964 to 0.938 of the ground
  /// truth's and TUM's main-map ATE rose from 0.0226 to 0.0277 m: without ORB-SLAM2's
  /// bag-of-words-node restriction the epipolar search still lets wrong matches through.
  int triangulation_keyframes = 0;
  double triangulation_match_ratio = 0.6;  ///< best / second best descriptor distance along the epipolar band
  /// Cull redundant keyframes after each local BA (ORB-SLAM2 LocalMapping::KeyFrameCulling, T-RO
  /// 2017 Sec. V-E): a keyframe covisible with the newest one, >= 90 % of whose close points are
  /// seen by >= 3 other keyframes at the same or a finer level (ORB-SLAM2: up to one level
  /// coarser). Stereo and RGB-D only. Default and measurements: docs/vslam.md.
  bool keyframe_culling = true;
  /// Fuse duplicate points after each new keyframe (ORB-SLAM2 LocalMapping::SearchInNeighbors
  /// with ORBmatcher::Fuse): the newest keyframe's points projected into its covisible keyframes
  /// and theirs into it; a keypoint that already holds another point merges the two. Without it
  /// a physical point seen from several keyframes is often several map points, each seen once.
  bool fuse_points = true;
  /// The fraction of a keyframe's close points that must be redundant (ORB-SLAM2: 0.9), in (0, 1].
  double keyframe_culling_redundancy = 0.9;
  /// Place recognition for loop closure and relocalisation (DBoW2-style, vision/vocabulary.hpp);
  /// null = neither (tracking loss then tries the 8 most recent keyframes only). It must not have
  /// been trained on the images it is used on.
  std::shared_ptr<const vision::Vocabulary> vocabulary;
  bool loop_closure = true;
  /// Match relocalisation, fallback and loop candidates only within vocabulary nodes (ORB-SLAM2's
  /// SearchByBoW, ratio 0.75) instead of by brute force (ratio 0.7). Off by default, measured on
  /// TUM fr1/desk every 4th frame (2026-11-25, docs/vslam.md): before the image-alignment start,
  /// on gave 82 frames in the main map at 0.0197 m but the desk revisit no longer verified (15
  /// PnP inliers < 20), off 60 frames at 0.0140 m with the revisit merged; since it, both give
  /// 147 frames (0.0169 and 0.0165 m).
  bool bow_restricted_matching = false;
  /// When the motion model's prediction explains too little (or tracking was lost), predict the
  /// rotation from the whole image before falling back to descriptor matching: PTAM's small
  /// blurry images (Klein & Murray, ECCV 2008, Sec. 4; vision/image_alignment.hpp), aligned
  /// with the last tracked frame's, then the last frame's points are searched around that pose.
  bool image_alignment = true;
  /// ECC correlation below which the images' rotation is not used.
  double image_alignment_min_correlation = 0.7;
  int loop_min_keyframes_apart = 10;   ///< no loop with the last 10 keyframes, none within 10 of the last loop (ORB-SLAM2)
  int loop_consistency = 3;            ///< consecutive keyframes whose candidates agree (ORB-SLAM2 mnCovisibilityConsistencyTh)
  int loop_min_pnp_inliers = 20;       ///< descriptor matches to, and PnP RANSAC inliers of, the candidate's points (ORB-SLAM2 ComputeSim3: 20 and 20)
  int loop_min_matches = 40;           ///< map-point matches after projecting the candidate's neighbourhood (ORB-SLAM2: 40)
  /// ORB-SLAM2 Relocalization: 50. Also the uniqueness test (cairn's; tracking.cpp
  /// relocalisation_rival): when another candidate passes it at another place (farther than the
  /// loop_drift_* bounds allow, or in another unmerged segment) the frame stays lost. Loops and
  /// merges are tested alike with their own verification (loop_closing.cpp loop_rival).
  int relocalisation_min_inliers = 50;
  /// A loop within a map segment is refused when it would move the keyframe further than the
  /// drift the keyframes since the candidate could have gathered: floor + fraction x distance
  /// travelled, floor + deg_per_m x distance for the rotation (stereo visual odometry drifts
  /// 1-2 %; an identical room 10 m away asks for a 10 m correction). Not ORB-SLAM2's; cairn's
  /// guard against aliasing, measured in tests/vslam/test_vslam_synthetic.cpp.
  double loop_drift_floor_m = 0.5;
  double loop_drift_fraction = 0.05;
  double loop_drift_floor_deg = 5.0;
  double loop_drift_deg_per_m = 0.5;
  bool global_ba_after_loop = true;    ///< a full bundle adjustment after each loop correction
  /// The Atlas (ORB-SLAM3, Campos et al. 2021, Sec. IV): after this many lost frames in a row, a
  /// frame with enough stereo/depth points starts a new map segment (its own keyframes and
  /// points, placed where the motion model guessed, with no constraint to the old ones); a
  /// monocular run feeds its lost frames to a new two-view initialisation instead (the segment
  /// placed where tracking was lost, its unit guessed). A verified loop between segments merges
  /// them (the same verification as a loop; Sim(3) for monocular). 0 = never.
  int new_map_after_lost_frames = 3;
  /// A new segment's first this-many keyframes each try to merge with the 8 keyframes tracked
  /// last before it (verified as a loop; no vocabulary needed). 0 = only place recognition merges.
  int merge_recent_keyframes_of_new_map = 10;
  VisualInertialOptions inertial;
  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
};

using TrackingHealth = core::Health;  // ok / degraded / lost (core/health.hpp)
using core::to_string;

struct FrameTimes {
  double features_s = 0.0;  ///< ORB on both images (in parallel for stereo)
  double stereo_s = 0.0;    ///< stereo matching or depth lookup
  double tracking_s = 0.0;  ///< motion model / reference, pose optimisation, local map
  double mapping_s = 0.0;   ///< keyframe insertion, culling, local BA (with the mapping thread: the previous keyframe's join, and this one's insertion)
  double total_s = 0.0;
};

struct FrameResult {
  std::size_t frame = 0;
  core::Timestamp time;
  bool tracked = false;  ///< false: the pose is the motion model's guess (health lost)
  TrackingHealth health = TrackingHealth::kLost;
  core::SE3 T_world_camera;
  int features = 0;
  int stereo_points = 0;       ///< keypoints with a stereo match or depth
  int motion_matches = 0;      ///< matches of the first stage (prediction or reference)
  bool used_reference = false; ///< the first stage fell back to the reference keyframe
  bool used_image_alignment = false; ///< the first stage's pose came from the images' rotation (PTAM SBI)
  int inliers = 0;             ///< map-point matches after the local map's pose optimisation
  double inlier_ratio = 0.0;   ///< inliers / matches given to that optimisation
  bool keyframe = false;
  bool relocalised = false;  ///< the pose came from a place-recognition match after being lost
  /// A relocalisation candidate was found and refused (ambiguous, or fewer inliers than
  /// relocalisation_min_inliers): the frame stays lost, the reason in `note`.
  bool relocalisation_refused = false;
  bool loop_closed = false;  ///< this frame's keyframe closed a loop
  bool new_map = false;      ///< this frame started a new map segment after being lost
  /// With an IMU (VisualInertialOptions): the first stage searched around the IMU's prediction,
  /// and the frame, untracked by the images, took that prediction (health degraded, tracked false).
  bool imu_predicted = false;
  bool carried_by_imu = false;
  int segment = 0;           ///< the map segment the frame was tracked in (at that time)
  double sigma_position_m = 0.0;  ///< sqrt of the largest eigenvalue of the position covariance
  FrameTimes times;
  std::string note;  ///< why lost / degraded
  /// The frame's keypoints and what became of each: 0 unmatched, 1 stereo/depth point only,
  /// 2 matched to a map point (an inlier of the pose). For pictures; the caller may drop them.
  std::vector<cv::KeyPoint> keypoints;
  std::vector<signed char> keypoint_states;
};

/// One loop candidate and what became of it.
struct LoopRecord {
  std::size_t keyframe = 0;   ///< the querying keyframe (index)
  std::size_t candidate = 0;  ///< the candidate keyframe
  std::size_t frame = 0, candidate_frame = 0;
  double score = 0.0;         ///< BoW L1 score; -1 for a merge attempt proposed by recency
  double min_covisible_score = 0.0;  ///< the query's lowest score with its covisible keyframes
  int consistency = 0;        ///< consecutive keyframes with agreeing candidates
  int pnp_inliers = 0, matches = 0;
  std::string decision;       ///< "accepted", "rejected", or "revisit" (a return tracking had already joined: verified, nothing corrected)
  std::string reason;
  bool merge = false;         ///< the candidate lies in another map segment: accepting it merges the two
  double correction_m = 0.0, correction_deg = 0.0;  ///< how far the keyframe moved (accepted; monocular: in map units)
  double scale = 1.0;         ///< monocular: the Sim(3) scale between the keyframe's and the candidate's maps
};

struct VisualSlamSummary {
  std::size_t frames = 0, frames_ok = 0, frames_degraded = 0, frames_lost = 0;
  std::size_t keyframes = 0, map_points = 0, map_points_culled = 0;
  std::size_t local_bas = 0, reference_fallbacks = 0;
  /// Frames whose first-stage pose came from the images' rotation (VisualSlamOptions::image_alignment).
  std::size_t image_alignment_poses = 0;
  double local_ba_s = 0.0;
  std::size_t loop_queries = 0, loops_accepted = 0, relocalisations = 0, global_bas = 0;
  /// Relocalisations refused because another place verified as well (the frame stayed lost),
  /// and loops / merges refused for the same reason (tracking.cpp relocalisation_rival, loop_closing.cpp loop_rival).
  std::size_t relocalisations_ambiguous = 0, loops_ambiguous = 0;
  std::size_t map_points_fused = 0;  ///< duplicates merged (loop closure and SearchInNeighbors)
  std::size_t fusion_observations = 0;  ///< observations added to existing points by SearchInNeighbors
  std::size_t maps_started = 0, maps_merged = 0;  ///< segments beyond the first; merges of two
  std::size_t merge_attempts = 0;  ///< verifications of a new segment against the keyframes tracked last before it
  /// Returns to a place that tracking joined to the old map by itself (the old keyframe shares
  /// points with the new one), verified as a loop (decision "revisit" in `loops`); no correction.
  std::size_t revisits_verified = 0;
  /// Keyframes culled as redundant (VisualSlamOptions::keyframe_culling); `keyframes` counts every
  /// keyframe made, so the map holds keyframes - keyframes_culled.
  std::size_t keyframes_culled = 0;
  double loop_s = 0.0, global_ba_s = 0.0;
  /// With an IMU: frames carried by it alone; inertial estimates made (the first one is the
  /// initialisation) and refused (the last reason kept); when the first succeeded.
  std::size_t frames_carried_by_imu = 0, inertial_estimates = 0, inertial_estimates_refused = 0;
  bool local_mapping_thread = false;  ///< a keyframe's local BA ran in its own thread (stereo / RGB-D with the option on)
  std::size_t frames_contradicting_imu = 0;  ///< tracked frames the IMU's prediction contradicts (degraded)
  /// Monocular with an IMU: the scale the first estimate gave the map (metres per unit of the
  /// two-view initialisation), the last estimate's scale of the map since (1 when it holds), and
  /// the frames degraded because it was more than max_scale_drift off.
  double monocular_initial_scale = 0.0, monocular_scale_estimate = 1.0;
  std::size_t frames_scale_drifted = 0;
  std::size_t scale_estimates_unexcited = 0;  ///< refinements that held the scale (too little acceleration to judge it)
  /// Local bundle adjustments with IMU factors (VisualInertialOptions::local_ba), and the IMU
  /// factors in them (one per pair of consecutive keyframes).
  std::size_t inertial_local_bas = 0, inertial_local_ba_factors = 0;
  std::size_t loops_corrected_in_4dof = 0;  ///< loop corrections in 4 DoF (VisualInertialOptions::four_dof_loops)
  std::string inertial_refusal;
  double inertial_initialised_at_s = -1.0;  ///< the frame time of the first estimate; -1: never
  double inertial_s = 0.0;                  ///< time in the inertial estimates
  std::vector<LoopRecord> loops;  ///< every candidate that reached verification, and why
};

class VisualSlam {
 public:
  VisualSlam(const io::CameraCalibration& camera, io::SequenceKind kind, const VisualSlamOptions& options = {});
  /// Localisation in a saved map (ORB-SLAM2's localisation mode, T-RO 2017 Sec. III-F): the
  /// map's camera, sequence kind and ORB settings; tracking as above, but no keyframe, point,
  /// loop or map segment is ever added and the map's points and poses never change; the first
  /// frame, and every frame after a loss, relocalises (bag of words when `options.vocabulary`,
  /// PnP, the local map, relocalisation_min_inliers and the uniqueness test). Throws
  /// std::invalid_argument for invalid options, a map without keyframes, or a map indexed with a
  /// vocabulary when none is given (map_incompatibility).
  VisualSlam(const SavedVisualMap& map, const VisualSlamOptions& options);
  ~VisualSlam();
  VisualSlam(const VisualSlam&) = delete;
  VisualSlam& operator=(const VisualSlam&) = delete;

  /// A rectified stereo pair (8-bit grey, same size).
  FrameResult add_stereo(core::Timestamp time, const cv::Mat& left, const cv::Mat& right);
  /// A grey image and its registered 16-bit depth image.
  FrameResult add_rgbd(core::Timestamp time, const cv::Mat& gray, const cv::Mat& depth);
  /// One grey image (monocular): the first frames initialise the map from two views (ORB-SLAM2's
  /// homography / essential-matrix selection); the scale is not observable and is set so that
  /// the initial scene's median depth is 1 (with an IMU, the inertial estimate rescales it to
  /// metres). No loop closure (needs Sim(3)) and no new map
  /// segments (need a new initialisation) in this version.
  FrameResult add_monocular(core::Timestamp time, const cv::Mat& gray);
  /// One IMU reading (options.inertial.enabled): readings come in time order, each before the
  /// frames it spans (a frame at t needs a reading at or after t to be predicted). Throws
  /// std::invalid_argument for a reading out of order or not finite, std::logic_error when the
  /// IMU is not enabled.
  void add_imu(const inertial::ImuSample& sample);
  /// The inertial estimate (after the first initialisation): gravity in the visual world, m/s^2,
  /// and the biases; nothing before it.
  bool inertial_initialised() const;
  Eigen::Vector3d gravity_world() const;
  inertial::ImuBias imu_bias() const;

  /// Every frame's pose, through its reference keyframe at the keyframe's current (bundle-
  /// adjusted) pose, as ORB-SLAM2 writes its trajectory.
  std::vector<core::SE3> trajectory() const;
  /// The keyframes in the map (culled ones left out), in order of creation.
  std::vector<core::SE3> keyframe_poses() const;
  /// Their frames' indices (localising in a saved map: the mapping run's frames) and times.
  std::vector<std::size_t> keyframe_frames() const;
  std::vector<core::Timestamp> keyframe_times() const;
  /// Per frame, the map segment it belongs to now (merges applied; the segment of keyframe 0 is
  /// the main map, main_segment()); -1 for a frame before the first keyframe.
  std::vector<int> frame_segments() const;
  int main_segment() const;
  /// The good map points in the world frame.
  std::vector<Eigen::Vector3d> map_points() const;
  /// The main map segment (keyframes, points, covisibility; saved_map.hpp), to save with
  /// write_saved_map (map_file.hpp). Throws std::logic_error before the first keyframe.
  SavedVisualMap saved_map(std::string configuration_json = {}, std::string source = {}) const;
  /// True when made from a saved map (the map is then never changed).
  bool localization_only() const;
  /// The run's counts (a keyframe's local mapping still running is taken first).
  const VisualSlamSummary& summary() const;
  const VisualSlamOptions& options() const { return options_; }

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  VisualSlamOptions options_;
  VisualSlamSummary summary_;
};

/// Why images of `kind` taken with `camera` cannot be localised in `map`, "; "-separated, or ""
/// when they can: another sequence kind, another camera (intrinsics, distortion, stereo baseline
/// or depth scale differ by more than 1e-9 relative), another image size (when camera.width and
/// height are set), or no vocabulary for a map indexed with one.
std::string map_incompatibility(const SavedVisualMap& map, const io::CameraCalibration& camera, io::SequenceKind kind,
                                const vision::Vocabulary* vocabulary);
/// A warning, or "": the map was indexed with another vocabulary than `vocabulary` (its keyframes'
/// words are then recomputed with the given one, so it works, but a vocabulary trained on other
/// images may relocalise less well).
std::string vocabulary_mismatch(const SavedVisualMap& map, const vision::Vocabulary* vocabulary);

}  // namespace cairn::vslam
