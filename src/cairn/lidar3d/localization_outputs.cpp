#include "cairn/lidar3d/localization_outputs.hpp"

#include <algorithm>
#include <numbers>
#include <ostream>

#include "cairn/io/output_file.hpp"
#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/report.hpp"

namespace cairn::lidar3d {

io::Trajectory localized_trajectory(const std::vector<Localization3dResult>& results) {
  io::Trajectory trajectory;
  for (const Localization3dResult& r : results) {
    if (!r.localised) continue;
    trajectory.stamps.push_back(core::Timestamp::from_seconds(r.time_s));
    trajectory.poses.push_back(r.T_map_sensor);
  }
  return trajectory;
}

void write_localization_csv(const std::vector<Localization3dResult>& results, const std::string& path) {
  io::write_output(path, [&](std::ostream& o) {
    o.precision(17);
    o << "scan,time_s,state,health,localised,x,y,z,qx,qy,qz,qw,fitness,inlier_rmse_m,translation_degeneracy,"
         "degenerate_axis,dead_reckoning,relocalised,odometry_health,hypotheses,reason,total_ms\n";
    for (const Localization3dResult& r : results) {
      const Eigen::Vector3d& t = r.T_map_sensor.translation();
      const Eigen::Quaterniond& q = r.T_map_sensor.unit_quaternion();
      o << r.scan << ',' << r.time_s << ',' << to_string(r.state) << ',' << core::to_string(r.health) << ','
        << (r.localised ? 1 : 0) << ',';
      if (r.localised) {
        o << t.x() << ',' << t.y() << ',' << t.z() << ',' << q.x() << ',' << q.y() << ',' << q.z() << ',' << q.w() << ',';
      } else {
        o << ",,,,,,,";
      }
      // The reason holds commas only inside quotes (RFC 4180).
      o << r.fitness << ',' << r.inlier_rmse_m << ',' << r.translation_degeneracy << ',' << r.degenerate_axis << ','
        << (r.dead_reckoning ? 1 : 0) << ',' << (r.relocalised ? 1 : 0) << ','
        << (r.odometry_step ? core::to_string(r.odometry_health) : std::string_view("not run")) << ','
        << r.live_hypotheses << ",\"" << r.reason << "\"," << 1e3 * r.total_s << '\n';
    }
  });
}

void write_localization_png(const SavedMap3D& map, const std::vector<Localization3dResult>& results,
                            const std::string& path, int max_side_px) {
  // The localised scans as render_top_down draws a run: a new segment after every lost stretch.
  std::vector<OdometryScanResult> drawn;
  int segment = 0;
  bool gap = false;
  for (const Localization3dResult& r : results) {
    if (!r.localised) {
      gap = !drawn.empty();
      continue;
    }
    if (gap) ++segment;
    gap = false;
    OdometryScanResult s;
    s.time_s = r.time_s;
    s.T_world_sensor = r.T_map_sensor;
    s.health = r.health;
    s.segment = segment;
    drawn.push_back(s);
  }
  const std::vector<unsigned char> png = render_top_down(map.points_world, drawn, {}, max_side_px);
  io::write_output(path, [&](std::ostream& o) {
    o.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

namespace {

nlohmann::json options_json(const Localizer3dOptions& o) {
  return {{"threads", o.threads},
          {"odometry_while_tracking", o.odometry_while_tracking},
          {"source_voxel_m", o.source_voxel_m},
          {"target_voxel_m", o.target_voxel_m},
          {"max_correspondence_m", o.max_correspondence_m},
          {"coarse_correspondence_m", o.coarse_correspondence_m},
          {"max_iterations", o.max_iterations},
          {"tracking_max_iterations", o.tracking_max_iterations},
          {"step_tolerance", o.step_tolerance},
          {"sparse_stride", o.sparse_stride},
          {"verification_min_fitness", o.verification_min_fitness},
          {"verification_max_rmse_m", o.verification_max_rmse_m},
          {"min_translation_degeneracy", o.min_translation_degeneracy},
          {"ok_min_fitness", o.ok_min_fitness},
          {"ok_max_rmse_m", o.ok_max_rmse_m},
          {"tracking_min_fitness", o.tracking_min_fitness},
          {"lost_after_failures", o.lost_after_failures},
          {"retry_yaw_offsets_rad", o.retry_yaw_offsets_rad},
          {"candidates", o.candidates},
          {"max_descriptor_distance", o.max_descriptor_distance},
          {"places_verified", o.places_verified},
          {"separation_m", o.separation_m},
          {"confirmations", o.confirmations},
          {"agreement_m", o.agreement_m},
          {"agreement_rad", o.agreement_rad},
          {"hypothesis_max_misses", o.hypothesis_max_misses},
          {"max_hypotheses", o.max_hypotheses},
          {"hypothesis_drop_deficit", o.hypothesis_drop_deficit},
          {"hypothesis_drop_window_scans", o.hypothesis_drop_window_scans},
          {"check_every_n_scans", o.check_every_n_scans},
          {"rival_score_margin", o.rival_score_margin},
          {"max_acceleration_mps2", o.max_acceleration_mps2},
          {"jump_margin_m", o.jump_margin_m},
          {"polish_offsets_m", o.polish_offsets_m}};
}

nlohmann::json attempt_json(const LocalizationAttempt3d& a) {
  return {{"scan", a.scan},
          {"keyframe", a.keyframe},
          {"descriptor_distance", a.descriptor_distance},
          {"descriptor_yaw_deg", a.descriptor_yaw_rad * 180.0 / std::numbers::pi},
          {"while_tracking", a.while_tracking},
          {"fitness", a.fitness},
          {"inlier_rmse_m", a.inlier_rmse_m},
          {"translation_degeneracy", a.translation_degeneracy},
          {"pose", pose_json(a.T_map_sensor)},
          {"decision", a.decision}};
}

nlohmann::json relocalisation_json(const Relocalisation3d& r) {
  return {{"scan", r.scan},
          {"time_s", r.time_s},
          {"pose", pose_json(r.T_map_sensor)},
          {"searching_since_scan", r.searching_since_scan},
          {"from_prior", r.from_prior},
          {"support_scans", r.support_scans},
          {"rival_hypotheses", r.rival_hypotheses}};
}

}  // namespace

TrackingTimes tracking_times(const std::vector<Localization3dResult>& results) {
  std::vector<double> ms;
  for (const Localization3dResult& r : results) {
    if (r.localised && !r.relocalised) ms.push_back(1e3 * r.total_s);
  }
  TrackingTimes t;
  if (ms.empty()) return t;
  std::sort(ms.begin(), ms.end());
  const std::size_t n = ms.size();
  t.scans = n;
  t.median_ms = n % 2 == 1 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
  t.p90_ms = ms[(9 * n + 9) / 10 - 1];  // nearest rank ceil(0.9 n), in integers
  t.max_ms = ms.back();
  return t;
}

nlohmann::json to_json(const TrackingTimes& times) {
  return {{"tracked_scans", times.scans}, {"median_ms", times.median_ms}, {"p90_ms", times.p90_ms}, {"max_ms", times.max_ms}};
}

nlohmann::json localization_report_json(const Localizer3d& localizer) {
  const Localizer3dSummary& s = localizer.summary();
  const SavedMap3D& map = localizer.map();
  nlohmann::json attempts = nlohmann::json::array();
  for (const LocalizationAttempt3d& a : s.attempts) attempts.push_back(attempt_json(a));
  nlohmann::json relocalisations = nlohmann::json::array();
  for (const Relocalisation3d& r : s.relocalisations) relocalisations.push_back(relocalisation_json(r));
  return {{"map", {{"source", map.source}, {"keyframes", s.map_keyframes}, {"points", s.map_points},
                   {"target_points", s.target_points}, {"map_voxel_m", map.map_voxel_m}, {"setup_s", s.setup_s}}},
          {"options", options_json(localizer.options())},
          {"summary",
           {{"scans", s.scans},
            {"ok", s.scans_ok},
            {"degraded", s.scans_degraded},
            {"lost", s.scans_lost},
            {"localised", s.scans_localised},
            {"first_localised_scan", s.first_localised_scan ? nlohmann::json(*s.first_localised_scan) : nlohmann::json()},
            {"descriptor_queries", s.descriptor_queries},
            {"places_matched", s.places_matched},
            {"places_verified", s.places_verified},
            {"hypotheses", s.hypotheses},
            {"hypotheses_dropped", s.hypotheses_dropped},
            {"hypotheses_ignored", s.hypotheses_ignored},
            {"scans_ambiguous", s.scans_ambiguous},
            {"tracking_failures", s.tracking_failures},
            {"tracking_checks", s.tracking_checks},
            {"tracking_contradicted", s.tracking_contradicted},
            {"tracking_corrections", s.tracking_corrections},
            {"implausible_jumps", s.implausible_jumps},
            {"localising_s", s.total_s},
            {"max_scan_s", s.max_scan_s},
            {"max_search_s", s.max_search_s}}},
          {"relocalisations", relocalisations},
          {"attempts", attempts}};
}

}  // namespace cairn::lidar3d
