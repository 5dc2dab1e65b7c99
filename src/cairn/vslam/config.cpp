#include "cairn/vslam/config.hpp"

#include "cairn/core/problems.hpp"

namespace cairn::vslam {

io::Parameters parameters(VisualSlamOptions& o) {
  return {
      {"orb", "features", &o.orb.features, "wanted over all levels (cairn vslam starts from 2000 for KITTI, 1000 for the other layouts, as ORB-SLAM2)"},
      {"orb", "scale_factor", &o.orb.scale_factor, "between pyramid levels, in (1, 2)"},
      {"orb", "levels", &o.orb.levels, "pyramid levels, 1 to 16"},
      {"orb", "initial_fast_threshold", &o.orb.initial_fast_threshold, "FAST threshold tried first in each cell"},
      {"orb", "min_fast_threshold", &o.orb.min_fast_threshold, "FAST threshold where the initial one finds no corner in a cell"},
      {"orb", "cell_px", &o.orb.cell_px, "side of the detection cells (ORB-SLAM's W), >= 10"},
      {"stereo", "max_descriptor_distance", &o.stereo.max_descriptor_distance, "left-right matches at most this Hamming distance (ORB-SLAM2: (TH_HIGH + TH_LOW) / 2)"},
      {"stereo", "window_half_size", &o.stereo.window_half_size, "SAD window half-width on the keypoint's level (5: 11 x 11)"},
      {"stereo", "search_half_range", &o.stereo.search_half_range, "SAD positions either side of the descriptor match"},
      {"stereo", "row_band_px", &o.stereo.row_band_px, "right keypoints within +- this x the level's scale of the left one's row"},
      {"stereo", "min_depth_baselines", &o.stereo.min_depth_baselines, "nearest depth accepted, in baselines (1: disparity <= fx)"},
      {"stereo", "sad_outlier_factor", &o.stereo.sad_outlier_factor, "matches with a SAD above this x the median are rejected (ORB-SLAM2: 1.5 x 1.4)"},
      {"tracking", "motion_search_radius_px", &o.motion_search_radius_px, "stereo: constant-velocity search radius (TrackWithMotionModel's th), x level scale"},
      {"tracking", "motion_search_radius_rgbd_px", &o.motion_search_radius_rgbd_px, "RGB-D: the same (ORB-SLAM2: 15; 7 tracked more of TUM fr1/desk, docs/vslam.md)"},
      {"tracking", "motion_search_radius_mono_px", &o.motion_search_radius_mono_px, "monocular: the same (ORB-SLAM2's 15)"},
      {"tracking", "local_search_radius_px", &o.local_search_radius_px, "local-map search radius (SearchLocalPoints' th; x 2.5 or 4 by viewing angle, x level scale)"},
      {"tracking", "max_descriptor_distance", &o.max_descriptor_distance, "map-point matches at most this Hamming distance (ORB-SLAM's TH_HIGH)"},
      {"tracking", "local_match_ratio", &o.local_match_ratio, "best / second best descriptor distance at the same level"},
      {"tracking", "reference_match_ratio", &o.reference_match_ratio, "the same, brute-force fallback against the reference keyframe"},
      {"tracking", "min_motion_matches", &o.min_motion_matches, "fewer prediction matches: widen the radius, then the fallback"},
      {"tracking", "local_map_keyframes", &o.local_map_keyframes, "keyframes whose points make the local map"},
      {"tracking", "chi2_mono", &o.chi2_mono, "outlier threshold of a monocular observation (chi^2, 2 DOF, 95 %)"},
      {"tracking", "chi2_stereo", &o.chi2_stereo, "outlier threshold of a stereo observation (chi^2, 3 DOF, 95 %)"},
      {"tracking", "image_alignment", &o.image_alignment, "predict the rotation from small blurry images when the prediction explains too little (PTAM)"},
      {"tracking", "image_alignment_min_correlation", &o.image_alignment_min_correlation, "ECC correlation below which the images' rotation is not used"},
      {"health", "degraded_below_inliers", &o.degraded_below_inliers, "fewer inliers: degraded (ORB-SLAM2 needs 30 to stay tracking)"},
      {"health", "lost_below_inliers", &o.lost_below_inliers, "fewer inliers: lost"},
      {"keyframes", "close_depth_baselines", &o.close_depth_baselines, "points nearer than this many baselines are close (ORB-SLAM2's ThDepth; RGB-D: the virtual baseline; cairn vslam starts from 40 for RGB-D)"},
      {"keyframes", "tracked_ratio", &o.keyframe_tracked_ratio, "new keyframe when inliers < this x the reference keyframe's points"},
      {"keyframes", "close_tracked", &o.keyframe_close_tracked, "... or fewer tracked close points than this"},
      {"keyframes", "close_untracked", &o.keyframe_close_untracked, "... while more untracked close points than this"},
      {"keyframes", "max_frames", &o.keyframe_max_frames, "at least one keyframe per this many frames"},
      {"keyframes", "monocular_turn_fov", &o.monocular_keyframe_turn_fov, "monocular: also one after turning this fraction of the horizontal field of view (0 = off)"},
      {"keyframes", "min_new_points", &o.min_new_points, "a new keyframe creates at least this many points (nearest first)"},
      {"local_mapping", "local_ba", &o.local_ba, "local bundle adjustment (false: visual odometry only, as --no-local-ba)"},
      {"local_mapping", "own_thread", &o.local_mapping_thread,
       "a keyframe's local bundle adjustment, culling and loop closing run beside the next frame's image reading and ORB, joined before it is tracked (false: within the keyframe's frame); stereo and RGB-D only"},
      {"local_mapping", "max_local_ba_keyframes", &o.max_local_ba_keyframes, "covisible keyframes optimised (most shared points first)"},
      {"local_mapping", "min_covisible_points", &o.min_covisible_points, "keyframes sharing fewer points are not covisible"},
      {"local_mapping", "triangulation_keyframes", &o.triangulation_keyframes, "new points triangulated with this many most covisible keyframes (0 = only stereo/depth creates points)"},
      {"local_mapping", "triangulation_match_ratio", &o.triangulation_match_ratio, "best / second best descriptor distance along the epipolar band"},
      {"local_mapping", "keyframe_culling", &o.keyframe_culling, "remove keyframes whose close points others see (ORB-SLAM2 KeyFrameCulling; stereo and RGB-D)"},
      {"local_mapping", "keyframe_culling_redundancy", &o.keyframe_culling_redundancy, "share of a keyframe's close points that must be redundant, in (0, 1]"},
      {"local_mapping", "fuse_points", &o.fuse_points, "fuse duplicate points after each new keyframe (ORB-SLAM2 SearchInNeighbors)"},
      {"loop_closure", "enabled", &o.loop_closure, "close loops (needs --vocabulary)"},
      {"loop_closure", "bow_restricted_matching", &o.bow_restricted_matching, "match relocalisation, fallback and loop candidates within vocabulary nodes (ORB-SLAM2 SearchByBoW)"},
      {"loop_closure", "min_keyframes_apart", &o.loop_min_keyframes_apart, "no loop with the last this-many keyframes, none within this many of the last loop"},
      {"loop_closure", "consistency", &o.loop_consistency, "consecutive keyframes whose candidates agree"},
      {"loop_closure", "min_pnp_inliers", &o.loop_min_pnp_inliers, "descriptor matches to, and PnP RANSAC inliers of, the candidate's points"},
      {"loop_closure", "min_matches", &o.loop_min_matches, "map-point matches after projecting the candidate's neighbourhood"},
      {"loop_closure", "relocalisation_min_inliers", &o.relocalisation_min_inliers, "inliers a relocalisation needs (ORB-SLAM2: 50); also the uniqueness test"},
      {"loop_closure", "drift_floor_m", &o.loop_drift_floor_m, "a loop within a segment may move the keyframe at most this ..."},
      {"loop_closure", "drift_fraction", &o.loop_drift_fraction, "... plus this x the distance travelled since the candidate"},
      {"loop_closure", "drift_floor_deg", &o.loop_drift_floor_deg, "... and turn it at most this ..."},
      {"loop_closure", "drift_deg_per_m", &o.loop_drift_deg_per_m, "... plus this per metre travelled"},
      {"loop_closure", "global_ba_after_loop", &o.global_ba_after_loop, "a full bundle adjustment after each loop correction"},
      {"inertial", "initialisation_window_s", &o.inertial.initialisation_window_s, "with --imu: keyframes over at least this long before the first inertial initialisation (ORB-SLAM3: 2 s), >= 1"},
      {"inertial", "refinement_window_s", &o.inertial.refinement_window_s, "every keyframe re-estimates gravity, velocities and biases over its last this-many seconds, >= initialisation_window_s"},
      {"inertial", "max_carried_s", &o.inertial.max_carried_s, "a frame the images do not track takes the IMU's prediction for at most this long (degraded), then it is lost"},
      {"inertial", "disagreement_m", &o.inertial.disagreement_m, "a tracked frame farther than this from the IMU's prediction is degraded ..."},
      {"inertial", "disagreement_deg", &o.inertial.disagreement_deg, "... or turned more than this from it"},
      {"inertial", "max_scale_drift", &o.inertial.max_scale_drift, "monocular: the IMU's scale estimate more than this fraction off 1 is scale drift (degraded), in (0, 1)"},
      {"inertial", "min_scale_excitation_mps2", &o.inertial.min_scale_excitation_mps2, "monocular: scale judged only over windows accelerating by at least this (RMS)"},
      {"inertial", "gravity_mps2", &o.inertial.gravity_mps2, "the magnitude of gravity"},
      {"inertial", "local_ba", &o.inertial.local_ba, "IMU factors between the newest keyframes of the local bundle adjustment (ORB-SLAM3 LocalInertialBA)"},
      {"inertial", "pose_optimisation", &o.inertial.pose_optimisation, "the IMU's factor from the last frame's state in a tracked frame's pose optimisation (ORB-SLAM3 PoseInertialOptimizationLastFrame)"},
      {"inertial", "pose_sigma_m", &o.inertial.pose_sigma_m, "... the last frame's position sigma when its own optimisation gave none (after a keyframe's estimate, a carried frame)"},
      {"inertial", "pose_sigma_deg", &o.inertial.pose_sigma_deg, "... its rotation sigma"},
      {"inertial", "velocity_sigma_mps", &o.inertial.velocity_sigma_mps, "... its velocity sigma"},
      {"inertial", "four_dof_loops", &o.inertial.four_dof_loops, "a loop within the IMU's map is corrected in yaw and position only, keeping gravity's direction (ORB-SLAM3's 4-DoF essential graph)"},
      {"maps", "new_map_after_lost_frames", &o.new_map_after_lost_frames, "lost frames in a row before a new map segment starts (0 = never)"},
      {"maps", "merge_recent_keyframes_of_new_map", &o.merge_recent_keyframes_of_new_map, "a new segment's first keyframes that try to merge with the keyframes tracked last (0 = place recognition only)"},
  };
}

VisualSlamOptions dataset_options(const std::string& layout, io::SequenceKind kind) {
  VisualSlamOptions o;
  // ORB-SLAM2's settings: 2000 for KITTI (stereo and monocular), 1000 for TUM.
  o.orb.features = layout == "kitti" ? 2000 : 1000;
  if (kind == io::SequenceKind::kRgbd) o.close_depth_baselines = 40.0;  // ORB-SLAM2 TUM*.yaml ThDepth
  return o;
}


const io::Configuration<VisualSlamOptions>& configuration() {
  static const io::Configuration<VisualSlamOptions> c(&parameters, "vslam", "# cairn vslam configuration: every key, its value and what it means.");
  return c;
}

}  // namespace cairn::vslam
