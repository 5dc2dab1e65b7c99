#pragma once
/// \file
/// The flags of `cairn slam3d` (cmd_slam3d.cpp): their definitions, the options they stand for
/// (the preset, a YAML file and --set assignments through lidar3d/config.hpp, then the dedicated
/// flags) and the IMU they name (lidar3d/inertial_input.hpp).

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/lidar3d/config.hpp"
#include "cairn/lidar3d/inertial_input.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"

namespace cairn::cli {

struct Slam3dFlags {
  std::vector<std::string> scans;
  std::string out;
  std::string preset = "default";
  std::string config;
  std::vector<std::string> set;
  std::string times;
  std::string cloud_topic;
  std::string mcap;
  std::string save_map;
  int times_column = 1;
  std::string ground_truth;
  std::string ground_truth_format;
  std::string metric;
  std::string deskew;
  std::string front_end;
  std::string imu;
  std::string imu_topic;
  std::string imu_calibration;
  std::string lidar_extrinsic;
  double imu_time_offset_s = 0.0;
  std::string gnss;
  std::string gnss_topic;
  std::vector<double> gnss_lever_arm_m;  ///< empty, or x, y, z: the antenna in the LiDAR's frame
  long max_scans = 0;
  int threads = 0;
  double map_voxel_m = 0.25;
  int picture_px = 1600;
  bool lenient = false, no_loop_closure = false, remap_degenerate = false, remove_dynamic = false;
  bool quiet = false, progress = false, overwrite = false, print_config = false;
  const CLI::App* command = nullptr;  // which flags were given

  /// --imu or --imu-topic given.
  bool uses_imu() const { return !imu.empty() || !imu_topic.empty(); }
  /// --gnss or --gnss-topic given.
  bool uses_gnss() const { return !gnss.empty() || !gnss_topic.empty(); }
};

/// The scans SCANS name (the first `max_scans`, 0 = all) and their times: scan files with
/// `times` (a table, `times_column` 1-based) or 0.1 s apart, or a bag's PointCloud2 topic
/// (`cloud_topic`, default the only one) with its header stamps. Throws UsageError for flags that
/// do not go together (--times with a bag, --cloud-topic with files).
lidar3d::ScanSequence read_scan_sequence(const std::vector<std::string>& scans, const std::string& times,
                                         int times_column, const std::string& cloud_topic, long max_scans);

/// Defines the flags of `app` into `flags` (which must outlive it).
void add_slam3d_flags(CLI::App& app, Slam3dFlags& flags);

/// The preset, --config, each --set, then the dedicated flags, which win; with an IMU, then
/// lidar3d::prepare_for_inertial (`*remap_forced`, when given, says whether it changed anything).
/// Throws UsageError for a bad --set or invalid options, io::ParseError for a bad --config file,
/// std::invalid_argument for a bad preset or flag value.
lidar3d::SlamConfiguration slam3d_options(const Slam3dFlags& flags, bool* remap_forced = nullptr);

/// The GNSS fixes the flags name (none without --gnss and --gnss-topic): --gnss a CSV
/// (docs/formats.md, "GNSS fixes") or a bag, --gnss-topic its NavSatFix topic (of the --gnss bag,
/// else of the scans' bag). Throws UsageError for flags that do not go together (--gnss-topic
/// with a CSV or without any bag, --gnss-lever-arm without GNSS), io::ParseError for a bad file.
/// The reader's notes (dropped fixes, warnings) go to `notes`.
std::vector<gnss::GnssFix> read_gnss_fixes(const Slam3dFlags& flags, std::vector<std::string>* notes);

/// The IMU the flags name (none without --imu and --imu-topic). Throws UsageError for flags that do
/// not go together: --imu-topic with scan files or with --imu, and --imu-calibration,
/// --lidar-extrinsic or --imu-time-offset without an IMU.
std::optional<lidar3d::InertialInputRequest> imu_request(const Slam3dFlags& flags);

}  // namespace cairn::cli
