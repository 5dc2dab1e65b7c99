#pragma once
/// \file
/// The flags of `cairn vslam` (the run is cmd_vslam.cpp's).

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace cairn::cli {

struct VslamFlags {
  std::string folder;
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
  long feature_frame = -1;
  bool no_local_ba = false;
  bool mono = false;
  bool quiet = false;
  bool progress = false;
  bool overwrite = false;
};

/// Registers every flag of `cairn vslam` on `command`, storing into `flags`. FOLDER is required
/// unless --print-config is given.
void add_vslam_flags(CLI::App& command, VslamFlags& flags);

}  // namespace cairn::cli
