#pragma once
/// \file
/// The real KITTI 00 key frames of ../shared/data/lidar3d/kitti00_keyframes as the CLI tests use
/// them: a key frame's scan file and its GNSS/INS pose (poses_keyframes.txt, read here, not by
/// cairn), with Eigen only (the CLI tests do not link cairn's libraries).

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "test_data.hpp"

namespace cairn::test {

inline constexpr const char* kKittiKeyFrameFolder = "lidar3d/kitti00_keyframes";

/// Line `k` (0-based) of poses_keyframes.txt: the GNSS/INS pose of key frame k.
inline Eigen::Isometry3d kitti_reference_pose(int k) {
  std::ifstream in(data_path(std::string(kKittiKeyFrameFolder) + "/poses_keyframes.txt"));
  std::string line;
  for (int i = 0; i <= k; ++i) std::getline(in, line);
  std::istringstream fields(line);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 12; ++i) fields >> T.matrix()(i / 4, i % 4);
  return T;
}

inline std::filesystem::path kitti_key_frame(int k) {
  return data_path(std::string(kKittiKeyFrameFolder) + "/key_frames/key_frame_" + std::to_string(k) + ".pcd.xz");
}

}  // namespace cairn::test
