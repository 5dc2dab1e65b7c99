#pragma once
/// \file
/// The real KITTI 00 key frames of ../shared/data/lidar3d/kitti00_keyframes (read its SOURCE.txt):
/// scan files, KITTI times and GNSS/INS poses, in key-frame order.

#include <cstddef>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "test_data.hpp"

namespace cairn::test {

inline constexpr const char* kKittiKeyFrames = "lidar3d/kitti00_keyframes";

struct KittiKeyFrames {
  std::vector<std::string> files;
  std::vector<double> times_s;
  std::vector<core::SE3> T_enu_velo;
};

/// The first `count` key frames (all by default) of keyframes.txt, with their lines of
/// poses_keyframes.txt.
inline KittiKeyFrames read_kitti_key_frames(std::size_t count = std::numeric_limits<std::size_t>::max()) {
  KittiKeyFrames k;
  const std::string folder = kKittiKeyFrames;
  std::ifstream list(data_path(folder + "/keyframes.txt"));
  std::ifstream poses(data_path(folder + "/poses_keyframes.txt"));
  std::string line;
  while (k.files.size() < count && std::getline(list, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    int index = 0, trajectory_line = 0, frame = 0;
    double time = 0.0;
    std::string file;
    fields >> index >> trajectory_line >> frame >> time >> file;
    k.files.push_back(data_path(folder + "/" + file).string());
    k.times_s.push_back(time);
    Eigen::Matrix<double, 3, 4> T;
    for (int i = 0; i < 12; ++i) poses >> T(i / 4, i % 4);
    k.T_enu_velo.push_back(core::SE3::from_matrix3x4(T));
  }
  return k;
}

}  // namespace cairn::test
