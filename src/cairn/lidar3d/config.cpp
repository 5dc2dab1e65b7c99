#include "cairn/lidar3d/config.hpp"

#include <cmath>
#include <string_view>
#include <utility>
#include <vector>

#include "cairn/core/problems.hpp"
#include "cairn/io/number_format.hpp"

namespace cairn::lidar3d {
namespace {

std::string_view metric_name(IcpMetric metric) {
  return metric == IcpMetric::kPointToPlane ? "point-to-plane" : "point-to-point";
}

// A key whose value is one of `values`, written as name(value).
template <typename Enum, typename Name>
io::Choice enum_choice(Enum& value, std::vector<Enum> values, Name name) {
  io::Choice choice;
  for (Enum v : values) choice.words.emplace_back(name(v));
  choice.get = [&value, name] { return std::string(name(value)); };
  choice.set = [&value, values = std::move(values), name](const std::string& word) {
    for (Enum v : values) {
      if (name(v) == word) value = v;
    }
  };
  return choice;
}

// The query's virtual viewpoints: those of slam_scan_context_options ("-4 -2 2 4") or "none"
// (a list is not a key type of io::Parameters; these are the two settings measured).
io::Choice lateral_offsets_choice(std::vector<double>& offsets_m) {
  auto text = [](const std::vector<double>& offsets) {
    if (offsets.empty()) return std::string("none");
    std::string out;
    for (double offset : offsets) {
      if (!out.empty()) out += ' ';
      io::append_number(out, offset);
    }
    return out;
  };
  std::vector<double> views = slam_scan_context_options().lateral_offsets_m;
  io::Choice choice;
  choice.words = {text(views), "none"};
  choice.get = [&offsets_m, text] { return text(offsets_m); };
  choice.set = [&offsets_m, views = std::move(views)](const std::string& word) {
    offsets_m = word == "none" ? std::vector<double>{} : views;
  };
  return choice;
}

}  // namespace

bool SlamConfiguration::is_valid(std::string* why) const {
  core::Problems problems;
  std::string nested;
  if (!slam.is_valid(&nested)) problems.add(nested);
  nested.clear();
  if (!imu.is_valid(&nested)) problems.add_all("imu: ", nested);
  return problems.report(why);
}

namespace {

// The keys of parameters() by part of the pipeline, in the order --print-config lists them.

/// The front end: odometry, registration, LOAM features and the scans' health.
io::Parameters front_end_parameters(LidarOdometryOptions& odometry) {
  RegistrationOptions& registration = odometry.registration;
  LoamFeatureOptions& loam = odometry.loam;
  return {
      {"odometry", "front_end",
       enum_choice(odometry.front_end, {FrontEnd::kAuto, FrontEnd::kDense, FrontEnd::kLoamFeatures},
                   [](FrontEnd f) { return to_string(f); }),
       "auto (loam when the first scan has rings, dense otherwise), dense (every point, KISS-ICP) or loam (LOAM features)"},
      {"odometry", "rings_from_kitti_order", &odometry.rings_from_kitti_order, "scans without rings get them from KITTI's point order (loam front end only)"},
      {"odometry", "min_range_m", &odometry.min_range_m, "points nearer are dropped (the vehicle itself)"},
      {"odometry", "max_range_m", &odometry.max_range_m, "points beyond are dropped; also the local map's radius"},
      {"odometry", "deskew",
       enum_choice(odometry.deskew, {DeskewMode::kOff, DeskewMode::kPointTimes, DeskewMode::kAzimuth},
                   [](DeskewMode m) { return to_string(m); }),
       "motion compensation: off, from the files' per-point times, or from each point's azimuth"},
      {"odometry", "sweep_period_s", &odometry.sweep_period_s, "duration of one sweep (0.1 for a 10 Hz LiDAR)"},
      {"odometry", "vertical_angle_correction_rad", &odometry.vertical_angle_correction_rad, "elevation added to every point (KITTI's HDL-64E: 0.205 deg)"},
      {"odometry", "voxel_size_m", &odometry.voxel_size_m, "voxel edge v of the local map (scans subsampled at 0.5 v and 1.5 v)"},
      {"odometry", "max_points_per_voxel", &odometry.max_points_per_voxel, "points kept per map voxel"},
      {"odometry", "initial_threshold_m", &odometry.initial_threshold_m, "adaptive threshold sigma before any motion sample (KISS-ICP eq. 4)"},
      {"odometry", "min_motion_m", &odometry.min_motion_m, "pose deviations below this do not update sigma"},
      {"odometry", "threads", &odometry.threads, "threads for preprocessing and registration (0 = all)"},
      {"registration", "metric",
       enum_choice(registration.metric, {IcpMetric::kPointToPlane, IcpMetric::kPointToPoint}, metric_name),
       "residual of the dense front end: point-to-plane or point-to-point (KISS-ICP's)"},
      {"registration", "max_iterations", &registration.max_iterations, "Gauss-Newton iterations at most"},
      {"registration", "convergence_step", &registration.convergence_step, "stop when the step's norm (m and rad mixed) is below this"},
      {"registration", "degenerate_min_eigenvalue", &registration.degenerate_min_eigenvalue, "translation directions whose normal moment is below this are degenerate, in [0, 1/3)"},
      {"registration", "remap_degenerate_directions", &registration.remap_degenerate_directions, "dense front end: degenerate directions from the prediction only (Zhang et al. 2016; loam always)"},
      {"loam", "neighbours", &loam.neighbours, "points on either side in the smoothness c (LOAM eq. 1)"},
      {"loam", "sectors_per_ring", &loam.sectors_per_ring, "sectors of equal point count per ring"},
      {"loam", "sharp_per_sector", &loam.sharp_per_sector, "edge points matched against the map, per sector"},
      {"loam", "less_sharp_per_sector", &loam.less_sharp_per_sector, "edge points added to the map, per sector"},
      {"loam", "flat_per_sector", &loam.flat_per_sector, "planar points matched against the map, per sector"},
      {"loam", "edge_curvature", &loam.edge_curvature, "c above this: an edge point"},
      {"loam", "plane_curvature", &loam.plane_curvature, "c below this: a planar point"},
      {"loam", "depth_jump_ratio", &loam.depth_jump_ratio, "a neighbour nearer or farther by this share of the range marks a depth jump"},
      {"loam", "less_flat_voxel_m", &loam.less_flat_voxel_m, "subsampling of the planar points added to the map"},
      {"health", "min_scan_points", &odometry.min_scan_points, "a scan with fewer points in range is lost without registration"},
      {"health", "degraded_min_correspondence_fraction", &odometry.degraded_min_correspondence_fraction, "fewer of the points matched: degraded"},
      {"health", "lost_min_correspondence_fraction", &odometry.lost_min_correspondence_fraction, "fewer matched: lost (pose from the prediction, new map segment)"},
      {"health", "lost_max_rms_voxels", &odometry.lost_max_rms_voxels, "dense front end: inlier RMS above this many voxels ..."},
      {"health", "lost_rms_max_correspondence_fraction", &odometry.lost_rms_max_correspondence_fraction, "... while fewer than this share matched: lost (0 = off)"},
  };
}

/// Keyframes, place recognition, loop closure and the pose graph.
io::Parameters back_end_parameters(LidarSlamOptions& o) {
  ScanContextOptions& sc = o.scan_context;
  return {
      {"keyframes", "distance_m", &o.keyframe_distance_m, "odometry motion since the last keyframe that makes a new one"},
      {"keyframes", "angle_rad", &o.keyframe_angle_rad, "rotation since the last keyframe that makes a new one"},
      {"scan_context", "rings", &sc.rings, "N_r rings of the descriptor"},
      {"scan_context", "sectors", &sc.sectors, "N_s sectors (yaw resolution 2 pi / N_s)"},
      {"scan_context", "max_radius_m", &sc.max_radius_m, "L_max: farther points are ignored"},
      {"scan_context", "sensor_height_m", &sc.sensor_height_m, "h added to every z before the bin maximum"},
      {"scan_context", "candidates", &sc.candidates, "nearest ring keys scored with the full distance"},
      {"scan_context", "search_ratio", &sc.search_ratio, "share of the column shifts tried around the sector keys' alignment (0 or 1: all)"},
      {"scan_context", "exclude_recent", &sc.exclude_recent, "keyframes this recent are not candidates"},
      {"scan_context", "max_distance", &sc.max_distance, "candidates at most this far (in [0, 2]) are verified"},
      {"scan_context", "tree_rebuild_period", &sc.tree_rebuild_period, "the k-d tree is rebuilt after this many new keyframes"},
      {"scan_context", "lateral_offsets_m", lateral_offsets_choice(sc.lateral_offsets_m), "virtual query viewpoints along the sensor's y axis (Scan Context++), or none"},
      {"loop_closure", "enabled", &o.loop_closure, "Scan Context search, verification and pose graph (false: odometry only)"},
      {"loop_closure", "places_verified", &o.loop_places_verified, "distinct places verified per keyframe, best descriptor distance first"},
      {"loop_closure", "verification_neighbours", &o.verification_neighbours, "keyframes on either side of the candidate forming the ICP target"},
      {"loop_closure", "verification_coarse_threshold_m", &o.verification_coarse_threshold_m, "first correspondence distance of the verification ICP"},
      {"loop_closure", "verification_fine_threshold_m", &o.verification_fine_threshold_m, "last correspondence distance; fitness counts points within it"},
      {"loop_closure", "verification_voxel_m", &o.verification_voxel_m, "voxel of the ICP target (source points: 1.5 times this)"},
      {"loop_closure", "min_fitness", &o.loop_min_fitness, "verification: share of points with a target point within the fine threshold"},
      {"loop_closure", "max_rms_m", &o.loop_max_rms_m, "verification: ICP residual RMS"},
      {"loop_closure", "gate_translation_m", &o.loop_gate_translation_m, "odometry gate: verified and estimated relative pose differ by at most this ..."},
      {"loop_closure", "gate_drift_per_m", &o.loop_gate_drift_per_m, "... plus this per metre travelled between the keyframes"},
      {"loop_closure", "gate_rotation_rad", &o.loop_gate_rotation_rad, "odometry gate, rotation ..."},
      {"loop_closure", "gate_rotation_drift_per_m", &o.loop_gate_rotation_drift_per_m, "... plus this per metre travelled"},
      {"loop_closure", "uniqueness_separation_m", &o.loop_uniqueness_separation_m, "places farther apart than this are distinct"},
      {"loop_closure", "ambiguity_fitness_margin", &o.loop_ambiguity_fitness_margin, "a second place fitting within this of the best makes the loop ambiguous"},
      {"back_end", "odometry_translation_sigma_m", &o.odometry_translation_sigma_m, "noise of keyframe-to-keyframe edges"},
      {"back_end", "odometry_rotation_sigma_rad", &o.odometry_rotation_sigma_rad, "noise of keyframe-to-keyframe edges"},
      {"back_end", "segment_break_translation_sigma_m", &o.segment_break_translation_sigma_m, "weak edge across a map-segment change"},
      {"back_end", "segment_break_rotation_sigma_rad", &o.segment_break_rotation_sigma_rad, "weak edge across a map-segment change"},
      {"back_end", "loop_translation_sigma_m", &o.loop_translation_sigma_m, "noise of loop-closure edges"},
      {"back_end", "loop_rotation_sigma_rad", &o.loop_rotation_sigma_rad, "noise of loop-closure edges"},
      {"back_end", "final_gnc", &o.final_gnc, "GNC over the loop closures at the end (rejects the ones that disagree)"},
  };
}

/// GNSS anchoring and the LiDAR-inertial fusion.
io::Parameters sensor_parameters(LidarSlamOptions& o, InertialFusionOptions& imu) {
  return {
      {"gnss", "max_fix_gap_s", &o.gnss.max_fix_gap_s, "a fix is placed between two scans only when one is this close in time (used with --gnss)"},
      {"gnss", "solve_every_keyframes", &o.gnss.solve_every_keyframes, "the graph with its GNSS factors is solved every this many keyframes (and at loops, at the end)"},
      {"gnss", "default_sigma_horizontal_m", &o.gnss.factor.default_sigma_horizontal_m, "a fix without a covariance: horizontal standard deviation"},
      {"gnss", "default_sigma_vertical_m", &o.gnss.factor.default_sigma_vertical_m, "... and vertical"},
      {"gnss", "min_sigma_m", &o.gnss.factor.min_sigma_m, "floor on a fix's standard deviation along every axis"},
      {"gnss", "alignment_min_spread_m", &o.gnss.alignment.min_spread_m, "yaw counts as observable once the path's RMS horizontal spread reaches this"},
      {"gnss", "world_tilt_sigma_rad", &o.gnss.world_tilt_sigma_rad, "how level the SLAM's world is (roll and pitch prior of T_enu_world)"},
      {"gnss", "degenerate_edge_sigma_m", &o.gnss.degenerate_edge_sigma_m, "odometry edges the registration could not see along: sigma along that direction"},
      {"gnss", "outlier_probability", &o.gnss.outlier_probability, "a fix beyond this chi-square(3) quantile after a solve is reported as an outlier"},
      {"imu", "window_states", &imu.window_states, "states (scans) in the sliding window of the LiDAR-inertial factor graph (>= 2; used with --imu)"},
      {"imu", "lidar_rotation_sigma_rad", &imu.lidar_rotation_sigma_rad, "LiDAR odometry factor: rotation standard deviation"},
      {"imu", "lidar_translation_sigma_m", &imu.lidar_translation_sigma_m, "LiDAR odometry factor: translation standard deviation"},
      {"imu", "degenerate_translation_sigma_m", &imu.degenerate_translation_sigma_m, "... along a degenerate direction (the IMU carries it)"},
      {"imu", "contradiction_chi2", &imu.contradiction_chi2, "a registration farther than this (squared Mahalanobis, 6 dof) from the IMU's prediction is degraded"},
      {"imu", "gravity_estimation_s", &imu.gravity_estimation_s, "gravity's direction is estimated for this long after the first scan, then held"},
      {"imu", "gravity_mps2", &imu.gravity_mps2, "magnitude of gravity (also the static initialisation's)"},
      {"imu", "initial_velocity_sigma_still_mps", &imu.initial_velocity_sigma_still_mps, "prior on the first velocity when the IMU was still at the start"},
      {"imu", "initial_velocity_sigma_moving_mps", &imu.initial_velocity_sigma_moving_mps, "... when it was moving (the registrations give the velocity)"},
      {"imu", "initial_gyro_bias_sigma_rad_s", &imu.initial_gyro_bias_sigma_rad_s, "prior on the first gyroscope bias"},
      {"imu", "initial_accel_bias_sigma_mps2", &imu.initial_accel_bias_sigma_mps2, "prior on the first accelerometer bias"},
      {"imu", "initialization_window_s", &imu.initialization.window_s, "static initialisation: the IMU's seconds before the first scan it looks at"},
      {"imu", "initialization_block_s", &imu.initialization.block_s, "... still when the means of its blocks this long ..."},
      {"imu", "initialization_gyro_block_spread_max_rad_s", &imu.initialization.gyro_block_spread_max_rad_s, "... agree with the window's mean within this (every gyroscope axis) ..."},
      {"imu", "initialization_accel_block_spread_max_mps2", &imu.initialization.accel_block_spread_max_mps2, "... and this (every accelerometer axis)"},
      {"imu", "initialization_lidar_motion_max_m", &imu.still_lidar_motion_max_m, "... and the LiDAR moved less than this in the window (a constant acceleration reads as a tilt to the IMU)"},
  };
}

}  // namespace

io::Parameters parameters(SlamConfiguration& configuration) {
  io::Parameters all = front_end_parameters(configuration.slam.odometry);
  const auto append = [&all](io::Parameters part) { all.insert(all.end(), part.begin(), part.end()); };
  append(back_end_parameters(configuration.slam));
  append(sensor_parameters(configuration.slam, configuration.imu));
  return all;
}

const io::Configuration<SlamConfiguration>& configuration() {
  static const io::Configuration<SlamConfiguration> c(&parameters, "slam3d", "# cairn slam3d configuration: every key, its value and what it means.");
  return c;
}

}  // namespace cairn::lidar3d
