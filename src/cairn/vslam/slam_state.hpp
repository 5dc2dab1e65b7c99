#pragma once
/// \file
/// Internal to cairn::vslam: the state of VisualSlam (frames, map points, keyframes, the Atlas's
/// segments, the place-recognition database) and the declaration of VisualSlam::Impl, whose
/// methods live in tracking.cpp (frames, matching, motion-only BA, local-map tracking, one frame),
/// local_mapping.cpp (keyframes, triangulation, culling, local and global BA), loop_closing.cpp
/// (loop detection, verification, correction, merges) and initialisation.cpp (monocular
/// two-view initialisation). Not installed; include only from those files.

#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <set>
#include <tuple>
#include <unordered_map>
#include "cairn/backend/least_squares.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/inertial/imu_types.hpp"
#include "cairn/inertial/preintegration.hpp"
#include "cairn/io/pose_graph.hpp"
#include "cairn/backend/reprojection_factors.hpp"
#include "cairn/vision/image_alignment.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::vslam {
namespace internal {


using core::Clock;
using core::seconds_since;

// A factor whose residual and Jacobians are scaled by sqrt(information) = 1 / sigma of the
// keypoint's level (ORB-SLAM2's invLevelSigma2 information), optionally with the point held
// fixed inside it (motion-only BA: the factor then has the pose as its only variable).
class ScaledFactor final : public backend::Factor {
 public:
  ScaledFactor(std::unique_ptr<backend::Factor> inner, double sqrt_information, const Eigen::Vector3d* fixed_point = nullptr)
      : inner_(std::move(inner)), weight_(sqrt_information), fixed_(fixed_point != nullptr) {
    if (fixed_point) point_ = *fixed_point;
  }
  int residual_size() const override { return inner_->residual_size(); }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    const int m = inner_->residual_size();
    bool ok;
    if (fixed_) {
      const double* v[2] = {values[0], point_.data()};
      double* j[2] = {jacobians ? jacobians[0] : nullptr, nullptr};
      ok = inner_->evaluate(v, residual, jacobians ? j : nullptr);
    } else {
      ok = inner_->evaluate(values, residual, jacobians);
    }
    if (!ok) return false;
    for (int i = 0; i < m; ++i) residual[i] *= weight_;
    if (jacobians) {
      const int blocks = fixed_ ? 1 : 2;
      const int sizes[2] = {6, 3};
      for (int b = 0; b < blocks; ++b) {
        if (!jacobians[b]) continue;
        for (int i = 0; i < m * sizes[b]; ++i) jacobians[b][i] *= weight_;
      }
    }
    return true;
  }

 private:
  std::unique_ptr<backend::Factor> inner_;
  double weight_;
  bool fixed_;
  Eigen::Vector3d point_ = Eigen::Vector3d::Zero();
};

// The best and second-best descriptor distance of a search and the best candidate: the ratio
// tests of every ORB-SLAM2 matcher.
struct BestTwo {
  int best = 256, second = 256, index = -1;
  void offer(int distance, int candidate) {
    if (distance < best) {
      second = best;
      best = distance;
      index = candidate;
    } else if (distance < second) {
      second = distance;
    }
  }
  /// A candidate within `max_distance` and better than `ratio` x the second best.
  bool passes(int max_distance, double ratio) const { return index >= 0 && best <= max_distance && best < ratio * second; }
};

constexpr int kGridCols = 64;
constexpr int kGridRows = 48;

struct FrameData {
  std::size_t index = 0;
  core::Timestamp time;
  std::vector<cv::KeyPoint> keypoints;
  std::vector<Eigen::Vector2d> undistorted;
  std::vector<double> u_right, depth;
  cv::Mat descriptors;
  std::vector<int> map_point;  // id or -1
  std::vector<char> outlier;
  std::vector<std::vector<int>> grid;
  core::SE3 T_world_camera;
  vision::SmallBlurryImage sbi;  // PTAM's small blurry image of the frame (empty: not made)
  std::size_t size() const { return keypoints.size(); }
};

struct MapPoint {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  cv::Mat descriptor;  // 1 x 32
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double min_distance = 0.0, max_distance = 0.0;
  std::map<int, int> observations;  // keyframe id -> keypoint index
  int first_keyframe = 0;
  int reference_keyframe = 0;
  int visible = 1, found = 1;
  bool bad = false;
  std::uint64_t last_search = 0;  // search_by_projection's stamp: considered already
};

struct KeyFrame {
  int id = 0;
  FrameData frame;
  int segment = 0;              // the map segment it was created in
  bool starts_segment = false;  // the first keyframe of a segment: no odometry link to the one before
  vision::BowVector bow;              // empty without a vocabulary
  std::vector<std::uint32_t> nodes;   // per keypoint, its vocabulary node two levels below the root
  // Culled as redundant (ORB-SLAM2 KeyFrame::SetBadFlag): out of the covisibility graph, its
  // points' observations and the database; kept only so that frames referring to it still have
  // a pose, through `parent` (an earlier keyframe of its segment, good when culled, maybe culled
  // since) and the relative pose at culling time (ORB-SLAM2's mTcp).
  bool bad = false;
  int parent = -1;
  core::SE3 T_parent_keyframe;
  // With an IMU: the body's velocity (world frame) and the biases at this keyframe, once known
  // (the IMU's prediction when it is made, then the inertial estimates and the visual-inertial
  // local BA; ORB-SLAM3 KeyFrame::mVw, mImuBias).
  bool has_imu_state = false;
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();
  inertial::ImuBias imu_bias;
};


