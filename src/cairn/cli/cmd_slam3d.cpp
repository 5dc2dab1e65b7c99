// `cairn slam3d SCANS --out DIR`: 3D LiDAR SLAM on a folder (or list) of scans, fed one scan
// at a time through the same streaming interface a robot would use (lidar3d/odometry.hpp). The
// run's record, outputs and report are the library's (lidar3d/slam_run.hpp, run_outputs.hpp).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <unistd.h>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/spread.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/run_outputs.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"

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
  bool lenient = false, no_loop_closure = false, remap_degenerate = false;
  bool quiet = false, progress = false, overwrite = false;
};

/// The preset with the flags applied; throws std::invalid_argument for a bad value.
lidar3d::LidarSlamOptions slam_options_from(const Slam3dFlags& flags) {
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
  return slam_options;
}

/// The scans (the first --max-scans) and their times.
lidar3d::ScanSequence read_sequence(const Slam3dFlags& flags) {
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
  return sequence;
}

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

/// Reads and feeds the scans one at a time, recording them in `run`, with health changes and
/// progress on stderr, until the last or an interrupt. Returns whether interrupted.
bool feed_scans(const Slam3dFlags& flags, const lidar3d::ScanSequence& sequence, lidar3d::LidarSlam& slam,
                lidar3d::SlamRun& run) {
  const std::size_t n = sequence.files.size();
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
      run.add_skipped(sequence.files[k], e.what());
      if (!flags.quiet) std::fprintf(stderr, "%scairn slam3d: skipped %s\n", tty_progress ? "\r" : "", e.what());
      processed = k + 1;
      continue;
    }
    const double read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - read_start).count();
    const lidar3d::SlamScanResult slam_result = slam.add_scan(cloud, sequence.times_s[k]);
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

void print_summary(const Slam3dFlags& flags, const lidar3d::LidarSlam& slam, const lidar3d::SlamRun& run,
                   const std::optional<lidar3d::TrajectoryErrors>& errors, double total_s, bool stopped) {
  const std::vector<lidar3d::OdometryScanResult>& results = run.scans();
  std::vector<double> t_total;
  for (const auto& r : results) t_total.push_back(r.times.total_s);
  const Spread total = spread(t_total);
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
  if (errors) print_errors(flags.ground_truth, *errors);
  std::printf("wrote trajectory.tum, trajectory.kitti, map.ply (%zu points), map.png, report.json to %s%s\n",
              run.global_map().size(), flags.out.c_str(), stopped ? " (interrupted: the result so far)" : "");
}

int slam3d_command(const Slam3dFlags& flags) {
  const lidar3d::LidarSlamOptions slam_options = slam_options_from(flags);
  if (!(flags.map_voxel_m > 0.0) || !std::isfinite(flags.map_voxel_m)) throw std::invalid_argument("--map-voxel must be > 0");
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  const lidar3d::ScanSequence sequence = read_sequence(flags);
  const std::vector<core::SE3> ground_truth = read_ground_truth(flags, sequence.files.size());
  if (!flags.quiet && !sequence.times_from_file) {
    std::fprintf(stderr, "cairn slam3d: no --times: scans taken as 0.1 s apart (the motion prediction assumes a steady rate)\n");
  }

  // Refuse a directory of another run before the work, not after it.
  io::OutputDirectory out(flags.out, flags.overwrite);
  const auto start = std::chrono::steady_clock::now();
  lidar3d::LidarSlam slam(slam_options);
  lidar3d::SlamRun run(slam_options.odometry, flags.map_voxel_m);
  const bool stopped = feed_scans(flags, sequence, slam, run);
  if (run.scans().empty()) throw std::runtime_error("no scan could be processed");
  if (!stopped) slam.finish();
  run.finish(slam);
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const lidar3d::SlamRunInputs inputs{flags.scans, flags.times, flags.preset, flags.ground_truth};
  const std::optional<lidar3d::TrajectoryErrors> errors =
      lidar3d::write_run_outputs(out, inputs, sequence, slam, run, ground_truth, flags.picture_px, total_s, stopped);
  if (!flags.quiet) print_summary(flags, slam, run, errors, total_s, stopped);
  return stopped ? interrupted_exit_status() : 0;
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
