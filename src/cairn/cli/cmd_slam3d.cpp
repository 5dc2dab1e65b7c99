// `cairn slam3d SCANS --out DIR`: 3D LiDAR SLAM on a folder (or list) of scans, fed one scan
// at a time through the same streaming interface a robot would use (lidar3d/odometry.hpp).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <unistd.h>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/spread.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::cli {
namespace {

struct Slam3dFlags {
  std::vector<std::string> scans;
  std::string out;
  std::string preset = "default";
  std::string times;
  int times_column = 1;
  std::string ground_truth;
  std::string ground_truth_format;
  std::string metric;
  std::string deskew;
  std::string front_end;
  long max_scans = 0;
  int threads = 0;
  double map_voxel_m = 0.25;
  int picture_px = 1600;
  bool lenient = false;
  bool no_loop_closure = false;
  bool remap_degenerate = false;
  bool quiet = false;
  bool progress = false;
  bool overwrite = false;
};

nlohmann::json pose_json(const core::SE3& T) {
  const Eigen::Quaterniond& q = T.unit_quaternion();
  return {{"t", {T.translation().x(), T.translation().y(), T.translation().z()}}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
}

int slam3d_command(const Slam3dFlags& flags) {
  lidar3d::LidarSlamOptions slam_options;
  slam_options.odometry = lidar3d::preset_options(flags.preset);
  slam_options.loop_closure = !flags.no_loop_closure;
  lidar3d::LidarOdometryOptions& options = slam_options.odometry;
  if (flags.metric == "point-to-point") options.registration.metric = lidar3d::IcpMetric::kPointToPoint;
  else if (flags.metric == "point-to-plane") options.registration.metric = lidar3d::IcpMetric::kPointToPlane;
  else if (!flags.metric.empty()) throw std::invalid_argument("--metric must be point-to-plane or point-to-point");
  if (flags.remap_degenerate) options.registration.remap_degenerate_directions = true;
  if (flags.front_end == "loam") options.front_end = lidar3d::FrontEnd::kLoamFeatures;
  else if (flags.front_end == "dense") options.front_end = lidar3d::FrontEnd::kDense;
  else if (flags.front_end == "auto") options.front_end = lidar3d::FrontEnd::kAuto;
  else if (!flags.front_end.empty()) throw std::invalid_argument("--front-end must be auto, dense or loam");
  if (flags.deskew == "off") options.deskew = lidar3d::DeskewMode::kOff;
  else if (flags.deskew == "point-times") options.deskew = lidar3d::DeskewMode::kPointTimes;
  else if (flags.deskew == "azimuth") options.deskew = lidar3d::DeskewMode::kAzimuth;
  else if (!flags.deskew.empty()) throw std::invalid_argument("--deskew must be off, point-times or azimuth");
  options.threads = flags.threads;
  std::string error;
  if (!slam_options.is_valid(&error)) throw std::invalid_argument("invalid configuration: " + error);
  if (!(flags.map_voxel_m > 0.0) || !std::isfinite(flags.map_voxel_m)) throw std::invalid_argument("--map-voxel must be > 0");
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");

  lidar3d::ScanSequence sequence = lidar3d::make_scan_sequence(flags.scans, "", 1);
  std::size_t n = sequence.files.size();
  if (flags.max_scans > 0) n = std::min<std::size_t>(n, static_cast<std::size_t>(flags.max_scans));
  sequence.files.resize(n);
  if (!flags.times.empty()) {
    sequence.times_s = lidar3d::read_scan_times(flags.times, flags.times_column, n);
    sequence.times_from_file = true;
  } else {
    sequence.times_s.resize(n);
  }
  std::vector<core::SE3> ground_truth;
  if (!flags.ground_truth.empty()) {
    const io::FileFormat format = resolve_format(flags.ground_truth, flags.ground_truth_format, "--ground-truth-format");
    const io::Trajectory trajectory = read_trajectory(flags.ground_truth, format, "", nullptr);
    if (trajectory.size() < n) {
      throw io::ParseError(flags.ground_truth, 0, "expected a pose for each of the " + std::to_string(n) + " scans, found " +
                                                      std::to_string(trajectory.size()));
    }
    ground_truth.assign(trajectory.poses.begin(), trajectory.poses.begin() + static_cast<std::ptrdiff_t>(n));
  }
  if (!flags.quiet && !sequence.times_from_file) {
    std::fprintf(stderr, "cairn slam3d: no --times: scans taken as 0.1 s apart (the motion prediction assumes a steady rate)\n");
  }

  // Refuse a directory of another run before the work, not after it.
  io::OutputDirectory out(flags.out, flags.overwrite);
  const auto start = std::chrono::steady_clock::now();
  lidar3d::LidarSlam slam(slam_options);
  // Keyframe points at the map's voxel, kept to draw the map at the final (loop-corrected) poses.
  std::vector<std::vector<Eigen::Vector3d>> keyframe_points;
  std::vector<lidar3d::OdometryScanResult> results;
  std::vector<std::size_t> used_index;  // scan k of the sequence -> results
  std::vector<std::pair<std::string, std::string>> skipped;
  std::vector<double> read_s;
  const bool tty_progress = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  lidar3d::Health last_health = lidar3d::Health::kOk;
  std::size_t processed = 0;
  for (std::size_t k = 0; k < n && !interrupted(); ++k) {
    const auto read_start = std::chrono::steady_clock::now();
    io::PointCloud cloud;
    try {
      cloud = io::read_point_cloud(sequence.files[k]);
    } catch (const io::ParseError& e) {
      if (!flags.lenient) throw;
      skipped.emplace_back(sequence.files[k], e.what());
      if (!flags.quiet) std::fprintf(stderr, "%scairn slam3d: skipped %s\n", tty_progress ? "\r" : "", e.what());
      processed = k + 1;
      continue;
    }
    read_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - read_start).count());
    const lidar3d::SlamScanResult slam_result = slam.add_scan(cloud, sequence.times_s[k]);
    const lidar3d::OdometryScanResult& result = slam_result.odometry;
    if (slam_result.keyframe) {
      std::vector<Eigen::Vector3d> points;
      points.reserve(cloud.size());
      const double max2 = options.max_range_m * options.max_range_m, min2 = options.min_range_m * options.min_range_m;
      for (const Eigen::Vector3f& p : cloud.points) {
        const double r2 = p.cast<double>().squaredNorm();
        if (r2 >= min2 && r2 <= max2) points.push_back(p.cast<double>());
      }
      keyframe_points.push_back(lidar3d::voxel_downsample(points, flags.map_voxel_m));
    }
    results.push_back(result);
    used_index.push_back(k);
    processed = k + 1;
    if (result.health != last_health && !flags.quiet) {
      std::fprintf(stderr, "%s[scan %zu, t = %.3f s] %s%s%s\n", tty_progress ? "\r" : "", k, result.time_s,
                   std::string(lidar3d::to_string(result.health)).c_str(),
                   result.degenerate_axis.empty() ? "" : ", degenerate along ", result.degenerate_axis.c_str());
      last_health = result.health;
    }
    if ((tty_progress || flags.progress) && (k % 20 == 0 || k + 1 == n)) {
      std::fprintf(stderr, "%sscan %zu / %zu  %.0f ms  segment %d  loops %zu  %s%s", tty_progress ? "\r" : "", k + 1, n,
                   1e3 * result.times.total_s, result.segment, slam.summary().loops_accepted,
                   std::string(lidar3d::to_string(result.health)).c_str(), tty_progress ? "   " : "\n");
      std::fflush(stderr);
    }
  }
  if (tty_progress) std::fprintf(stderr, "\n");
  const bool stopped = interrupted();
  if (stopped) {
    std::fprintf(stderr, "cairn slam3d: interrupted by %s after scan %zu of %zu: writing the result so far\n",
                 interrupt_signal_name(), processed, n);
  }
  if (results.empty()) throw std::runtime_error("no scan could be processed");
  if (!stopped) slam.finish();
  {
    const std::vector<core::SE3> final_poses = slam.trajectory();
    for (std::size_t i = 0; i < results.size(); ++i) results[i].T_world_sensor = final_poses[i];
  }
  lidar3d::GlobalMap global_map(flags.map_voxel_m);
  {
    // The stored points are the raw scans (not deskewed): placed at their scans' stamp poses.
    const std::vector<std::size_t> keyframe_scans = slam.keyframe_scans();
    for (std::size_t i = 0; i < keyframe_scans.size() && i < keyframe_points.size(); ++i) {
      global_map.add_scan(keyframe_points[i], results[keyframe_scans[i]].T_world_sensor);
    }
  }
  const lidar3d::LidarSlamSummary& slam_summary = slam.summary();
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Trajectory files.
  io::Trajectory trajectory;
  for (const auto& r : results) {
    trajectory.stamps.push_back(core::Timestamp::from_seconds(r.time_s));
    trajectory.poses.push_back(r.T_world_sensor);
  }
  io::write_output(out.staging_path("trajectory.tum"), [&](std::ostream& o) { io::write_tum(o, trajectory); });
  io::write_output(out.staging_path("trajectory.kitti"), [&](std::ostream& o) { io::write_kitti(o, trajectory); });
  const std::vector<Eigen::Vector3f> map_points = global_map.points();
  io::write_output(out.staging_path("map.ply"), [&](std::ostream& o) {
    io::write_ply(o, map_points, "cairn slam3d map, voxel " + std::to_string(flags.map_voxel_m) + " m, world frame = first scan");
  });
  std::vector<core::SE3> ground_truth_used;
  for (std::size_t index : used_index) {
    if (!ground_truth.empty()) ground_truth_used.push_back(ground_truth[index]);
  }
  const std::vector<unsigned char> png = lidar3d::render_top_down(map_points, results, ground_truth_used, flags.picture_px);
  io::write_output(out.staging_path("map.png"), [&](std::ostream& o) {
    o.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });

