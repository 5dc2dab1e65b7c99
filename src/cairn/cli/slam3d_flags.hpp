#pragma once
/// \file
/// The flags of `cairn slam3d` (cmd_slam3d.cpp): their definitions and the options they stand for
/// (the preset, a YAML file and --set assignments through lidar3d/config.hpp, then the dedicated
/// flags).

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cairn/lidar3d/slam.hpp"

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
  bool quiet = false, progress = false, overwrite = false, print_config = false;
  const CLI::App* command = nullptr;  // which flags were given
};

/// Defines the flags of `app` into `flags` (which must outlive it).
void add_slam3d_flags(CLI::App& app, Slam3dFlags& flags);

/// The preset, --config, each --set, then the dedicated flags, which win. Throws UsageError for a
/// bad --set or invalid options, io::ParseError for a bad --config file, std::invalid_argument for
/// a bad preset or flag value.
lidar3d::LidarSlamOptions slam3d_options(const Slam3dFlags& flags);

}  // namespace cairn::cli