inline vision::OrbOptions doubled(vision::OrbOptions o) {
  o.features *= 2;
  return o;
}

}  // namespace internal

using internal::BestTwo;
using internal::Clock;
using internal::doubled;
using internal::FrameData;
using internal::KeyFrame;
using internal::kGridCols;
using internal::kGridRows;
using internal::MapPoint;
using internal::ScaledFactor;
using internal::seconds_since;

struct VisualSlam::Impl {
  io::CameraCalibration camera;
  io::SequenceKind kind;
  VisualSlamOptions options;
  VisualSlamSummary* summary = nullptr;
  vision::OrbExtractor orb;
  vision::OrbExtractor orb_initialisation;  // monocular, until initialised: twice the features (ORB-SLAM2 mpIniORBextractor)
  double bf = 0.0;            // fx * baseline (virtual for RGB-D)
  double close_depth_m = 0.0; // ThDepth in metres
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  double cell_w_inv = 0, cell_h_inv = 0;
  int width = 0, height = 0;
  std::vector<double> scales, inv_sigma2;

  std::vector<MapPoint> points;
  std::vector<KeyFrame> keyframes;
  std::vector<int> recent_points;
  FrameData last;
  // The last tracked frame's pose: `last` keeps that frame's matches while lost, but its pose
  // then follows the motion model's guesses.
  core::SE3 T_world_last_tracked;
  bool have_last = false;
  bool have_velocity = false;
  core::SE3 velocity;  // T_last_current of the last step: T_current = T_last * velocity
  int reference_keyframe = -1;
  int last_keyframe_frame = 0;
  std::size_t frames = 0;
  bool lost = false;
  std::uint64_t search_stamp = 0;
  // Place recognition.
  vision::BowDatabase database;
  int last_loop_keyframe = 0;
  int last_revisit_keyframe = -1;  // the last keyframe whose revisit was verified (verify_revisit)
  std::set<int> revisit_tried;      // old keyframes verify_revisit has tried
  std::vector<std::pair<std::set<int>, int>> consistent_groups;  // ORB-SLAM2 mvConsistentGroups
  std::set<int> pending_loop_candidates;  // the candidates behind consistent_groups: never culled (ORB-SLAM2 SetNotErase)
  // The Atlas: map segments, merged by union-find.
  int segment = 0;
  std::vector<int> segment_parent{0};
  int lost_frames = 0;
  int find(int s) const {
    while (segment_parent[static_cast<std::size_t>(s)] != s) s = segment_parent[static_cast<std::size_t>(s)];
    return s;
  }
  int segment_of(int kf) const { return find(keyframes[static_cast<std::size_t>(kf)].segment); }
  // The keyframe that holds its segment's gauge in bundle adjustment: the first keyframe of a
  // segment not merged into an older one (keyframe 0 always; ORB-SLAM3 fixes each map's first
  // keyframe). Without it a young segment's local BA has no fixed pose at all.
  bool anchors_segment(int kf) const {
    const KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
    return k.starts_segment && find(k.segment) == k.segment;
  }
  // Per frame: reference keyframe and the pose relative to it, for the final trajectory.
  std::vector<std::pair<int, core::SE3>> relative;
  // Visual-inertial (inertial_tracking.cpp; VisualInertialOptions).
  std::vector<inertial::ImuSample> imu_samples;  // time order; those no estimate needs any more dropped
  bool imu_initialised = false;
  Eigen::Vector3d gravity_world = Eigen::Vector3d::Zero();  // in the visual world
  inertial::ImuBias imu_bias;
  bool have_imu_state = false;
  inertial::NavState imu_state;  // the body at the last frame (tracked or carried)
  // ... the covariance of its camera pose and velocity, when a visual-inertial pose optimisation
  // gave it (else inertial_pose_terms assumes VisualInertialOptions' defaults).
  bool have_imu_state_covariance = false;
  Eigen::Matrix<double, 6, 6> imu_state_pose_covariance = Eigen::Matrix<double, 6, 6>::Identity();
  Eigen::Matrix3d imu_state_velocity_covariance = Eigen::Matrix3d::Identity();
  core::Timestamp imu_state_time;
  core::Timestamp last_tracked_time;  // for max_carried_s
  int inertial_segment = -1;   // the segment the estimates are for (a new one starts them again)
  bool scale_drifted = false;  // monocular: the last estimate's scale was more than max_scale_drift off
  // A keyframe's pose; a culled one's through its chain of parents (ORB-SLAM2's trajectory
  // writer walks mpParent with mTcp the same way).
  core::SE3 keyframe_pose(int kf) const {
    if (!keyframes[static_cast<std::size_t>(kf)].bad) return keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera;
    core::SE3 T_parent_kf;
    while (keyframes[static_cast<std::size_t>(kf)].bad) {
      const KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
      T_parent_kf = k.T_parent_keyframe * T_parent_kf;
      kf = k.parent;
    }
    return keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera * T_parent_kf;
  }

