#include "cairn/lidar3d/report.hpp"
#include "cairn/eval/spread.hpp"
#include "cairn/lidar3d/config.hpp"
#include "cairn/lidar3d/gnss_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace cairn::lidar3d {
nlohmann::json pose_json(const core::SE3& T) {
  const Eigen::Quaterniond& q = T.unit_quaternion();
  return {{"t", {T.translation().x(), T.translation().y(), T.translation().z()}}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
}

namespace {


nlohmann::json input_json(const SlamRunInputs& inputs, const ScanSequence& sequence, const SlamRun& run) {
  nlohmann::json input = {{"scans", inputs.scans},
                          {"scans_listed", sequence.files.size()},
                          {"scans_processed", run.scans().size()},
                          {"times", inputs.times_file.empty() ? nlohmann::json(nullptr) : nlohmann::json(inputs.times_file)},
                          {"times_from_file", sequence.times_from_file},
                          {"skipped", nlohmann::json::array()}};
  for (const SkippedScan& s : run.skipped()) input["skipped"].push_back({{"file", s.file}, {"error", s.error}});
  return input;
}

// configuration().json of the options in effect, with the run's facts that are not options: the preset
// they started from, the front end kAuto chose, and the written map's voxel. The `imu` section only
// when the run had an IMU, the `gnss` section (with the lever arm) only when it had fixes.
nlohmann::json options_json(const SlamRunInputs& inputs, const LidarSlam& slam, const SlamRun& run,
                            const InertialRun* inertial) {
  nlohmann::json options =
      configuration().json(SlamConfiguration{slam.options(), inertial ? inertial->options() : InertialFusionOptions{}});
  if (inertial == nullptr) options.erase("imu");
  if (slam.gnss() == nullptr) {
    options.erase("gnss");
  } else {
    options["gnss"]["lever_arm_lidar_m"] = {slam.options().gnss.factor.lever_arm_body_m.x(), slam.options().gnss.factor.lever_arm_body_m.y(),
                                            slam.options().gnss.factor.lever_arm_body_m.z()};
  }
  options["preset"] = inputs.preset;
  options["front_end_used"] = std::string(to_string(slam.front_end()));
  options["map_voxel_m"] = run.map_voxel_m();
  return options;
}

nlohmann::json scan_json(const OdometryScanResult& r, std::size_t sequence_index, const std::string& file) {
  return {{"scan", sequence_index},
          {"file", file},
          {"time_s", r.time_s},
          {"health", std::string(to_string(r.health))},
          {"segment", r.segment},
          {"pose", pose_json(r.T_world_sensor)},
          {"points_read", r.points_read},
          {"points_in_range", r.points_in_range},
          {"point_times_unusable", r.point_times_unusable},
          {"source_points", r.registration.source_points},
          {"correspondences", r.registration.correspondences},
          {"planar_correspondences", r.registration.planar_correspondences},
          {"iterations", r.registration.iterations},
          {"converged", r.registration.converged},
          {"rms_m", r.registration.rms_m},
          {"threshold_sigma_m", r.threshold_sigma_m},
          {"degeneracy", r.registration.degeneracy},
          {"translation_degeneracy", r.registration.translation_degeneracy},
          {"degenerate_directions", r.registration.degenerate_directions},
          {"degenerate_axis", r.degenerate_axis},
          {"local_map_points", r.local_map_points},
          {"time_ms", {{"preprocess", 1e3 * r.times.preprocess_s}, {"register", 1e3 * r.times.register_s},
                       {"map", 1e3 * r.times.map_s}, {"total", 1e3 * r.times.total_s}}}};
}

// Every change of health, from the first scan's.
nlohmann::json health_events_json(const SlamRun& run) {
  const std::vector<OdometryScanResult>& results = run.scans();
  nlohmann::json events = nlohmann::json::array();
  for (std::size_t i = 0; i < results.size(); ++i) {
    const OdometryScanResult& r = results[i];
    if (i == 0 || r.health != results[i - 1].health) {
      events.push_back({{"scan", run.sequence_indices()[i]}, {"time_s", r.time_s}, {"health", std::string(to_string(r.health))},
                        {"degenerate_axis", r.degenerate_axis}});
    }
  }
  return events;
}

nlohmann::json loop_closure_json(const LidarSlam& slam) {
  const LidarSlamSummary& summary = slam.summary();
  nlohmann::json candidates = nlohmann::json::array();
  for (const LoopCandidateRecord& c : summary.candidates) {
    candidates.push_back({{"query_keyframe", c.query_keyframe},
                          {"candidate_keyframe", c.candidate_keyframe},
                          {"query_time_s", c.query_time_s},
                          {"candidate_time_s", c.candidate_time_s},
                          {"descriptor_distance", c.descriptor_distance},
                          {"descriptor_yaw_deg", c.descriptor_yaw_rad * 180.0 / M_PI},
                          {"second_place_descriptor_distance", c.second_descriptor_distance},
                          {"icp_fitness", c.fitness},
                          {"icp_rms_m", c.rms_m},
                          {"gate_translation_m", c.gate_translation_m},
                          {"gate_limit_m", c.gate_limit_m},
                          {"gate_rotation_deg", c.gate_rotation_rad * 180.0 / M_PI},
                          {"T_candidate_query", pose_json(c.T_candidate_query)},
                          {"decision", c.decision},
                          {"rejected_by_gnc", c.rejected_by_gnc}});
  }
  return {{"enabled", slam.options().loop_closure},
          {"keyframes", summary.keyframes},
          {"queries", summary.loop_queries},
          {"candidates_verified", summary.candidates.size()},
          {"accepted", summary.loops_accepted},
          {"rejected_by_gnc", summary.loops_rejected_by_gnc},
          {"optimizations", summary.optimizations},
          {"time_s", {{"search", summary.loop_search_s}, {"verification", summary.verification_s},
                      {"optimization", summary.optimization_s}}},
          {"candidates", candidates}};
}

nlohmann::json time_per_scan_json(const SlamRun& run) {
  std::vector<double> t_total, t_pre, t_reg, t_map;
  for (const OdometryScanResult& r : run.scans()) {
    t_total.push_back(r.times.total_s);
    t_pre.push_back(r.times.preprocess_s);
    t_reg.push_back(r.times.register_s);
    t_map.push_back(r.times.map_s);
  }
  return {{"total", eval::spread_json_ms(t_total)}, {"preprocess", eval::spread_json_ms(t_pre)}, {"register", eval::spread_json_ms(t_reg)},
          {"map_update", eval::spread_json_ms(t_map)}, {"read_file", eval::spread_json_ms(run.read_times_s())}};
}

nlohmann::json ground_truth_json(const std::string& file, const TrajectoryErrors& errors) {
  nlohmann::json e = {{"file", file},
                      {"poses", errors.poses},
                      {"path_length_m", errors.path_length_m},
                      {"end_point_error_m", errors.end_point_error_m},
                      {"end_point_error_percent", errors.end_point_error_percent},
                      {"rpe_translation_rmse_m", errors.rpe_translation_rmse_m},
                      {"rpe_rotation_rmse_deg", errors.rpe_rotation_rmse_deg},
                      {"ate_se3_rmse_m", errors.ate_rmse_m ? nlohmann::json(*errors.ate_rmse_m) : nlohmann::json(nullptr)}};
  if (!errors.ate_note.empty()) e["ate_note"] = errors.ate_note;
  if (errors.kitti_translation_percent) {
    e["kitti_t_err_percent"] = *errors.kitti_translation_percent;
    e["kitti_r_err_deg_per_100m"] = *errors.kitti_rotation_deg_per_100m;
  }
  return e;
}

}  // namespace

nlohmann::json report_json(const SlamRunInputs& inputs, const ScanSequence& sequence, const LidarSlam& slam,
                           const SlamRun& run, double wall_time_s, bool interrupted,
                           const std::optional<TrajectoryErrors>& errors, const InertialRun* inertial) {
  const HealthCounts health = run.health_counts();
  nlohmann::json scans = nlohmann::json::array();
  for (std::size_t i = 0; i < run.scans().size(); ++i) {
    const std::size_t index = run.sequence_indices()[i];
    scans.push_back(scan_json(run.scans()[i], index, sequence.files[index]));
  }
  nlohmann::json report;
  report["input"] = input_json(inputs, sequence, run);
  report["options"] = options_json(inputs, slam, run, inertial);
  report["summary"] = {{"scans_ok", health.ok}, {"scans_degraded", health.degraded}, {"scans_lost", health.lost},
                       {"map_segments", run.scans().back().segment + 1}, {"map_points", run.global_map().size()},
                       {"scans_with_unusable_point_times", health.unusable_point_times}};
  if (run.dynamic_options()) {
    const DynamicPointSummary& d = run.dynamic_summary();
    report["dynamic_points"] = {{"removed", d.dynamic}, {"of", d.points}, {"rays", d.rays},
                                {"ground_exempt", d.ground_exempt}, {"time_s", d.time_s}};
  }
  report["health_events"] = health_events_json(run);
  report["loop_closure"] = loop_closure_json(slam);
  report["time_per_scan_ms"] = time_per_scan_json(run);
  report["wall_time_s"] = wall_time_s;
  report["interrupted"] = interrupted;
  if (errors) report["ground_truth"] = ground_truth_json(inputs.ground_truth_file, *errors);
  if (inertial != nullptr) report["inertial"] = inertial_json(*inertial);
  if (slam.gnss() != nullptr) report["gnss"] = gnss_json(*slam.gnss());
  report["scans"] = scans;
  return report;
}

}  // namespace cairn::lidar3d