  // Report.
  nlohmann::json report;
  report["input"] = {{"scans", flags.scans},
                     {"scans_listed", sequence.files.size()},
                     {"scans_processed", results.size()},
                     {"times", flags.times.empty() ? nlohmann::json(nullptr) : nlohmann::json(flags.times)},
                     {"times_from_file", sequence.times_from_file},
                     {"skipped", nlohmann::json::array()}};
  for (const auto& [file, why] : skipped) report["input"]["skipped"].push_back({{"file", file}, {"error", why}});
  report["options"] = {{"preset", flags.preset},
                       {"front_end", std::string(lidar3d::to_string(options.front_end))},
                       {"front_end_used", std::string(lidar3d::to_string(slam.front_end()))},
                       {"metric", options.registration.metric == lidar3d::IcpMetric::kPointToPlane ? "point-to-plane" : "point-to-point"},
                       {"deskew", std::string(lidar3d::to_string(options.deskew))},
                       {"max_range_m", options.max_range_m},
                       {"min_range_m", options.min_range_m},
                       {"voxel_size_m", options.voxel_size_m},
                       {"max_points_per_voxel", options.max_points_per_voxel},
                       {"vertical_angle_correction_rad", options.vertical_angle_correction_rad},
                       {"initial_threshold_m", options.initial_threshold_m},
                       {"min_motion_m", options.min_motion_m},
                       {"degenerate_min_eigenvalue", options.registration.degenerate_min_eigenvalue},
                       {"remap_degenerate_directions", options.registration.remap_degenerate_directions},
                       {"threads", options.threads},
                       {"map_voxel_m", flags.map_voxel_m}};
  std::size_t ok = 0, degraded = 0, lost = 0, unusable_times = 0;
  for (const auto& r : results) unusable_times += r.point_times_unusable ? 1 : 0;
  std::vector<double> t_total, t_pre, t_reg, t_map;
  nlohmann::json scans = nlohmann::json::array();
  nlohmann::json events = nlohmann::json::array();
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& r = results[i];
    (r.health == lidar3d::Health::kOk ? ok : r.health == lidar3d::Health::kDegraded ? degraded : lost)++;
    t_total.push_back(r.times.total_s);
    t_pre.push_back(r.times.preprocess_s);
    t_reg.push_back(r.times.register_s);
    t_map.push_back(r.times.map_s);
    if (i == 0 || r.health != results[i - 1].health) {
      events.push_back({{"scan", used_index[i]}, {"time_s", r.time_s}, {"health", std::string(lidar3d::to_string(r.health))},
                        {"degenerate_axis", r.degenerate_axis}});
    }
    scans.push_back({{"scan", used_index[i]},
                     {"file", sequence.files[used_index[i]]},
                     {"time_s", r.time_s},
                     {"health", std::string(lidar3d::to_string(r.health))},
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
                                  {"map", 1e3 * r.times.map_s}, {"total", 1e3 * r.times.total_s}}}});
  }
  report["summary"] = {{"scans_ok", ok}, {"scans_degraded", degraded}, {"scans_lost", lost},
                       {"map_segments", results.back().segment + 1}, {"map_points", map_points.size()},
                       {"scans_with_unusable_point_times", unusable_times}};
  report["health_events"] = events;
  nlohmann::json candidates = nlohmann::json::array();
  for (const auto& c : slam_summary.candidates) {
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
  report["loop_closure"] = {{"enabled", slam_options.loop_closure},
                            {"keyframes", slam_summary.keyframes},
                            {"queries", slam_summary.loop_queries},
                            {"candidates_verified", slam_summary.candidates.size()},
                            {"accepted", slam_summary.loops_accepted},
                            {"rejected_by_gnc", slam_summary.loops_rejected_by_gnc},
                            {"optimizations", slam_summary.optimizations},
                            {"time_s", {{"search", slam_summary.loop_search_s},
                                        {"verification", slam_summary.verification_s},
                                        {"optimization", slam_summary.optimization_s}}},
                            {"candidates", candidates}};
  report["time_per_scan_ms"] = {{"total", spread_json_ms(t_total)}, {"preprocess", spread_json_ms(t_pre)},
                                {"register", spread_json_ms(t_reg)}, {"map_update", spread_json_ms(t_map)},
                                {"read_file", spread_json_ms(read_s)}};
  report["wall_time_s"] = total_s;
  report["interrupted"] = stopped;
  std::optional<lidar3d::TrajectoryErrors> errors;
  if (!ground_truth_used.empty() && ground_truth_used.size() >= 2) {
    errors = lidar3d::evaluate_trajectory(ground_truth_used, trajectory.poses);
    nlohmann::json e = {{"file", flags.ground_truth},
                        {"poses", errors->poses},
                        {"path_length_m", errors->path_length_m},
                        {"end_point_error_m", errors->end_point_error_m},
                        {"end_point_error_percent", errors->end_point_error_percent},
                        {"rpe_translation_rmse_m", errors->rpe_translation_rmse_m},
                        {"rpe_rotation_rmse_deg", errors->rpe_rotation_rmse_deg},
                        {"ate_se3_rmse_m", errors->ate_rmse_m ? nlohmann::json(*errors->ate_rmse_m) : nlohmann::json(nullptr)}};
    if (!errors->ate_note.empty()) e["ate_note"] = errors->ate_note;
    if (errors->kitti_translation_percent) {
      e["kitti_t_err_percent"] = *errors->kitti_translation_percent;
      e["kitti_r_err_deg_per_100m"] = *errors->kitti_rotation_deg_per_100m;
    }
    report["ground_truth"] = e;
  }
  report["scans"] = scans;
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  out.commit();

  if (!flags.quiet) {
    const Spread total = spread(t_total);
    std::printf("%zu scans in %.1f s; per scan %.1f ms median, %.1f ms mean, %.1f ms max (odometry only)\n", results.size(),
                total_s, 1e3 * total.median, 1e3 * total.mean, 1e3 * total.max);
    std::printf("health: %zu ok, %zu degraded, %zu lost; %d map segment%s\n", ok, degraded, lost, results.back().segment + 1,
                results.back().segment == 0 ? "" : "s");
    if (unusable_times > 0) {
      std::printf("warning: %zu scans carry per-point times that are not offsets within a sweep (absolute times? another "
                  "unit?): used without deskew\n", unusable_times);
    }
    if (slam_options.loop_closure) {
      std::printf("loop closure: %zu keyframes, %zu candidates verified, %zu accepted, %zu rejected by the back end (GNC)\n",
                  slam_summary.keyframes, slam_summary.candidates.size(), slam_summary.loops_accepted,
                  slam_summary.loops_rejected_by_gnc);
    }
    if (errors) {
      std::printf("against %s (%zu poses, %.1f m):\n", flags.ground_truth.c_str(), errors->poses, errors->path_length_m);
      std::printf("  end-point error      %.3f m (%.2f %% of the path)\n", errors->end_point_error_m, errors->end_point_error_percent);
      std::printf("  RPE, consecutive     %.4f m  %.4f deg (RMSE)\n", errors->rpe_translation_rmse_m, errors->rpe_rotation_rmse_deg);
      if (errors->ate_rmse_m) {
        std::printf("  ATE, SE(3)-aligned   %.4f m (RMSE)\n", *errors->ate_rmse_m);
      } else {
        std::printf("  ATE, SE(3)-aligned   not available: %s\n", errors->ate_note.c_str());
      }
      if (errors->kitti_translation_percent) {
        std::printf("  KITTI devkit         t_err %.3f %%  r_err %.4f deg/100 m\n", *errors->kitti_translation_percent,
                    *errors->kitti_rotation_deg_per_100m);
      }
    }
    std::printf("wrote trajectory.tum, trajectory.kitti, map.ply (%zu points), map.png, report.json to %s%s\n",
                map_points.size(), flags.out.c_str(), stopped ? " (interrupted: the result so far)" : "");
  }
  if (stopped) return interrupted_exit_status();
  return 0;
}

}  // namespace

