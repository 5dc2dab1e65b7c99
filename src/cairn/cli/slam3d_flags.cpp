#include "cairn/cli/slam3d_flags.hpp"

#include <algorithm>
#include <limits>
#include <utility>
#include <stdexcept>

#include "cairn/bag/bag.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/gnss/gnss_reader.hpp"
#include "cairn/lidar3d/config.hpp"
#include "cairn/lidar3d/odometry.hpp"

namespace cairn::cli {
namespace {

// A dedicated flag naming an enum: the word of its key (lidar3d/config.hpp), else `message`.
void set_word(lidar3d::SlamConfiguration& options, const std::string& key, const std::string& word, const char* message) {
  if (word.empty()) return;
  try {
    lidar3d::configuration().set(key + "=" + word, options);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(message);
  }
}

}  // namespace

lidar3d::SlamConfiguration slam3d_options(const Slam3dFlags& flags, bool* remap_forced) {
  lidar3d::SlamConfiguration options;
  options.slam.odometry = lidar3d::preset_options(flags.preset);
  checks::apply_configuration(lidar3d::configuration(), flags.config, flags.set, options);
  lidar3d::LidarSlamOptions& slam = options.slam;
  if (flags.no_loop_closure) slam.loop_closure = false;
  set_word(options, "registration.metric", flags.metric, "--metric must be point-to-plane or point-to-point");
  if (flags.remap_degenerate) slam.odometry.registration.remap_degenerate_directions = true;
  set_word(options, "odometry.front_end", flags.front_end, "--front-end must be auto, dense or loam");
  set_word(options, "odometry.deskew", flags.deskew, "--deskew must be off, point-times or azimuth");
  if (flags.command != nullptr && flags.command->count("--threads") > 0) slam.odometry.threads = flags.threads;
  if (!flags.gnss_lever_arm_m.empty()) {
    if (!flags.uses_gnss()) throw UsageError("--gnss-lever-arm goes with --gnss PATH or --gnss-topic TOPIC, and neither was given");
    slam.gnss.factor.lever_arm_body_m = Vector3(flags.gnss_lever_arm_m[0], flags.gnss_lever_arm_m[1], flags.gnss_lever_arm_m[2]);
  }
  const bool forced = flags.uses_imu() && lidar3d::prepare_for_inertial(slam);
  if (remap_forced != nullptr) *remap_forced = forced;
  std::string error;
  if (!options.is_valid(&error)) throw UsageError("invalid configuration: " + error);
  return options;
}

std::optional<lidar3d::InertialInputRequest> imu_request(const Slam3dFlags& flags) {
  const bool offset_given = flags.command != nullptr && flags.command->count("--imu-time-offset") > 0;
  checks::refuse_imu_companions_without_imu(flags.uses_imu(), !flags.imu_calibration.empty(), "--lidar-extrinsic",
                                            !flags.lidar_extrinsic.empty(), offset_given);
  if (!flags.uses_imu()) return std::nullopt;
  const bool scans_in_bag = flags.scans.size() == 1 && bag::is_bag(flags.scans.front());
  if (!flags.imu_topic.empty() && !flags.imu.empty()) {
    throw UsageError("--imu and --imu-topic: give one (--imu-topic reads sensor_msgs/Imu from the scans' bag, --imu a file, "
                     "folder or another bag)");
  }
  if (!flags.imu_topic.empty() && !scans_in_bag) {
    throw UsageError("--imu-topic reads sensor_msgs/Imu from the scans' bag, but SCANS are not a bag: give --imu PATH");
  }
  lidar3d::InertialInputRequest request;
  request.imu.imu = flags.imu;
  if (!flags.imu_topic.empty()) request.imu.bag = flags.scans.front();
  request.imu.topic = flags.imu_topic;
  request.imu.calibration = flags.imu_calibration;
  request.imu.time_offset_s = flags.imu_time_offset_s;
  request.lidar_extrinsic = flags.lidar_extrinsic;
  return request;
}

std::vector<gnss::GnssFix> read_gnss_fixes(const Slam3dFlags& flags, std::vector<std::string>* notes) {
  if (!flags.uses_gnss()) return {};
  const bool gnss_is_bag = !flags.gnss.empty() && bag::is_bag(flags.gnss);
  const bool scans_in_bag = flags.scans.size() == 1 && bag::is_bag(flags.scans.front());
  if (!flags.gnss_topic.empty() && !flags.gnss.empty() && !gnss_is_bag) {
    throw UsageError("--gnss-topic names a sensor_msgs/NavSatFix topic of a bag, but --gnss is not a bag (a CSV needs no topic)");
  }
  if (!flags.gnss_topic.empty() && flags.gnss.empty() && !scans_in_bag) {
    throw UsageError("--gnss-topic reads sensor_msgs/NavSatFix from the scans' bag, but SCANS are not a bag: give --gnss PATH");
  }
  gnss::GnssReadReport report;
  std::vector<gnss::GnssFix> fixes;
  if (gnss_is_bag || flags.gnss.empty()) {
    fixes = gnss::read_gnss_bag(flags.gnss.empty() ? flags.scans.front() : flags.gnss, flags.gnss_topic, &report);
  } else {
    fixes = gnss::read_gnss_csv(flags.gnss, &report);
  }
  if (notes != nullptr) {
    if (report.dropped_no_fix + report.dropped_not_finite + report.dropped_out_of_order > 0) {
      notes->push_back(std::to_string(report.dropped_no_fix + report.dropped_not_finite + report.dropped_out_of_order) +
                       " GNSS records dropped (no fix, NaN or out of order; the first: " + report.first_dropped + ")");
    }
    for (const std::string& w : report.warnings) notes->push_back(w);
    if (fixes.empty()) notes->push_back("no usable GNSS fix: the run goes without GNSS");
  }
  return fixes;
}

lidar3d::ScanSequence read_scan_sequence(const std::vector<std::string>& scans, const std::string& times,
                                         int times_column, const std::string& cloud_topic, long max_scans) {
  // The combinations the library refuses, as usage errors (exit status 2) before any work.
  const bool bag = scans.size() == 1 && bag::is_bag(scans.front());
  if (bag && !times.empty()) throw UsageError("--times goes with scan files: a bag's scans carry their stamps");
  if (!bag && !cloud_topic.empty()) throw UsageError("--cloud-topic goes with a bag, and the scans are files");
  return lidar3d::open_scan_sequence(scans, times, times_column, cloud_topic,
                                     max_scans > 0 ? static_cast<std::size_t>(max_scans) : 0);
}

void add_slam3d_flags(CLI::App& app, Slam3dFlags& flags) {
  CLI::Option* scans =
      app.add_option("SCANS", flags.scans,
                     "A folder of scans (.pcd/.ply/.bin, optionally .gz/.bz2/.xz; natural name order), scan files in order, or a bag with a sensor_msgs/PointCloud2 topic (ROS 1 .bag, .mcap, rosbag2 .db3 or folder)")
          ->required();
  app.add_option("--out", flags.out, "Output directory: trajectory.tum, trajectory.kitti, map.ply, map.png, report.json");
  app.add_option("--preset", flags.preset,
                 "Starting configuration: default, or kitti (KITTI HDL-64E scans: 0.205 deg vertical-angle correction, no deskew)")
      ->capture_default_str();
  app.add_option("--config", flags.config, "YAML configuration (every key optional; --print-config lists them), applied after --preset");
  app.add_option("--set", flags.set, "Override one key: section.key=value (repeatable), after --config; the dedicated flags "
                 "(--metric, --front-end, --deskew, --threads, --remap-degenerate, --no-loop-closure) win over both");
  // CLI11 runs a flag's callback before it checks requirements: with --print-config, SCANS may be left out.
  app.add_flag_callback("--print-config", [&flags, scans] { flags.print_config = true; scans->required(false); },
                        "Print the configuration in effect (YAML) and exit unless SCANS are given");
  app.add_option("--mcap", flags.mcap, "Also write the trajectory, health, map and loop closures as MCAP for Foxglove");
  app.add_option("--save-map", flags.save_map,
                 "Also write the finished map (points with normals, keyframes with Scan Context, pose graph, sensor model) "
                 "for cairn localize3d --map (docs/formats.md, \"cairn 3D LiDAR map\")");
  app.add_option("--cloud-topic", flags.cloud_topic, "Bag input: the sensor_msgs/PointCloud2 topic (default: the only one)");
  app.add_option("--times", flags.times, "Table with one row per scan holding its time in seconds (e.g. KITTI times.txt)");
  app.add_option("--times-column", flags.times_column, "Column of --times holding the time (1-based)")->check(checks::count(10000))->capture_default_str();
  app.add_option("--imu", flags.imu,
                 "LiDAR-inertial SLAM with this IMU: an EuRoC imu0 (or mav0) folder or imu0/data.csv, a plain IMU CSV "
                 "(docs/formats.md), or a bag with one sensor_msgs/Imu topic");
  app.add_option("--imu-topic", flags.imu_topic, "LiDAR-inertial SLAM with this sensor_msgs/Imu topic of the scans' bag (instead of --imu)");
  app.add_option("--imu-calibration", flags.imu_calibration,
                 "The IMU's noise (EuRoC/Kalibr sensor.yaml; default: sensor.yaml beside the IMU's data, else EuRoC's ADIS16448)");
  app.add_option("--lidar-extrinsic", flags.lidar_extrinsic,
                 "A sensor.yaml whose T_BS is the LiDAR in the body (IMU) frame (default: lidar0/sensor.yaml beside the "
                 "IMU's folder, else identity)");
  app.add_option("--imu-time-offset", flags.imu_time_offset_s, "Seconds added to every IMU stamp to put it on the scans' clock")
      ->capture_default_str();
  app.add_option("--gnss", flags.gnss,
                 "GNSS fixes as position factors on the keyframes: a CSV (docs/formats.md, \"GNSS fixes\") or a bag with "
                 "sensor_msgs/NavSatFix, on the scans' clock");
  app.add_option("--gnss-topic", flags.gnss_topic,
                 "The sensor_msgs/NavSatFix topic (of the --gnss bag, or of the scans' bag without --gnss)");
  app.add_option("--gnss-lever-arm", flags.gnss_lever_arm_m, "The GNSS antenna in the LiDAR's frame, metres: X,Y,Z (default 0,0,0)")
      ->expected(3)
      ->delimiter(',');
  app.add_option("--ground-truth", flags.ground_truth,
                 "Ground-truth poses of the same scans (KITTI 3x4 per line, or TUM): print and report drift, RPE, ATE");
  app.add_option("--ground-truth-format", flags.ground_truth_format, "kitti or tum (default: from the file)");
  app.add_option("--metric", flags.metric, "ICP residual of the dense front end: point-to-plane (default) or point-to-point (KISS-ICP's)");
  app.add_option("--front-end", flags.front_end,
                 "auto (default: loam when the scans carry rings, dense otherwise; the kitti preset: dense), dense (every "
                 "point, KISS-ICP's way) or loam (edge and planar features per ring, Zhang & Singh 2014)");
  app.add_option("--deskew", flags.deskew, "off, point-times (default: with the files' per-point times) or azimuth");
  app.add_option("--threads", flags.threads, "Threads (0 = all; more than the machine has are clamped)")->transform(checks::threads())->capture_default_str();
  app.add_option("--map-voxel", flags.map_voxel_m, "Voxel of the written map, metres")->check(checks::in_range(0.001, 1000.0))->capture_default_str();
  app.add_option("--picture-size", flags.picture_px, "Longer side of map.png, pixels")->capture_default_str()->check(checks::whole_range(200, 20000));
  app.add_option("--max-scans", flags.max_scans, "Process only the first N scans")->check(checks::count(std::numeric_limits<long>::max()));
  app.add_flag("--remap-degenerate", flags.remap_degenerate,
               "Dense front end: solve degenerate directions from the motion prediction only (Zhang et al. 2016's "
               "remapping; the loam front end always does)");
  app.add_flag("--remove-dynamic", flags.remove_dynamic,
               "Leave points seen on something that moved out of map.ply and --save-map's map (free-space carving over "
               "the keyframes); they go to dynamic.ply");
  app.add_flag("--no-loop-closure", flags.no_loop_closure, "Odometry only: no Scan Context search, no pose graph");
  app.add_flag("--lenient", flags.lenient, "Skip scans that cannot be read (listed in the report) instead of stopping");
  app.add_flag("-q,--quiet", flags.quiet, "Print nothing on success");
  app.add_flag("--progress", flags.progress, "Progress as a line every 20 scans on stderr, also when stderr is not a terminal");
  app.add_flag("--overwrite", flags.overwrite,
               "Write into an --out directory that already holds files (those of the same names are replaced)");
  flags.command = &app;
}

}  // namespace cairn::cli
