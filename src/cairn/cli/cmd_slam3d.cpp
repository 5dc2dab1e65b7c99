// `cairn slam3d SCANS --out DIR`: 3D LiDAR SLAM on a folder (or list) of scans, fed one scan
// at a time through the same streaming interface a robot would use (lidar3d/odometry.hpp); with
// --imu (or --imu-topic), LiDAR-inertial SLAM (lidar3d/lidar_inertial_slam.hpp) over the same scans,
// every IMU sample given first. The run's record, outputs and report are the library's
// (lidar3d/slam_run.hpp, run_outputs.hpp, inertial_outputs.hpp), and so are the description of every
// option (lidar3d/config.hpp) and the reading of the IMU (lidar3d/inertial_input.hpp); the flags and
// the options they stand for are in slam3d_flags.cpp.

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <memory>
#include <optional>
#include <unistd.h>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/slam3d_flags.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/eval/spread.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/lidar3d/config.hpp"
#include "cairn/lidar3d/foxglove_output.hpp"
#include "cairn/lidar3d/gnss_outputs.hpp"
#include "cairn/lidar3d/inertial_outputs.hpp"
#include "cairn/lidar3d/lidar_inertial_slam.hpp"
#include "cairn/lidar3d/map_file.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/run_outputs.hpp"
#include "cairn/lidar3d/saved_map.hpp"
#include "cairn/lidar3d/scan_reader.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"

namespace cairn::cli {
namespace {

/// One --ground-truth pose per scan of the sequence (none without the flag).
std::vector<core::SE3> read_ground_truth(const Slam3dFlags& flags, std::size_t n) {
  std::vector<core::SE3> ground_truth;
  if (flags.ground_truth.empty()) return ground_truth;
  const io::FileFormat format = resolve_format(flags.ground_truth, flags.ground_truth_format, "--ground-truth-format");
  const io::Trajectory trajectory = read_trajectory(flags.ground_truth, format, "", nullptr);
  if (trajectory.size() < n) {
    throw io::ParseError(flags.ground_truth, 0, "expected a pose for each of the " + std::to_string(n) + " scans, found " +
                                                    std::to_string(trajectory.size()));
  }
  ground_truth.assign(trajectory.poses.begin(), trajectory.poses.begin() + static_cast<std::ptrdiff_t>(n));
  return ground_truth;
}

/// LidarSlam, or LiDAR-inertial SLAM over it when the run has an IMU (every sample given at once);
/// the GNSS fixes up to each scan's time given before it.
struct Pipeline {
  lidar3d::LidarSlam& slam;
  std::optional<lidar3d::LidarInertialSlam> inertial;
  lidar3d::InertialRun* inertial_run = nullptr;
  const std::vector<gnss::GnssFix>* fixes = nullptr;
  std::size_t next_fix = 0;

  /// The fixes up to `time_s` (all when infinite) not given yet.
  void add_fixes_until(double time_s) {
    for (; fixes != nullptr && next_fix < fixes->size() && (*fixes)[next_fix].stamp.seconds() <= time_s; ++next_fix) {
      slam.add_gnss((*fixes)[next_fix]);
    }
  }

