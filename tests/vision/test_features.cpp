// ORB features, stereo matching and image reading on a real KITTI pair; stereo disparities are
// checked against OpenCV's semi-global matcher, an independent estimator on the same images.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>

#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/image_file.hpp"
#include "test_data.hpp"

namespace cairn::vision {
namespace {

namespace fs = std::filesystem;
const char* kKitti = "visual/kitti_extract_seq2";

TEST(Orb, SpreadsTheWantedNumberOfFeaturesOverTheImageAndTheLevels) {
  CAIRN_REQUIRE_DATA(kKitti);
  const cv::Mat image = read_gray_image(test::data_path(std::string(kKitti) + "/image_l/000000.png").string());
  ASSERT_EQ(image.cols, 1241);
  const OrbExtractor orb;  // 2000 features, 8 levels, 1.2
  const Features f = orb.extract(image);
  EXPECT_GE(f.keypoints.size(), 1900u);
  EXPECT_LE(f.keypoints.size(), 2000u);
  ASSERT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
  // Levels: shares proportional to the area, so level 0 holds the most and every level some.
  std::vector<int> per_level(8, 0);
  for (const auto& kp : f.keypoints) ++per_level[static_cast<std::size_t>(kp.octave)];
  for (int l = 0; l < 8; ++l) EXPECT_GT(per_level[static_cast<std::size_t>(l)], 50) << "level " << l;
  EXPECT_GT(per_level[0], per_level[7]);
  // Spread: every cell of a 4 x 3 partition of the image holds at least 2 % of the features
  // (plain cv::ORB keeps the strongest corners wherever they are).
  int cells[3][4] = {};
  for (const auto& kp : f.keypoints) {
    ++cells[std::min(2, static_cast<int>(kp.pt.y / (static_cast<float>(image.rows) / 3.0f)))]
           [std::min(3, static_cast<int>(kp.pt.x / (static_cast<float>(image.cols) / 4.0f)))];
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) EXPECT_GT(cells[r][c], static_cast<int>(f.keypoints.size()) / 50) << "cell " << r << "," << c;
  }
  // Keypoints keep ORB-SLAM's border: none within 19 pixels of the level's edge.
  for (const auto& kp : f.keypoints) {
    const double s = f.scales[static_cast<std::size_t>(kp.octave)];
    EXPECT_GE(static_cast<double>(kp.pt.x) / s, 18.5);
    EXPECT_LT(static_cast<double>(kp.pt.x) / s, f.pyramid[static_cast<std::size_t>(kp.octave)].cols - 18.5);
  }
}

TEST(Orb, DescriptorsFollowTheOrientation) {
  CAIRN_REQUIRE_DATA(kKitti);
  const cv::Mat image = read_gray_image(test::data_path(std::string(kKitti) + "/image_l/000000.png").string());
  // The same image rotated by 90 degrees: a feature and its rotated twin should match (steered
  // BRIEF); matched pairs must lie where the rotation puts them.
  cv::Mat rotated;
  cv::rotate(image, rotated, cv::ROTATE_90_CLOCKWISE);
  const OrbExtractor orb;
  const Features a = orb.extract(image), b = orb.extract(rotated);
  int good = 0, tried = 0;
  for (std::size_t i = 0; i < a.keypoints.size(); i += 10) {
    int best = 256, best_j = -1;
    for (std::size_t j = 0; j < b.keypoints.size(); ++j) {
      const int d = descriptor_distance(a.descriptors.ptr(static_cast<int>(i)), b.descriptors.ptr(static_cast<int>(j)));
      if (d < best) {
        best = d;
        best_j = static_cast<int>(j);
      }
    }
    if (best > 40) continue;
    ++tried;
    // (x, y) -> (rows - 1 - y, x) under a clockwise quarter turn.
    const cv::Point2f expected(static_cast<float>(image.rows - 1) - a.keypoints[i].pt.y, a.keypoints[i].pt.x);
    if (cv::norm(b.keypoints[static_cast<std::size_t>(best_j)].pt - expected) < 3.0) ++good;
  }
  ASSERT_GT(tried, 40);
  EXPECT_GT(good, tried * 8 / 10) << good << " of " << tried;
}

TEST(Stereo, DisparitiesAgreeWithSemiGlobalMatching) {
  CAIRN_REQUIRE_DATA(kKitti);
  const io::ImageSequence seq = io::read_kitti_stereo(test::data_path(kKitti).string());
  const cv::Mat left = read_gray_image(seq.frames[10].image), right = read_gray_image(seq.frames[10].right_image);
  const OrbExtractor orb;
  const Features fl = orb.extract(left), fr = orb.extract(right);
  const StereoMatches m = match_stereo(fl, fr, seq.calibration);
  EXPECT_GT(m.matched, 700u);
  const cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(0, 128, 5, 8 * 25, 32 * 25, 1, 0, 10, 100, 2);
  cv::Mat disparity;
  sgbm->compute(left, right, disparity);
  std::vector<double> differences;
  for (std::size_t i = 0; i < fl.keypoints.size(); ++i) {
    if (m.depth_m[i] <= 0 || fl.keypoints[i].octave > 1) continue;
    const short d = disparity.at<short>(cvRound(fl.keypoints[i].pt.y), cvRound(fl.keypoints[i].pt.x));
    if (d <= 0) continue;
    const double ours = static_cast<double>(fl.keypoints[i].pt.x) - m.u_right[i];
    EXPECT_NEAR(m.depth_m[i], seq.calibration.fx * seq.calibration.baseline_m / ours, 1e-9);
    differences.push_back(std::abs(ours - d / 16.0));
  }
  ASSERT_GT(differences.size(), 150u);
  std::sort(differences.begin(), differences.end());
  const double median = differences[differences.size() / 2];
  const double q90 = differences[differences.size() * 9 / 10];
  std::printf("stereo: %zu matches; |ours - SGBM| on levels 0-1: median %.3f px, 90 %% %.3f px (%zu compared)\n", m.matched, median,
              q90, differences.size());
  EXPECT_LT(median, 0.5);
  EXPECT_LT(q90, 2.0);
}

TEST(Images, UnreadableImagesGiveClearErrors) {
  const fs::path dir = fs::temp_directory_path() / "cairn_test_images";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path text = dir / "text.png";
  std::ofstream(text) << "this is not a PNG\n";
  EXPECT_THROW(read_gray_image(text.string()), io::ParseError);
  try {
    read_gray_image((dir / "missing.png").string());
    ADD_FAILURE();
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png: cannot open image"), std::string::npos) << e.what();
  }
  // A real PNG cut in half, and one of the wrong size.
  const cv::Mat image(40, 60, CV_8UC1, cv::Scalar(100));
  const std::string png = encode_png(image);
  const fs::path cut = dir / "cut.png";
  std::ofstream(cut, std::ios::binary) << png.substr(0, png.size() / 2);
  EXPECT_THROW(read_gray_image(cut.string()), io::ParseError);
  const fs::path whole = dir / "whole.png";
  std::ofstream(whole, std::ios::binary) << png;
  EXPECT_EQ(read_gray_image(whole.string()).cols, 60);
  try {
    read_gray_image(whole.string(), 61, 40);
    ADD_FAILURE();
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("is 60 x 40 pixels, expected 61 x 40"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_depth_image(whole.string()), io::ParseError);  // 8-bit, not a depth image
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cairn::vision