Runner register_slam3d(CLI::App& app) {
  auto flags = std::make_shared<Slam3dFlags>();
  app.add_option("SCANS", flags->scans,
                 "A folder of scans (.pcd/.ply/.bin, optionally .gz/.bz2/.xz; natural name order) or scan files in order")
      ->required();
  app.add_option("--out", flags->out, "Output directory: trajectory.tum, trajectory.kitti, map.ply, map.png, report.json");
  app.add_option("--preset", flags->preset,
                 "Starting configuration: default, or kitti (KITTI HDL-64E scans: 0.205 deg vertical-angle correction, no deskew)")
      ->capture_default_str();
  app.add_option("--times", flags->times, "Table with one row per scan holding its time in seconds (e.g. KITTI times.txt)");
  app.add_option("--times-column", flags->times_column, "Column of --times holding the time (1-based)")->check(checks::count(10000))->capture_default_str();
  app.add_option("--ground-truth", flags->ground_truth,
                 "Ground-truth poses of the same scans (KITTI 3x4 per line, or TUM): print and report drift, RPE, ATE");
  app.add_option("--ground-truth-format", flags->ground_truth_format, "kitti or tum (default: from the file)");
  app.add_option("--metric", flags->metric, "ICP residual of the dense front end: point-to-plane (default) or point-to-point (KISS-ICP's)");
  app.add_option("--front-end", flags->front_end,
                 "auto (default: loam when the scans carry rings, dense otherwise; the kitti preset: dense), dense (every "
                 "point, KISS-ICP's way) or loam (edge and planar features per ring, Zhang & Singh 2014)");
  app.add_option("--deskew", flags->deskew, "off, point-times (default: with the files' per-point times) or azimuth");
  app.add_option("--threads", flags->threads, "Threads (0 = all; more than the machine has are clamped)")->transform(checks::threads())->capture_default_str();
  app.add_option("--map-voxel", flags->map_voxel_m, "Voxel of the written map, metres")->check(checks::in_range(0.001, 1000.0))->capture_default_str();
  app.add_option("--picture-size", flags->picture_px, "Longer side of map.png, pixels")->capture_default_str()->check(checks::whole_range(200, 20000));
  app.add_option("--max-scans", flags->max_scans, "Process only the first N scans")->check(checks::count(std::numeric_limits<long>::max()));
  app.add_flag("--remap-degenerate", flags->remap_degenerate,
               "Dense front end: solve degenerate directions from the motion prediction only (Zhang et al. 2016's "
               "remapping; the loam front end always does)");
  app.add_flag("--no-loop-closure", flags->no_loop_closure, "Odometry only: no Scan Context search, no pose graph");
  app.add_flag("--lenient", flags->lenient, "Skip scans that cannot be read (listed in the report) instead of stopping");
  app.add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  app.add_flag("--progress", flags->progress, "Progress as a line every 20 scans on stderr, also when stderr is not a terminal");
  app.add_flag("--overwrite", flags->overwrite,
               "Write into an --out directory that already holds files (those of the same names are replaced)");
  return [flags]() { return slam3d_command(*flags); };
}

}  // namespace cairn::cli