  lidar3d::SlamScanResult add_scan(std::size_t k, const io::PointCloud& cloud, double time_s) {
    add_fixes_until(time_s);
    if (!inertial) return slam.add_scan(cloud, time_s);
    lidar3d::LidarInertialScan scan = inertial->add_scan(cloud, time_s);
    inertial_run->add_scan(k, scan.inertial);
    return scan.slam;
  }
};

/// Reads and feeds the scans one at a time, recording them in `run`, with health changes and
/// progress on stderr, until the last or an interrupt. Returns whether interrupted.
bool feed_scans(const Slam3dFlags& flags, lidar3d::ScanSequence& sequence, Pipeline& pipeline, lidar3d::SlamRun& run) {
  const lidar3d::LidarSlam& slam = pipeline.slam;
  const std::size_t n = sequence.files.size();
  lidar3d::ScanReader reader(sequence);
  const bool tty_progress = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  lidar3d::Health last_health = lidar3d::Health::kOk;
  std::size_t processed = 0;
  for (std::size_t k = 0; k < n && !interrupted(); ++k) {
    const auto read_start = core::Clock::now();
    io::PointCloud cloud;
    try {
      cloud = reader.read(k);
    } catch (const io::ParseError& e) {
      if (!flags.lenient) throw;
      run.add_skipped(sequence.files[k], e.what());
      if (!flags.quiet) std::fprintf(stderr, "%scairn slam3d: skipped %s\n", tty_progress ? "\r" : "", e.what());
      processed = k + 1;
      continue;
    }
    const double read_s = core::seconds_since(read_start);
    const lidar3d::SlamScanResult slam_result = pipeline.add_scan(k, cloud, sequence.times_s[k]);
    const lidar3d::OdometryScanResult& result = slam_result.odometry;
    run.add_scan(k, cloud, slam_result, read_s);
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
  return stopped;
}

void print_errors(const std::string& ground_truth_file, const lidar3d::TrajectoryErrors& errors) {
  std::printf("against %s (%zu poses, %.1f m):\n", ground_truth_file.c_str(), errors.poses, errors.path_length_m);
  std::printf("  end-point error      %.3f m (%.2f %% of the path)\n", errors.end_point_error_m, errors.end_point_error_percent);
  std::printf("  RPE, consecutive     %.4f m  %.4f deg (RMSE)\n", errors.rpe_translation_rmse_m, errors.rpe_rotation_rmse_deg);
  if (errors.ate_rmse_m) {
    std::printf("  ATE, SE(3)-aligned   %.4f m (RMSE)\n", *errors.ate_rmse_m);
  } else {
    std::printf("  ATE, SE(3)-aligned   not available: %s\n", errors.ate_note.c_str());
  }
  if (errors.kitti_translation_percent) {
    std::printf("  KITTI devkit         t_err %.3f %%  r_err %.4f deg/100 m\n", *errors.kitti_translation_percent,
                *errors.kitti_rotation_deg_per_100m);
  }
}

void print_inertial(const lidar3d::InertialRun& inertial) {
  const lidar3d::InertialSummary s = lidar3d::summarize(inertial);
  const auto& init = inertial.initialization();
  std::printf("IMU: %zu samples at %.1f Hz from %s; initialised %s; %zu scans fused, %zu without a prediction\n",
              inertial.input().checks.samples, inertial.input().checks.median_rate_hz, inertial.input().source.c_str(),
              !init ? "never" : init->still ? "still" : "moving", s.fused_scans, s.scans_without_prediction);
  std::printf("  registration vs IMU  chi2 median %.2f, p90 %.2f; %zu contradicting the IMU, %zu degenerate carried by it\n",
              s.median_chi2, s.p90_chi2, s.scans_contradicting_imu, s.degenerate_scans_carried);
  const Vector3& bg = s.final_bias.gyro_rad_s;
  const Vector3& ba = s.final_bias.accel_mps2;
  std::printf("  final biases         gyro %.5f %.5f %.5f rad/s, accel %.4f %.4f %.4f m/s^2\n", bg.x(), bg.y(), bg.z(),
              ba.x(), ba.y(), ba.z());
}

void print_gnss(const lidar3d::GnssAnchoring& gnss) {
  const lidar3d::GnssAnchoringSummary& s = gnss.summary();
  std::printf("GNSS: %zu fixes, %zu placed on keyframes, %zu used, %zu outliers (chi2 > %.1f)", s.fixes, s.placed, s.used,
              s.outliers, s.outlier_chi2);
  if (s.aligned) {
    std::printf("; aligned at %.1f s (yaw %.2f deg, path spread %.1f m)\n", s.alignment_time_s,
                s.T_enu_world.so3().log().z() * 180.0 / M_PI, s.alignment.spread_m);
  } else {
    std::printf("; never aligned (%s): no GNSS factor used\n", s.alignment.message.empty() ? "no fix placed" : s.alignment.message.c_str());
  }
}

void print_summary(const Slam3dFlags& flags, const lidar3d::LidarSlam& slam, const lidar3d::SlamRun& run,
                   const std::optional<lidar3d::TrajectoryErrors>& errors, double total_s, bool stopped,
                   const lidar3d::InertialRun* inertial) {
  const std::vector<lidar3d::OdometryScanResult>& results = run.scans();
  std::vector<double> t_total;
  for (const auto& r : results) t_total.push_back(r.times.total_s);
  const eval::Spread total = eval::spread(t_total);
  const lidar3d::HealthCounts health = run.health_counts();
  const lidar3d::LidarSlamSummary& slam_summary = slam.summary();
  std::printf("%zu scans in %.1f s; per scan %.1f ms median, %.1f ms mean, %.1f ms max (odometry only)\n", results.size(),
              total_s, 1e3 * total.median, 1e3 * total.mean, 1e3 * total.max);
  std::printf("health: %zu ok, %zu degraded, %zu lost; %d map segment%s\n", health.ok, health.degraded, health.lost,
              results.back().segment + 1, results.back().segment == 0 ? "" : "s");
  if (health.unusable_point_times > 0) {
    std::printf("warning: %zu scans carry per-point times that are not offsets within a sweep (absolute times? another "
                "unit?): used without deskew\n", health.unusable_point_times);
  }
  if (slam.options().loop_closure) {
    std::printf("loop closure: %zu keyframes, %zu candidates verified, %zu accepted, %zu rejected by the back end (GNC)\n",
                slam_summary.keyframes, slam_summary.candidates.size(), slam_summary.loops_accepted,
                slam_summary.loops_rejected_by_gnc);
  }
  if (inertial != nullptr) print_inertial(*inertial);
  if (slam.gnss() != nullptr) print_gnss(*slam.gnss());
  if (errors) print_errors(flags.ground_truth, *errors);
  const bool enu = slam.gnss() != nullptr && slam.gnss()->aligned();
  std::printf("wrote trajectory.tum, trajectory.kitti, %smap.ply (%zu points), map.png, %s%sreport.json to %s%s\n",
              enu ? "trajectory_enu.tum, " : "", run.global_map().size(),
              inertial != nullptr ? "inertial_states.csv, inertial.png, " : "", slam.gnss() != nullptr ? "gnss_fixes.csv, " : "",
              flags.out.c_str(), stopped ? " (interrupted: the result so far)" : "");
  if (!flags.save_map.empty()) {
    std::printf("wrote the map for reuse (cairn localize3d --map) to %s\n", flags.save_map.c_str());
  }
}

/// The run's IMU (none without --imu / --imu-topic), its notes on stderr.
std::unique_ptr<lidar3d::InertialRun> read_imu(const Slam3dFlags& flags, const lidar3d::SlamConfiguration& options,
                                               bool remap_forced) {
  const std::optional<lidar3d::InertialInputRequest> request = imu_request(flags);
  if (!request) return nullptr;
  lidar3d::InertialInput input = lidar3d::read_inertial_input(*request);
  if (!flags.quiet) {
    for (const std::string& note : input.notes) std::fprintf(stderr, "cairn slam3d: %s\n", note.c_str());
    if (remap_forced) {
      std::fprintf(stderr, "cairn slam3d: with an IMU, registration.remap_degenerate_directions is set to true (the IMU "
                           "carries the degenerate directions)\n");
    }
  }
  const lidar3d::InertialFusionOptions fusion = lidar3d::inertial_fusion_options(options.imu, input);
  return std::make_unique<lidar3d::InertialRun>(std::move(input), fusion, remap_forced);
}

int slam3d_command(const Slam3dFlags& flags) {
  bool remap_forced = false;
  const lidar3d::SlamConfiguration options = slam3d_options(flags, &remap_forced);
  const lidar3d::LidarSlamOptions& slam_options = options.slam;
  if (flags.print_config) {
    std::fputs(lidar3d::configuration().yaml(options).c_str(), stdout);
    if (flags.scans.empty()) return 0;
  }
  if (!(flags.map_voxel_m > 0.0) || !std::isfinite(flags.map_voxel_m)) throw std::invalid_argument("--map-voxel must be > 0");
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  if (!flags.mcap.empty()) {
    if (io::is_standard_output(flags.mcap)) throw std::invalid_argument("--mcap needs a file: MCAP is binary");
    io::resolve_output(flags.mcap);
    io::check_file_outside_directory("--mcap", flags.mcap, "--out", flags.out,
                                     {"trajectory.tum", "trajectory.kitti", "map.ply", "map.png", "report.json", "inertial_states.csv", "inertial.png",
                                      "gnss_fixes.csv", "trajectory_enu.tum", "dynamic.ply"});
  }
  if (!flags.save_map.empty()) {
    if (io::is_standard_output(flags.save_map)) throw std::invalid_argument("--save-map needs a file: the map is binary");
    io::resolve_output(flags.save_map);
    io::check_file_outside_directory("--save-map", flags.save_map, "--out", flags.out,
                                     {"trajectory.tum", "trajectory.kitti", "map.ply", "map.png", "report.json", "inertial_states.csv", "inertial.png",
                                      "gnss_fixes.csv", "trajectory_enu.tum", "dynamic.ply"});
  }
  lidar3d::ScanSequence sequence =
      read_scan_sequence(flags.scans, flags.times, flags.times_column, flags.cloud_topic, flags.max_scans);
  const std::vector<core::SE3> ground_truth = read_ground_truth(flags, sequence.files.size());
  const std::unique_ptr<lidar3d::InertialRun> inertial = read_imu(flags, options, remap_forced);
  std::vector<std::string> gnss_notes;
  const std::vector<gnss::GnssFix> fixes = read_gnss_fixes(flags, &gnss_notes);
  if (!flags.quiet) {
    for (const std::string& note : gnss_notes) std::fprintf(stderr, "cairn slam3d: %s\n", note.c_str());
  }
  if (!flags.quiet && !sequence.times_from_file) {
    std::fprintf(stderr, "cairn slam3d: no --times: scans taken as 0.1 s apart (the motion prediction assumes a steady rate)\n");
  }

  // Refuse a directory of another run before the work, not after it.
  io::OutputDirectory out(flags.out, flags.overwrite);
  const auto start = core::Clock::now();
  lidar3d::LidarSlam slam(slam_options);
  lidar3d::SlamRun run(slam_options.odometry, flags.map_voxel_m);
  Pipeline pipeline{slam, std::nullopt, inertial.get(), fixes.empty() ? nullptr : &fixes, 0};
  if (inertial) {
    pipeline.inertial.emplace(slam, inertial->options());
    for (const inertial::ImuSample& sample : inertial->input().samples) pipeline.inertial->add_imu(sample);
  }
  const bool stopped = feed_scans(flags, sequence, pipeline, run);
  if (run.scans().empty()) throw std::runtime_error("no scan could be processed");
  if (!stopped) {
    pipeline.add_fixes_until(std::numeric_limits<double>::infinity());  // those after the last scan: reported as such
    slam.finish();
  }
  run.finish(slam);
  if (flags.remove_dynamic) run.remove_dynamic_points(slam, lidar3d::DynamicPointOptions{});
  if (inertial) inertial->finish(pipeline.inertial->fusion());
  const double total_s = core::seconds_since(start);

  const lidar3d::SlamRunInputs inputs{flags.scans, flags.times, flags.preset, flags.ground_truth};
  const std::optional<lidar3d::TrajectoryErrors> errors =
      lidar3d::write_run_outputs(out, inputs, sequence, slam, run, ground_truth, flags.picture_px, total_s, stopped, inertial.get());
  if (!flags.mcap.empty()) lidar3d::write_foxglove_mcap(flags.mcap, slam, run);
  if (!flags.save_map.empty()) {
    const std::string source = flags.scans.size() == 1 ? flags.scans.front() : flags.scans.front() + " ...";
    lidar3d::write_saved_map(flags.save_map, lidar3d::make_saved_map(slam, run, lidar3d::configuration().json(options).dump(), source));
  }
  if (!flags.quiet) print_summary(flags, slam, run, errors, total_s, stopped, inertial.get());
  if (inertial && !flags.quiet) {
    for (const std::string& warning : lidar3d::summarize(*inertial).warnings) warn(warning);
  }
  if (slam.gnss() != nullptr && !flags.quiet) {
    for (const std::string& warning : lidar3d::gnss_warnings(*slam.gnss())) warn(warning);
  }
  return stopped ? interrupted_exit_status() : 0;
}

}  // namespace

Runner register_slam3d(CLI::App& app) {
  auto flags = std::make_shared<Slam3dFlags>();
  add_slam3d_flags(app, *flags);
  return [flags]() { return slam3d_command(*flags); };
}

}  // namespace cairn::cli