  ~Impl() {
    if (mapping_job.running) mapping_job.group.wait();
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  Impl(const io::CameraCalibration& c, io::SequenceKind k, const VisualSlamOptions& o)
      : camera(c), kind(k), options(o), orb(o.orb), orb_initialisation(doubled(o.orb)) {
    const double baseline = kind == io::SequenceKind::kStereo ? camera.baseline_m : camera.virtual_baseline_m;
    bf = camera.fx * baseline;
    close_depth_m = options.close_depth_baselines * baseline;
    double s = 1.0;
    for (int l = 0; l < options.orb.levels; ++l) {
      scales.push_back(s);
      inv_sigma2.push_back(1.0 / (s * s));
      s *= options.orb.scale_factor;
    }
  }

  bool cell_of(double x, double y, int& cx, int& cy) const {
    cx = static_cast<int>(std::floor((x - min_x) * cell_w_inv));
    cy = static_cast<int>(std::floor((y - min_y) * cell_h_inv));
    return cx >= 0 && cx < kGridCols && cy >= 0 && cy < kGridRows;
  }

  // Made from a saved map (VisualSlam(const SavedVisualMap&, ...)): tracking only; the map's
  // keyframes, points and their statistics are never changed.
  bool localization_only = false;
  // --- Map reuse (map_reuse.cpp) ---
  SavedVisualMap export_main_segment() const;
  void export_keyframe_observations(const KeyFrame& kf, int k, SavedVisualMap& map, std::unordered_map<int, int>& point_index) const;
  void import_map(const SavedVisualMap& map);

  // Monocular, until initialised: the reference frame of the two-view initialisation.
  FrameData init_reference;
  bool have_init_reference = false;

  // --- Camera geometry and the keypoint grid (tracking.cpp) ---
  void set_image_size(int w, int h);
  void build_grid(FrameData& f) const;
  std::vector<int> features_in_area(const FrameData& f, double x, double y, double r, int min_level, int max_level) const;
  bool project(const core::SE3& T_camera_world, const Eigen::Vector3d& p_world, double& u, double& v, double& ur, double& z) const;
  int predict_level(const MapPoint& mp, double distance) const;
  Eigen::Vector3d unproject(const FrameData& f, std::size_t i) const;

  // --- Frames (tracking.cpp) ---
  FrameData make_frame(core::Timestamp time, vision::Features& left, const vision::StereoMatches& stereo) const;

  // --- Map points (tracking.cpp) ---
  void update_normal_and_depth(MapPoint& mp);
  // The observation's descriptor with the least median distance to the others (ORB-SLAM2
  // MapPoint::ComputeDistinctiveDescriptors).
  void update_descriptor(MapPoint& mp);
  int observation_weight(const MapPoint& mp) const;
  void erase_observation(int point, int kf);
  void set_bad(int point);

  // --- Matching (tracking.cpp) ---
  // ORB-SLAM2 ORBmatcher::SearchByProjection(CurrentFrame, LastFrame, th, bMono) without the
  // rotation-histogram check (stereo and RGB-D do not use it).
  int search_from_last(FrameData& current, const FrameData& previous, double radius_px);
  // Brute-force descriptor matching of the frame's keypoints against the points `ids` with a
  // ratio test and TH_LOW (50): the matcher of the reference fallback, relocalisation and loop
  // verification (ORB-SLAM2 restricts these to keypoints in the same bag-of-words node instead).
  int match_brute_force(FrameData& current, const std::vector<int>& point_ids);
  // ORB-SLAM2 ORBmatcher::SearchByBoW when VisualSlamOptions::bow_restricted_matching: the
  // frame's keypoints matched to the keyframe's points only within the same vocabulary node
  // (`frame_nodes`, KeyFrame::nodes), TH_LOW and a 0.75 ratio; else (and without a vocabulary)
  // brute force (match_brute_force).
  int match_to_keyframe(FrameData& current, const std::vector<std::uint32_t>* frame_nodes, const KeyFrame& kf);
  int bow_levels_up() const { return options.vocabulary ? std::max(1, options.vocabulary->depth() - 2) : 1; }
  // PnP with RANSAC (OpenCV's solvePnPRansac, EPnP minimal sets; Lepetit et al. 2009) on the
  // frame's map-point matches: the starting pose when there is no prediction. Matches that are
  // not RANSAC inliers are dropped. Returns the inliers (0 when it fails).
  int pnp_ransac(FrameData& f) const;

  // --- Motion-only bundle adjustment (ORB-SLAM2 Optimizer::PoseOptimization) (tracking.cpp) ---
  // chi^2 of keypoint i of f observing p_world from T_camera_world: the squared reprojection
  // error (u, v and, with stereo/depth, u_right) times the level's information (ORB-SLAM2's
  // chi2() of its edges); infinite behind the camera.
  double chi2(const FrameData& f, std::size_t i, const core::SE3& T_cw, const Eigen::Vector3d& p_world) const;
  double chi2_of(const FrameData& f, std::size_t i, const core::SE3& T_cw) const;
  std::unique_ptr<backend::Factor> observation_factor(const FrameData& f, std::size_t i) const;
  // The IMU's part of a visual-inertial motion-only BA (ORB-SLAM3 Optimizer::
  // PoseInertialOptimizationLastFrame, Campos et al. T-RO 2021 Sec. V): the last frame's state
  // with its covariance (a prior, as ORB-SLAM3's marginalised one), the readings since, the
  // biases; out: this frame's velocity and the covariance of its pose and velocity.
  struct InertialPoseTerms {
    inertial::PreintegratedImu preintegrated;  // last frame -> this frame, with the hold's error
    core::SE3 T_world_camera_previous;
    Eigen::Vector3d v_world_previous = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 6, 6> pose_covariance_previous = Eigen::Matrix<double, 6, 6>::Identity();  // camera, (rho, phi) on the right
    Eigen::Matrix3d velocity_covariance_previous = Eigen::Matrix3d::Identity();
    Eigen::Vector3d v_world = Eigen::Vector3d::Zero();  // out, and the start
    Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Identity();  // out
    Eigen::Matrix3d velocity_covariance = Eigen::Matrix3d::Identity();                      // out
    bool solved = false, covariance_ok = false;                                              // out
  };
  // Returns the inliers; marks outliers in f.outlier; sets f.T_world_camera. With `imu`, the
  // IMU's factor and the last frame's prior join the reprojections (inertial_tracking.cpp).
  int optimize_pose(FrameData& f, double* sigma_position_m = nullptr, InertialPoseTerms* imu = nullptr);
  // The IMU's variables and factors in a motion-only BA whose pose variable is `pose_variable`;
  // `values` (kInertialPoseValues) holds the last frame's pose and velocity, this frame's velocity
  // and the biases. Returns the velocity's variable.
  static constexpr int kInertialPoseValues = 19;
  int add_inertial_pose_terms(const InertialPoseTerms& imu, backend::LeastSquaresProblem& problem, int pose_variable, double* values) const;
  void drop_outliers(FrameData& f);

  // --- Local map (ORB-SLAM2 Tracking::TrackLocalMap) (tracking.cpp) ---
  // Projects the points `ids` (repeats allowed) at f's pose and matches each to the best
  // unmatched keypoint near its projection (ORB-SLAM2 ORBmatcher::SearchByProjection(Frame,
  // vector<MapPoint*>, th) after Frame::isInFrustum): in front, inside the image, within the
  // point's scale-invariance distances, viewed within 60 degrees of its mean viewing direction;
  // radius th x (2.5 or 4 by viewing angle) x the predicted level's scale; the best descriptor
  // within TH_HIGH and, when the second best is on the same level, better than ratio x it.
  // Points the frame already holds are skipped. Returns the new matches.
  int search_by_projection(FrameData& f, const std::vector<int>& ids, double th, bool count_visible);
  // update_statistics false: a trial (a rival place of a relocalisation) that leaves the map's
  // found / visible counts and the reference keyframe as they were.
  int track_local_map(FrameData& f, double* sigma_position_m, int* given, bool update_statistics = true, InertialPoseTerms* imu = nullptr);

  // --- Relocalisation and its uniqueness (tracking.cpp) ---
  // The first stage against keyframe `kf` (ORB-SLAM2 Relocalization's per-candidate steps):
  // `f`'s keypoints matched to the keyframe's points, PnP RANSAC, the motion-only BA. `f` gets
  // the pose and the inlier matches; returns the inliers (0 below 15 matches or PnP inliers).
  int match_pose_to_keyframe(FrameData& f, int kf, const std::vector<std::uint32_t>* frame_nodes, int* matches = nullptr);
  // Path length along the keyframes from a to b, and whether poses of two views, as the map
  // around keyframes a and b gives them, are two places: they differ by more than the drift
  // (loop_drift_*) the keyframes between a and b could have gathered, or a and b lie in
  // different (unmerged) map segments, whose relation is unknown.
  double travelled_between(int a, int b) const;
  bool distinct_places(int kf_a, const core::SE3& T_world_a, int kf_b, const core::SE3& T_world_b) const;
  // The uniqueness test of a relocalisation: `f`, accepted through `accepted_kf` with `inliers`
  // after the local map, against every other candidate keyframe. Returns the reason when another
  // place passes the same test (the frame must stay lost), else "".
  std::string relocalisation_rival(const FrameData& f, int inliers, int accepted_kf, const std::vector<int>& candidates,
                                   const std::vector<std::uint32_t>* frame_nodes);

  // --- Keyframes and local mapping (local_mapping.cpp) ---
  bool need_keyframe(const FrameData& f, int inliers) const;
  void insert_keyframe(FrameData& f, bool starts_segment = false);
  // ORB-SLAM2 LocalMapping::CreateNewMapPoints: the newest keyframe's unmatched keypoints are
  // matched to those of its 10 most covisible keyframes (descriptor within TH_LOW, the best one
  // within 3.84 sigma^2 of the epipolar line; ORB-SLAM2 restricts the search to bag-of-words
  // nodes, here every unmatched keypoint is compared) and triangulated (linear, Hartley &
  // Zisserman 12.2) when the rays' parallax beats the stereo parallax, else taken from the view
  // with the better stereo depth; kept when in front of both cameras, within the chi^2
  // thresholds in both, and at consistent scales (distance ratio within 1.5 x scale factor of
  // the octave ratio). Returns the points created.
  int triangulate_new_points(int current, int count);
  // Its stages (local_mapping.cpp): one covisible keyframe; the epipolar matching; one match
  // triangulated; the new point's checks; the point made.
  int triangulate_with_neighbour(int current, int k2_id, const Eigen::Matrix3d& K_inv);
  std::vector<int> match_along_epipolar_lines(const FrameData& f1, const FrameData& f2, const Eigen::Matrix3d& F12, bool epipole_valid, double ex,
                                              double ey) const;
  bool triangulate_match(const FrameData& f1, std::size_t i1, const FrameData& f2, std::size_t i2, const core::SE3& T1_cw, const core::SE3& T2_cw,
                         const Eigen::Matrix3d& K_inv, Eigen::Vector3d& X) const;
  bool consistent_new_point(const FrameData& f1, std::size_t i1, const FrameData& f2, std::size_t i2, const core::SE3& T1_cw, const core::SE3& T2_cw,
                            const Eigen::Vector3d& X) const;
  void add_triangulated_point(int current, std::size_t i1, int k2_id, std::size_t i2, const Eigen::Vector3d& X);
  // ORB-SLAM2 LocalMapping::MapPointCulling (stereo: 3 observations, a stereo one counting 2).
  void cull_points();
  // ORB-SLAM2 LocalMapping::SearchInNeighbors: duplicates between the newest keyframe and its
  // first and second covisible neighbours fused (fuse_into both ways).
  void search_in_neighbours(int current);
  // ORB-SLAM2 ORBmatcher::Fuse(pKF, vpMapPoints, th = 3): each point projected into keyframe kf
  // and matched to the best keypoint near it (predicted level or one finer, chi^2 of the
  // reprojection within the 95 % bound, descriptor within TH_LOW); a keypoint holding another
  // point keeps the one with more observations, a free one takes the point. Returns the fusions.
  int fuse_into(int kf, const std::vector<int>& ids, double th);
  // ORB-SLAM2 LocalMapping::KeyFrameCulling (T-RO 2017 Sec. V-E): a keyframe covisible with the
  // newest one whose close map points (stereo/RGB-D: depth below ThDepth) are, for >= 90 % of
  // them, seen by at least 3 other keyframes at the same, a finer or the next coarser level
  // (ORB-SLAM2's scaleLeveli <= scaleLevel + 1) is culled (cull_keyframe). Never keyframe 0, the
  // first keyframe of a segment, one of another segment, or a pending loop candidate.
  void cull_keyframes();
  // ORB-SLAM2 KeyFrame::SetBadFlag: the keyframe's observations erased (points left with too few
  // observations culled, as erase_observation does), out of the database, its parent the
  // previous good keyframe of its segment, so that the consecutive chain of the loop closer's
  // pose graph stays connected through the keyframes that remain.
  void cull_keyframe(int kf);
  // Keyframes sharing at least `min_shared` good points with keyframe `kf`, most first.
  std::vector<std::pair<int, int>> covisible(int kf, int min_shared) const;
  // ORB-SLAM2 Optimizer::LocalBundleAdjustment: the newest keyframe and its covisible ones.
  void local_bundle_adjustment();
  // Bundle adjustment on the engine of the keyframes `local` (free, but keyframe 0) and every
  // point they see, the other keyframes that see those points fixed; `first` LM iterations with
  // Huber, chi^2 outliers removed, `second` more without the kernel, outlier observations erased.
  void bundle_adjustment(const std::set<int>& local, int first, int second_iterations);
  // What the stages of bundle_adjustment share: its scope, the engine's values and variable
  // indices of poses and points, the observations (edges) and their outlier flags.
  struct BundleAdjustmentState {
    struct Edge {
      int point, kf, idx;
    };
    std::set<int> local_points;  // every good point the local keyframes see
    std::set<int> fixed;         // the other keyframes that see them
    std::map<int, std::array<double, 7>> pose_values;
    std::map<int, int> pose_var;
    std::unordered_map<int, Eigen::Vector3d> point_values;
    std::unordered_map<int, int> point_var;
    std::vector<Edge> edges;
    std::vector<char> is_outlier;
    // Visual-inertial (collect_inertial_scope): the chain of consecutive keyframes the IMU joins,
    // in time order, the preintegrated readings between each and the next (links[k] from
    // chain[k] to chain[k + 1]), the keyframes' velocities and biases as the engine's values.
    std::vector<int> chain;
    std::vector<inertial::PreintegratedImu> links;
    std::map<int, Eigen::Vector3d> velocity_values;
    std::map<int, Eigen::Matrix<double, 6, 1>> bias_values;
    std::map<int, int> velocity_var, bias_var;
    Eigen::Matrix<double, 6, 1> oldest_bias_prior = Eigen::Matrix<double, 6, 1>::Zero();  // the oldest keyframe's biases as collected
    Eigen::Vector3d gravity_world = Eigen::Vector3d::Zero();
  };
  // Its stages, in order (local_mapping.cpp).
  void collect_bundle_adjustment_scope(const std::set<int>& local, BundleAdjustmentState& ba) const;
  void add_bundle_adjustment_variables(const std::set<int>& local, BundleAdjustmentState& ba, backend::LeastSquaresProblem& problem) const;
  void add_bundle_adjustment_factors(BundleAdjustmentState& ba, backend::LeastSquaresProblem& p, bool robust) const;
  // Visual-inertial local BA (ORB-SLAM3 Optimizer::LocalInertialBA, Campos et al. T-RO 2021 Sec.
  // VI-A): the newest keyframes of the local window that the IMU joins get velocity and bias
  // variables, an IMU factor and a bias random walk factor to the next (local_mapping.cpp).
  // Collected on the caller's thread (the IMU readings are not the job's to read).
  void collect_inertial_scope(const std::set<int>& local, BundleAdjustmentState& ba) const;
  void add_inertial_factors(BundleAdjustmentState& ba, backend::LeastSquaresProblem& p) const;
  void classify_bundle_adjustment_edges(BundleAdjustmentState& ba) const;
  void bundle_adjustment_second_pass(BundleAdjustmentState& ba, backend::LeastSquaresOptions& lso, int second_iterations) const;
  void apply_bundle_adjustment(const std::set<int>& local, BundleAdjustmentState& ba);
  // Everything of bundle_adjustment but applying it: reads the map, writes only `ba`. False when
  // there is nothing to adjust.
  bool solve_bundle_adjustment(const std::set<int>& local, int first, int second_iterations, BundleAdjustmentState& ba) const;

  // Local mapping's own thread (VisualSlamOptions::local_mapping_thread; ORB-SLAM3's LocalMapping
  // runs beside Tracking): a keyframe's local bundle adjustment is solved in the background on
  // copies of the poses and points while the caller reads and extracts the next frame; it is
  // joined, applied and followed by keyframe culling and loop closing before the next frame is
  // tracked, or when the map is read, so the results never depend on timing (local_mapping.cpp).
  struct LocalMappingJob {
    bool running = false;
    tbb::task_group group;
    std::set<int> local;
    BundleAdjustmentState ba;
    bool solved = false;
    double seconds = 0.0;
    std::size_t frame_index = 0;  // the keyframe's frame (`last` while the job runs)
    int keyframe = -1;
  };
  LocalMappingJob mapping_job;
  std::set<int> local_ba_keyframes() const;
  void start_local_mapping();
  void join_local_mapping(FrameResult* result);
  void finish_keyframe(FrameResult& result);

  // --- Place recognition: loop closure (ORB-SLAM2 LoopClosing) (loop_closing.cpp) ---
  // Replaces point `old_id` by `new_id` everywhere (ORB-SLAM2 MapPoint::Replace): its
  // observations move to the new point where the keyframe does not see that one already.
  void replace_point(int old_id, int new_id);
  // Geometric verification of a loop candidate (stereo / RGB-D: SE(3), ORB-SLAM2 ComputeSim3
  // with the scale fixed): the keyframe's keypoints matched to the candidate's points, a PnP
  // RANSAC pose, the motion-only BA, then the points of the candidate and its covisible
  // keyframes projected at that pose and the BA again. `probe` gets the keyframe at the pose
  // the candidate's part of the map gives it, with its matches to that part.
  // drift_guard false: without the drift bound (a rival of the uniqueness test).
  bool verify_loop(int current, int candidate, LoopRecord& record, FrameData& probe, bool drift_guard = true);
  // The candidate's neighbourhood projected into the probe, then the motion-only BA; false (with
  // record.reason) below loop_min_matches inliers.
  bool match_candidate_neighbourhood(int candidate, FrameData& probe, LoopRecord& record);
  // Monocular: Sim(3) (ORB-SLAM2 ComputeSim3 / Sim3Solver); record.scale gets the scale.
  bool verify_loop_sim3(int current, int candidate, LoopRecord& record, FrameData& probe, bool drift_guard);
  // Its last stage: the correction recorded and, with drift_guard, its rotation bounded by the drift.
  bool sim3_within_drift(int current, int candidate, LoopRecord& record, const FrameData& probe, bool drift_guard) const;
  // The uniqueness test of a verified loop or merge (current -> candidate, `record`, `probe`):
  // each of `rivals` (but those of the querying keyframe's own segment when the candidate lies
  // in another) is verified as a loop (no drift bound); one that verifies at another place
  // (distinct_places) makes the loop ambiguous. Returns "" when unique, else the reason.
  std::string loop_rival(int current, int candidate, const LoopRecord& record, const FrameData& probe, const std::vector<int>& rivals);
  // Loop correction (ORB-SLAM2 CorrectLoop, stereo: SE(3)): the pose graph of every keyframe
  // (consecutive keyframes, covisibility edges of >= 100 shared points, the loop edge; unit
  // information as ORB-SLAM2's essential graph; keyframe 0 fixed) optimised on the back end;
  // points follow their reference keyframe; the keyframe's loop matches fuse its points into the
  // old ones; then a global bundle adjustment.
  void correct_loop(int current, int candidate, const FrameData& probe, double scale = 1.0);
  std::vector<std::tuple<int, int, double>> essential_graph_edges(const std::vector<int>& good) const;
  void correct_poses_se3(int current, int candidate, const FrameData& probe);
  void follow_keyframe_correction(const std::vector<core::SE3>& old_poses);
  // With an IMU (loop_closing.cpp): loops of a visual-inertial map corrected in 4 DoF.
  bool corrects_in_four_dof(int current, int candidate) const;
  void correct_poses_4dof(int current, int candidate, const FrameData& probe);
  void move_inertial_states(const std::vector<core::SE3>& old_poses, bool similarity);
  void correct_poses_sim3(int current, int candidate, const FrameData& probe, double scale);
  // Its stages, in order, and what they share (loop_closing.cpp, where Sim3Correction is defined).
  struct Sim3Correction;
  void spread_loop_similarity(int current, int candidate, Sim3Correction& c) const;
  void move_points_before_graph(Sim3Correction& c);
  void optimise_sim3_essential_graph(int current, int candidate, Sim3Correction& c);
  void apply_sim3_correction(const Sim3Correction& c);
  void fuse_loop_and_adjust(int current, const FrameData& probe);
  // ORB-SLAM2 LoopClosing::DetectLoop: candidates from the database scoring at least as well as
  // the keyframe's worst covisible neighbour and sharing at least 80 % of the best candidate's
  // words, kept only when their covisibility group was also a candidate group for the previous
  // loop_consistency - 1 keyframes; then verified, best score first.
  void detect_and_close_loop(FrameResult& result);
  // Its candidates that pass the consistency test, (score, candidate, consistency), best first.
  std::vector<std::tuple<double, int, int>> consistent_loop_candidates(int current, const std::vector<vision::BowDatabase::Result>& results,
                                                                       double min_score, bool too_early);
  enum class LoopOutcome { kRejected, kAmbiguous, kAccepted };
  // One loop or merge candidate verified, tested for uniqueness and, when it stands, closed
  // (loop_closing.cpp try_loop).
  LoopOutcome try_loop(int current, LoopRecord& record, const std::vector<int>& rivals, const char* accepted_reason, FrameResult& result);
  void merge_with_recent(FrameResult& result);
  // A return to a place that tracking the local map already joined (the old keyframe shares
  // points with the new one, so DetectLoop leaves it out): found in the covisibility graph,
  // verified as a loop would be, recorded with decision "revisit"; nothing is corrected.
  void verify_revisit(int current, const std::vector<std::pair<int, int>>& neighbours);

  // --- Monocular initialisation (ORB-SLAM2 Initializer, Mur-Artal et al. T-RO 2015 Sec. IV) (initialisation.cpp) ---
  // Level-0 keypoints of the reference matched to the frame within 100 px (ORB-SLAM2
  // SearchForInitialization: TH_LOW, ratio 0.9, one-to-one).
  std::vector<std::pair<int, int>> match_for_initialisation(const FrameData& a, const FrameData& b) const;
  // Two-view reconstruction: the homography and the essential matrix (RANSAC, OpenCV), scored
  // as ORB-SLAM2 scores them (sum of chi^2 margins below 5.991 of the symmetric transfer errors
  // for H, of the distances to the epipolar lines below 3.841 for F); H when
  // S_H / (S_H + S_F) > 0.40, else E; the pose from cv::recoverPose / the homography's
  // decompositions (the one with most points in front); points triangulated, kept in front of
  // both cameras within 2 px; success with >= 50 points seen at >= 1 degree of parallax.
  // `note` says which model and why it failed.
  bool reconstruct_two_views(const FrameData& a, const FrameData& b, const std::vector<std::pair<int, int>>& matches, core::SE3& T_b_a,
                             std::vector<std::pair<int, Eigen::Vector3d>>& points_a, std::string& note) const;
  // One frame of the two-view initialisation of a map (segment): false (with `note`) until
  // init_reference and `f` reconstruct; then two keyframes and their points, the reference at
  // T_world_reference with the points' median depth in it `median_depth` (initialisation.cpp).
  bool two_view_map(FrameData& f, const core::SE3& T_world_reference, double median_depth, bool add_second_to_database, std::string& note,
                    int& made, double& inlier_ratio, double& mapping_s);
  FrameResult initialise_monocular(FrameData f, FrameResult result, FrameTimes times, Clock::time_point start, Clock::time_point tracking_start);
  // Monocular, lost for new_map_after_lost_frames: the frame fed to the two-view initialisation of
  // a new map segment; on success `result` reports it (tracking.cpp).
  void start_monocular_segment(FrameData& f, FrameResult& result, FrameTimes& times);
  // Monocular: the next lost frame goes to start_monocular_segment.
  bool initialising_new_segment() const {
    return kind == io::SequenceKind::kMonocular && lost && options.new_map_after_lost_frames > 0 &&
           lost_frames + 1 >= options.new_map_after_lost_frames;
  }
  // The median depth of keyframe kf's points in its camera; none without points (tracking.cpp).
  std::optional<double> median_point_depth(int kf) const;

  // --- One frame (tracking.cpp) ---
  FrameResult track(core::Timestamp time, vision::Features& left, const vision::StereoMatches& stereo, vision::SmallBlurryImage sbi, FrameTimes times,
                    Clock::time_point start);
  // What the stages of track share about the frame being tracked: the frame, its report, and
  // what one stage tells the next.
  struct TrackingFrame {
    FrameData f;
    FrameResult result;
    FrameTimes times;
    Clock::time_point start, tracking_start;
    bool was_lost = false;           // lost before this frame
    double motion_radius_px = 0.0;   // the motion model's search radius
    int matches = 0;                 // first-stage map-point matches
    int inliers = 0;                 // inliers of the frame's current pose
    int given = 0;                   // the local map's matches behind the inliers
    bool prediction_failed = false;  // the motion model explained too little: the fallbacks' trigger
    int accepted_keyframe = -1;      // the keyframe whose matches gave the first stage's pose (fallback / relocalisation)
    std::vector<int> relocalisation_candidates;
    std::vector<std::uint32_t> relocalisation_nodes;
    bool jumped = false;  // the fallback's pose jumped: verified as a relocalisation
    double jump_m = 0.0;
    bool relocalising = false;      // after being lost, or a jump
    bool unverified_start = false;  // neither the prediction nor the reference keyframe explained the frame
    bool have_imu_prediction = false;  // the IMU predicted the body's state at this frame
    inertial::NavState imu_prediction;
    std::optional<InertialPoseTerms> imu_terms;  // the visual-inertial pose optimisation's, when it ran
  };
  // The reference-keyframe fallback's candidates and the frame's words.
  struct FallbackCandidates {
    std::vector<int> candidates;       // tried in order, the reference keyframe first
    std::vector<int> rival_keyframes;  // the uniqueness test's further rivals
    std::vector<std::uint32_t> frame_nodes;
    vision::BowVector frame_bow;
    bool use_nodes = false;  // node-restricted matching (bow_restricted_matching with a vocabulary)
  };
  // The stages of track, in order (tracking.cpp, where each is described).
  bool start_first_map(TrackingFrame& w);
  int search_around_last(FrameData& frame, double motion_radius_px);
  void track_motion_model(TrackingFrame& w);
  void align_small_images(TrackingFrame& w);
  void track_reference_fallback(TrackingFrame& w);
  FallbackCandidates fallback_candidates(const FrameData& f) const;
  void try_fallback_candidates(TrackingFrame& w, const FallbackCandidates& c);
  void check_fallback_jump(TrackingFrame& w, FallbackCandidates& c);
  void assess_first_stage(TrackingFrame& w);
  void refine_with_local_map(TrackingFrame& w);
  void verify_relocalisation(TrackingFrame& w);
  void handle_lost_frame(TrackingFrame& w);
  void start_stereo_segment(TrackingFrame& w);
  // Visual-inertial stages (inertial_tracking.cpp).
  void predict_with_imu(TrackingFrame& w);
  std::optional<InertialPoseTerms> inertial_pose_terms(const TrackingFrame& w) const;
  bool carry_with_imu(TrackingFrame& w);
  void map_carried_view(TrackingFrame& w);
  void start_keyframe_imu_state(const TrackingFrame& w);
  void advance_inertial_state(TrackingFrame& w);
  void check_against_imu(TrackingFrame& w);
  bool agrees_with_imu(const TrackingFrame& w, double* distance_m = nullptr, double* angle_deg = nullptr) const;
  void estimate_inertial(TrackingFrame& w);
  void rescale_segment(int seg, double scale);
  core::SE3 camera_pose(const inertial::NavState& body) const;
  void accept_tracked_frame(TrackingFrame& w);
  void map_keyframe(TrackingFrame& w);
  FrameResult record_frame(TrackingFrame& w);
};

}  // namespace cairn::vslam
