#pragma once
// What the TUM fr1/desk tests share (test_visual_slam.cpp, test_vslam_map_reuse.cpp): the
// vocabulary trained on the KITTI images (never on TUM's), TUM's published fr1 camera and
// ORB-SLAM2's TUM settings, and the ground-truth pose nearest a stamp.

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "test_data.hpp"

namespace cairn::vslam::test_tum {

/// k=10, L=4 over the 51 KITTI left images in name order (as `cairn vocabulary train image_l/`).
inline std::shared_ptr<const vision::Vocabulary> kitti_vocabulary() {
  std::vector<cv::Mat> training;
  const vision::OrbExtractor kitti_orb(vision::OrbOptions{1000});
  std::vector<std::string> images;
  for (const auto& entry : std::filesystem::directory_iterator(test::data_path("visual/kitti_extract_seq2/image_l"))) {
    images.push_back(entry.path().string());
  }
  std::sort(images.begin(), images.end());
  for (const std::string& image : images) training.push_back(kitti_orb.extract(vision::read_gray_image(image)).descriptors);
  vision::VocabularyOptions vo;
  vo.branching = 10;
  vo.depth = 4;
  return std::make_shared<const vision::Vocabulary>(vision::Vocabulary::train(training, vo));
}

/// TUM's published fr1 colour camera (as ORB-SLAM2's TUM1.yaml, bf = 40).
inline io::CameraCalibration fr1_camera() {
  io::CameraCalibration camera{517.306408, 516.469215, 318.643040, 255.313989, 0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  camera.depth_units_per_m = 5000.0;
  camera.virtual_baseline_m = 40.0 / camera.fx;
  return camera;
}

/// ORB-SLAM2's TUM settings: 1000 features, ThDepth 40.
inline VisualSlamOptions rgbd_options(std::shared_ptr<const vision::Vocabulary> vocabulary) {
  VisualSlamOptions options;
  options.orb.features = 1000;
  options.close_depth_baselines = 40.0;
  options.vocabulary = std::move(vocabulary);
  return options;
}

/// The ground-truth pose nearest in time (TUM's mocap runs at 100 Hz).
inline core::SE3 nearest(const io::Trajectory& truth, core::Timestamp t) {
  const auto it = std::lower_bound(truth.stamps.begin(), truth.stamps.end(), t);
  std::size_t i = static_cast<std::size_t>(it - truth.stamps.begin());
  if (i == truth.stamps.size() || (i > 0 && (t.seconds() - truth.stamps[i - 1].seconds()) < (truth.stamps[i].seconds() - t.seconds()))) --i;
  return truth.poses[i];
}

}  // namespace cairn::vslam::test_tum
