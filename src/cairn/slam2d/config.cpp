#include "cairn/slam2d/config.hpp"

#include <stdexcept>

namespace cairn::slam2d {

io::Parameters parameters(Slam2dOptions& o) {
  return {
      {"scan", "min_range_m", &o.filter.min_range_m, "readings below are dropped"},
      {"scan", "max_range_m", &o.filter.max_range_m, "readings at or beyond are no-returns (the log's PARAM max range wins when smaller)"},
      {"scan", "missing_ray_length_m", &o.filter.missing_ray_length_m, "free-space ray drawn for a no-return (0 = none)"},
      {"scan", "voxel_size_m", &o.filter.voxel_size_m, "voxel filter applied to every scan"},
      {"scan", "adaptive_min_points", &o.filter.adaptive_min_points, "adaptive voxel filter keeps at least this many points for matching"},
      {"scan", "adaptive_max_voxel_size_m", &o.filter.adaptive_max_voxel_size_m, "largest voxel of the adaptive filter"},
      {"front_end", "keyframe_distance_m", &o.keyframe_distance_m, "motion since the last keyframe that makes a new one"},
      {"front_end", "keyframe_angle_rad", &o.keyframe_angle_rad, "rotation since the last keyframe that makes a new one"},
      {"front_end", "local_map_keyframes", &o.local_map_keyframes, "keyframes whose points form the local map"},
      {"front_end", "submap_keyframes", &o.submap_keyframes, "keyframes per submap (a new submap starts every half of this)"},
      {"front_end", "submap_install_delay_keyframes", &o.submap_install_delay_keyframes,
       "a full submap is built in the background and searchable this many keyframes later (more: faster, but fewer loops and wider drift windows; 10 let false loops through in simulation)"},
      {"front_end", "map_cell_size_m", &o.map_points.cell_size_m, "hash cell of the point maps (>= icp.max_correspondence_m)"},
      {"front_end", "normal_radius_m", &o.map_points.normal_radius_m, "neighbourhood radius for point normals"},
      {"icp", "max_iterations", &o.icp.max_iterations, "Gauss-Newton iterations at most"},
      {"icp", "max_correspondence_m", &o.icp.max_correspondence_m, "first search radius for correspondences"},
      {"icp", "final_correspondence_m", &o.icp.final_correspondence_m, "final search radius (halved every 3 iterations down to this)"},
      {"icp", "point_sigma_m", &o.icp.point_sigma_m, "range noise that scales the residuals"},
      {"icp", "huber_threshold_m", &o.icp.huber_threshold_m, "Huber kernel width"},
      {"icp", "point_to_point_weight", &o.icp.point_to_point_weight, "weight of map points without a normal (0 = ignored)"},
      {"icp", "inlier_distance_m", &o.icp.inlier_distance_m, "a point within this of the map is an inlier"},
      {"icp", "prior_translation_sigma_m", &o.icp.prior_translation_sigma_m, "odometry prior, translation (<= 0 disables the prior)"},
      {"icp", "degenerate_threshold", &o.icp.degenerate_threshold, "translation directions constrained less than this follow the odometry prior"},
      {"icp", "prior_rotation_sigma_rad", &o.icp.prior_rotation_sigma_rad, "odometry prior, rotation"},
      {"grid", "resolution_m", &o.grid.resolution_m, "cell side of submap grids and the output map"},
      {"grid", "hit_probability", &o.grid.hit_probability, "p(occupied | hit)"},
      {"grid", "miss_probability", &o.grid.miss_probability, "p(occupied | ray passed through)"},
      {"loop_closure", "search_every_n_keyframes", &o.loop_search_every_n_keyframes, "search loops from every n-th keyframe"},
      {"loop_closure", "max_distance_m", &o.loop_max_distance_m, "submaps farther than this from the keyframe are not searched"},
      {"loop_closure", "max_submaps_per_search", &o.loop_max_submaps_per_search, "the nearest finished submaps searched per keyframe"},
      {"loop_closure", "max_linear_window_m", &o.loop_search.linear_search_window_m, "largest half-width of the translation search"},
      {"loop_closure", "max_angular_window_rad", &o.loop_search.angular_search_window_rad, "largest half-width of the angle search"},
      {"loop_closure", "window_base_m", &o.loop_window_base_m, "translation window at zero path length"},
      {"loop_closure", "window_drift_per_m", &o.loop_window_drift_per_m, "window growth per metre travelled since the submap"},
      {"loop_closure", "angle_window_base_rad", &o.loop_angle_window_base_rad, "angle window at zero path length"},
      {"loop_closure", "angle_window_drift_per_m", &o.loop_angle_window_drift_per_m, "angle window growth per metre"},
      {"loop_closure", "branch_and_bound_depth", &o.loop_search.depth, "precomputation grids (2^(depth-1) cells at the top)"},
      {"loop_closure", "unknown_probability", &o.loop_search.unknown_probability, "score of unexplored cells"},
      {"loop_closure", "angular_step_range_quantile", &o.loop_search.angular_step_range_quantile, "angle step from this quantile of the scan's ranges (1 = farthest point, Hess eq. 7)"},
      {"loop_closure", "min_score", &o.loop_min_score, "branch-and-bound score a candidate needs"},
      {"loop_closure", "relocalisation_min_score", &o.relocalisation_min_score, "branch-and-bound score a relocalisation needs (while matching fails)"},
      {"loop_closure", "min_inlier_fraction", &o.loop_min_inlier_fraction, "verification: ICP inliers against the submap"},
      {"loop_closure", "max_rms_m", &o.loop_max_rms_m, "verification: ICP residual RMS"},
      {"loop_closure", "min_degeneracy", &o.loop_min_degeneracy, "verification: smallest normal-spread eigenvalue of the match"},
      {"loop_closure", "min_inliers", &o.loop_min_inliers, "verification: scan points within inlier distance of the submap"},
      {"loop_closure", "ambiguity_window_m", &o.loop_ambiguity_window_m, "verification: the ambiguity search spans at least this half-width"},
      {"loop_closure", "ambiguity_max_window_m", &o.loop_ambiguity_max_window_m, "verification: ... and spans the estimate's possible drift up to this half-width"},
      {"loop_closure", "ambiguity_distance_m", &o.loop_ambiguity_distance_m, "verification: another match farther than this ..."},
      {"loop_closure", "ambiguity_angle_rad", &o.loop_ambiguity_angle_rad, "... or rotated more than this ..."},
      {"loop_closure", "ambiguity_margin", &o.loop_ambiguity_margin, "... must score at least this much lower"},
      {"back_end", "odometry_translation_sigma_m", &o.odometry_translation_sigma_m, "noise of keyframe-to-keyframe edges"},
      {"back_end", "odometry_rotation_sigma_rad", &o.odometry_rotation_sigma_rad, "noise of keyframe-to-keyframe edges"},
      {"back_end", "loop_translation_sigma_m", &o.loop_translation_sigma_m, "noise of loop-closure edges"},
      {"back_end", "loop_rotation_sigma_rad", &o.loop_rotation_sigma_rad, "noise of loop-closure edges"},
      {"back_end", "optimize_every_n_keyframes", &o.optimize_every_n_keyframes, "optimise when loops arrived and this many keyframes passed"},
      {"back_end", "final_gnc", &o.final_gnc, "GNC over loop closures at the end (rejects the ones that disagree)"},
      {"back_end", "edge_covariance_from_matcher", &o.edge_covariance_from_matcher, "keyframe edges add the match covariance (weak along degenerate directions)"},
      {"output", "map_resolution_m", &o.output_map_resolution_m, "cell side of the written map (map.pgm, map.png)"},
      {"health", "degraded_min_inlier_fraction", &o.degraded_min_inlier_fraction, "below: degraded"},
      {"health", "degraded_min_degeneracy", &o.degraded_min_degeneracy, "smallest normal-spread eigenvalue below: degraded"},
      {"health", "min_matching_points", &o.min_matching_points, "scans with fewer returns are not matched (degraded, odometry only)"},
      {"health", "lost_inlier_fraction", &o.lost_inlier_fraction, "a match below this failed (pose from odometry)"},
      {"health", "new_space_max_rays_through", &o.new_space_max_rays_through,
       "a failed match whose rays cross the local map at most this often sees new structure: degraded, not towards lost (< 0: off)"},
      {"health", "lost_after_scans", &o.lost_after_scans, "consecutive failed matches before lost"},
      {"segments", "link_translation_sigma_m", &o.segment_link_translation_sigma_m, "weak odometry edge joining a new map segment (and spanning failed matches)"},
      {"segments", "link_rotation_sigma_rad", &o.segment_link_rotation_sigma_rad, "weak odometry edge, rotation"},
      {"segments", "min_keyframes", &o.min_segment_keyframes, "a lost segment with fewer mapped keyframes restarts in place"},
      {"segments", "confirm_scans", &o.segment_confirm_scans, "scans in a row that must match a new segment's seed (probation)"},
      {"segments", "trusted_link_min_inlier_fraction", &o.segment_trusted_link_min_inlier_fraction, "odometry places a new segment when the failed matches explained this share on average"},
      {"segments", "merge_searches_per_keyframe", &o.merge_searches_per_keyframe, "windowed merge searches per keyframe (hypothesis tests, then around the estimate)"},
      {"segments", "merge_max_distance_m", &o.merge_max_distance_m, "windowed merge searches: submap centre within this of the guess"},
      {"segments", "merge_confirmations", &o.merge_confirmations, "agreeing verified matches (distinct keyframes) a merge needs"},
      {"segments", "merge_min_spread_m", &o.merge_min_spread_m, "path the agreeing matches support when the merge disagrees with odometry"},
      {"segments", "merge_min_spread_corroborated_m", &o.merge_min_spread_corroborated_m, "path they support when odometry agrees"},
      {"segments", "merge_odometry_radius_m", &o.merge_odometry_radius_m, "odometry agrees: the merge moves the keyframe less than this ..."},
      {"segments", "merge_odometry_angle_rad", &o.merge_odometry_angle_rad, "... and turns it less than this"},
      {"segments", "merge_agreement_m", &o.merge_agreement_m, "two matches agree on a placement within this ..."},
      {"segments", "merge_agreement_rad", &o.merge_agreement_rad, "... and this"},
      {"segments", "merge_max_misses_in_a_row", &o.merge_max_misses_in_a_row, "a placement not found again this often in a row is dropped"},
      {"segments", "merge_support_gap_m", &o.merge_support_gap_m, "supported path: each gap between supporting keyframes counts up to this"},
      {"segments", "merge_miss_coverage_m", &o.merge_miss_coverage_m, "a failed test counts against a placement far from the odometry link only within this of the other map's keyframes"},
      {"search_budget", "per_keyframe", &o.search_budget_per_keyframe, "search tokens each keyframe adds"},
      {"search_budget", "burst", &o.search_budget_burst, "most tokens the budget holds"},
      {"search_budget", "global_search_every_n_keyframes", &o.global_search_every_n_keyframes, "one whole-submap search per this many keyframes while segments are unmerged"},
      {"search_budget", "global_search_max_range_m", &o.global_search_max_range_m, "whole-submap searches use the scan's points within this range"},
  };
}

std::vector<std::string> preset_names() { return {"default", "short-range"}; }

Slam2dOptions preset_options(const std::string& name) {
  Slam2dOptions o;
  // SICK LMS-class scanners: 180-361 beams over 180 degrees, range noise about 1 cm, up to 30 m
  // used. The Freiburg logs (ACES, Intel, MIT CSAIL) and cairn's simulator all run with this.
  if (name == "default") return o;
  if (name == "short-range") {
    // Low-cost 360-degree scanners (RPLIDAR A1/A2, YDLIDAR X4 class): 12 m at most, range noise
    // 2-3 cm. Residual scale, inlier band and the loop verification's RMS widen with the noise.
    o.filter.max_range_m = 12.0;
    o.filter.missing_ray_length_m = 3.0;
    o.icp.point_sigma_m = 0.03;
    o.icp.huber_threshold_m = 0.05;
    o.icp.inlier_distance_m = 0.08;
    o.loop_max_rms_m = 0.05;
    return o;
  }
  throw std::invalid_argument("unknown preset '" + name + "' (known: default, short-range)");
}

const io::Configuration<Slam2dOptions>& configuration() {
  static const io::Configuration<Slam2dOptions> c(&parameters, "slam2d",
                                                  "# cairn slam2d configuration: every key, its value and what it means.");
  return c;
}

void apply_setting(const std::string& assignment, Slam2dOptions& options) { configuration().set(assignment, options); }
void load_config(const std::string& path, Slam2dOptions& options) { configuration().load(path, options); }
std::string config_to_yaml(const Slam2dOptions& options) { return configuration().yaml(options); }
nlohmann::json config_json(const Slam2dOptions& options) { return configuration().json(options); }

io::Parameters localization_parameters(Localizer2dOptions& o) {
  const char* s = "localization";
  return {
      {s, "tracking_min_inlier_fraction", &o.tracking_min_inlier_fraction, "a tracked match below this failed (odometry carries the pose)"},
      {s, "ok_min_inlier_fraction", &o.ok_min_inlier_fraction, "a tracked match below this is degraded"},
      {s, "verification_min_inlier_fraction", &o.verification_min_inlier_fraction, "verification: ICP inliers against the submap"},
      {s, "verification_min_degeneracy", &o.verification_min_degeneracy, "verification: the match constrains every direction at least this much"},
      {s, "verification_max_free_fraction", &o.verification_max_free_fraction, "verification: at most this share of the points where the map saw empty space"},
      {s, "look_alike_min_observed_fraction", &o.look_alike_min_observed_fraction, "a partly mapped look-alike counts when this share of the scan lands in observed cells"},
      {s, "look_alike_places", &o.look_alike_places, "places of the coarse ranking tested as look-alikes"},
      {s, "global_searches_per_scan", &o.global_searches_per_scan, "whole-submap searches per scan while searching"},
      {s, "round_robin_searches_per_scan", &o.round_robin_searches_per_scan, "of those, submaps taken in turn rather than by the coarse ranking"},
      {s, "coarse_cell_factor", &o.coarse_cell_factor, "max-pooled cell of the coarse search, in map cells"},
      {s, "coarse_depth", &o.coarse_depth, "precomputation grids of the coarse search"},
      {s, "global_search_margin_m", &o.global_search_margin_m, "whole-submap searches reach this far beyond the submap"},
      {s, "check_every_n_scans", &o.check_every_n_scans, "while tracking, a verification search every n scans"},
      {s, "confirmations", &o.confirmations, "scans whose verified matches must agree before a pose is accepted"},
      {s, "agreement_m", &o.agreement_m, "two matches agree within this ..."},
      {s, "agreement_rad", &o.agreement_rad, "... and this"},
      {s, "confirmation_window_m", &o.confirmation_window_m, "confirmation searches: translation half-width around the hypothesis"},
      {s, "confirmation_window_rad", &o.confirmation_window_rad, "confirmation searches: angle half-width"},
      {s, "hypothesis_drop_deficit", &o.hypothesis_drop_deficit, "a hypothesis this far behind the best over the window is dropped"},
      {s, "hypothesis_drop_window_scans", &o.hypothesis_drop_window_scans, "scans the drop deficit is measured over"},
      {s, "max_hypotheses", &o.max_hypotheses, "hypotheses kept at once"},
  };
}

nlohmann::json localization_config_json(const Localizer2dOptions& options) {
  Localizer2dOptions copy = options;
  nlohmann::json j = io::parameters_json(localization_parameters(copy));
  j["matching"] = config_json(options.matching);
  return j;
}

}  // namespace cairn::slam2d
