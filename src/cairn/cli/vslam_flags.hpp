#pragma once
/// \file
/// The flags of `cairn vslam` (the run is cmd_vslam.cpp's).

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace cairn::cli {

struct VslamFlags {
  std::string folder;
  std::string mcap;
  std::string out;
  std::string camera;
  std::string calib;
  std::string ground_truth;
  std::string vocabulary;
  std::string config;
  std::vector<std::string> set;
  bool print_config = false;
  int features = 0;
  long max_frames = 0;
  long first_frame = 0;
  std::string save_map;    // write the main map for --localize-in (vslam/map_file.hpp)
  std::string localize_in; // localise in a saved map without changing it
  long feature_frame = -1;
  bool no_local_ba = false;
  bool mono = false;
  bool quiet = false;
  bool progress = false;
  bool overwrite = false;
  // A bag input (cairn vslam BAG, vslam/bag_images.hpp): the topics (empty: chosen from the bag)
  // and the depth scale (0: REP 118's). Given with a folder, they are a usage error.
  std::string left_topic;
  std::string right_topic;
  std::string image_topic;
  std::string depth_topic;
  std::string camera_info_topic;
  std::string right_camera_info_topic;
  double depth_scale = 0.0;
  // Visual-inertial (vslam/inertial_input.hpp): the IMU as a file or folder, or a topic of the
  // images' bag; its noise, the camera's extrinsic and the IMU's clock offset.
  std::string imu;
  std::string imu_topic;
  std::string imu_calibration;
  std::string camera_extrinsic;
  double imu_time_offset_s = 0.0;
  CLI::App* command = nullptr;  // to tell a given --imu-time-offset from its default
  bool uses_imu() const { return !imu.empty() || !imu_topic.empty(); }
};

/// Registers every flag of `cairn vslam` on `command`, storing into `flags`. FOLDER (a dataset
/// folder or a bag) is required unless --print-config is given.
void add_vslam_flags(CLI::App& command, VslamFlags& flags);

}  // namespace cairn::cli
