// An EuRoC-layout folder written from the synthetic world with an unrectified pair (the right
// camera turned by 1.5 degrees and shifted off the baseline, as real rigs are): the reader, the
// rectification and the tracking of the rectified left camera against the body ground truth.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cairn/eval/ape.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/image_file.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "synthetic_world.hpp"

namespace cairn::test {
namespace {

namespace fs = std::filesystem;

SurfaceTexture seeded(std::uint64_t seed) {
  SurfaceTexture t;
  t.seed = seed;
  return t;
}

void write_sensor_yaml(const fs::path& path, const StereoCamera& camera, const core::SE3& T_body_camera) {
  const Eigen::Matrix4d T = T_body_camera.matrix();
  std::ofstream out(path);
  out << "%YAML:1.0\nsensor_type: camera\ncomment: synthetic\nT_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int k = 0; k < 16; ++k) out << (k ? ", " : "") << (k % 4 == 0 && k ? "\n         " : "") << T(k / 4, k % 4);
  out << "]\nrate_hz: 10\nresolution: [" << camera.width << ", " << camera.height << "]\ncamera_model: pinhole\n"
      << "intrinsics: [" << camera.fx << ", " << camera.fy << ", " << camera.cx << ", " << camera.cy << "] #fu, fv, cu, cv\n"
      << "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n";
}

TEST(EurocSynthetic, RectifiesTheUnrectifiedPairAndTracksTheLeftCamera) {
  SyntheticWorld world;
  const double half = 1.0, ceiling = -1.0, floor_y = 1.3, z0 = -1.0, z1 = 14.0;
  const Eigen::Vector3d lower(-half, ceiling, z0);
  world.add_wall(0, lower, Eigen::Vector3d(-half, floor_y, z1), seeded(201), lower);
  world.add_wall(0, Eigen::Vector3d(half, ceiling, z0), Eigen::Vector3d(half, floor_y, z1), seeded(202), lower);
  world.add_wall(1, Eigen::Vector3d(-half, ceiling, z0), Eigen::Vector3d(half, ceiling, z1), seeded(203), lower);
  world.add_wall(1, Eigen::Vector3d(-half, floor_y, z0), Eigen::Vector3d(half, floor_y, z1), seeded(204), lower);
  world.add_wall(2, Eigen::Vector3d(-half, ceiling, z1), Eigen::Vector3d(half, floor_y, z1), seeded(205), Eigen::Vector3d(-half, ceiling, z1));
  const StereoCamera camera;
  // The body is the left camera turned (EuRoC's body is the IMU); the right camera: 0.12 m to
  // the right, 5 mm down, turned 1.5 degrees about y and 0.5 about x.
  const core::SE3 T_body_left(core::SO3::from_rpy(0.02, -0.01, 0.03), Eigen::Vector3d(0.05, -0.02, 0.01));
  const core::SE3 T_left_right(core::SO3::from_rpy(0.5 * 3.14159265358979 / 180.0, 1.5 * 3.14159265358979 / 180.0, 0.0),
                               Eigen::Vector3d(camera.baseline_m, 0.005, 0.0));
  const fs::path dir = fs::temp_directory_path() / "cairn_test_euroc_synthetic" / "mav0";
  fs::remove_all(dir.parent_path());
  for (const char* cam : {"cam0", "cam1"}) fs::create_directories(dir / cam / "data");
  fs::create_directories(dir / "state_groundtruth_estimate0");
  write_sensor_yaml(dir / "cam0" / "sensor.yaml", camera, T_body_left);
  write_sensor_yaml(dir / "cam1" / "sensor.yaml", camera, T_body_left * T_left_right);
  const std::vector<core::SE3> poses = walk(Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.0, 0.0, 8.0), 0.15, 0.0, 0.1, 0.2);
  std::ofstream csv0(dir / "cam0" / "data.csv"), csv1(dir / "cam1" / "data.csv");
  csv0 << "#timestamp [ns],filename\n";
  csv1 << "#timestamp [ns],filename\n";
  io::Trajectory body;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const std::int64_t ns = 1403636579763555584LL + static_cast<std::int64_t>(k) * 100'000'000LL;
    const std::string name = std::to_string(ns) + ".png";
    std::ofstream(dir / "cam0" / "data" / name, std::ios::binary) << vision::encode_png(world.render(poses[k], camera));
    std::ofstream(dir / "cam1" / "data" / name, std::ios::binary) << vision::encode_png(world.render(poses[k] * T_left_right, camera));
    csv0 << ns << "," << name << "\n";
    csv1 << ns << "," << name << "\n";
    body.stamps.push_back(core::Timestamp::from_nanoseconds(ns));
    body.poses.push_back(poses[k] * T_body_left.inverse());  // T_world_body
  }
  csv0.close();
  csv1.close();
  io::write_euroc((dir / "state_groundtruth_estimate0" / "data.csv").string(), body);

  EXPECT_EQ(io::detect_image_layout(dir.parent_path().string()), "euroc");
  const io::ImageSequence seq = io::read_euroc_stereo(dir.parent_path().string());
  ASSERT_EQ(seq.frames.size(), poses.size());
  ASSERT_TRUE(seq.rig.has_value());
  ASSERT_TRUE(seq.ground_truth.has_value());
  EXPECT_NEAR((seq.rig->T_body_left.inverse() * seq.rig->T_body_right).translation().x(), camera.baseline_m, 1e-6);
  const vision::StereoRectifier rectifier(*seq.rig, camera.width, camera.height);
  std::printf("rectified: fx %.2f, cx %.2f, cy %.2f, baseline %.4f m\n", rectifier.rectified().fx, rectifier.rectified().cx,
              rectifier.rectified().cy, rectifier.rectified().baseline_m);
  // The rig's baseline is 0.12 m along x and 5 mm along y: the rectified baseline is their norm.
  EXPECT_NEAR(rectifier.rectified().baseline_m, std::hypot(camera.baseline_m, 0.005), 1e-6);
  vslam::VisualSlam slam(rectifier.rectified(), io::SequenceKind::kStereo);
  std::size_t tracked = 0;
  for (const io::ImageFrame& frame : seq.frames) {
    cv::Mat left, right;
    rectifier.rectify(vision::read_gray_image(frame.image), vision::read_gray_image(frame.right_image), left, right);
    tracked += slam.add_stereo(frame.time, left, right).tracked ? 1 : 0;
  }
  EXPECT_EQ(tracked, seq.frames.size());
  // The ground truth of the rectified left camera: body * T_body_left * T_left_rectified.
  io::Trajectory truth = *seq.ground_truth, estimate;
  for (core::SE3& T : truth.poses) T = T * seq.rig->T_body_left * rectifier.T_left_rectified();
  estimate.stamps = truth.stamps;
  estimate.poses = slam.trajectory();
  eval::ApeOptions se3;
  se3.alignment.method = eval::AlignmentMethod::kSE3;
  const eval::ApeResult ape = eval::evaluate_ape(truth, estimate, se3);
  ASSERT_TRUE(ape.outcome.ok()) << ape.outcome.message;
  std::printf("EuRoC layout, %zu frames over 8 m: ATE (SE(3)-aligned) %.4f m RMSE, max %.4f m\n", seq.frames.size(), ape.statistics.rmse,
              ape.statistics.max);
  EXPECT_LT(ape.statistics.rmse, 0.05);
  fs::remove_all(dir.parent_path());
}

TEST(EurocSynthetic, BadSensorFilesNameTheLine) {
  const fs::path dir = fs::temp_directory_path() / "cairn_test_euroc_bad";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path yaml = dir / "sensor.yaml";
  std::ofstream(yaml) << "%YAML:1.0\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0]\n"
                         "intrinsics: [458.6, 457.3, 367.2, 248.4]\n";
  try {
    io::read_euroc_camera(yaml.string(), nullptr);
    ADD_FAILURE() << "15 numbers accepted";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.line(), 2u) << e.what();
    EXPECT_NE(std::string(e.what()).find("16 numbers"), std::string::npos) << e.what();
  }
  std::ofstream(yaml) << "T_BS:\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\nintrinsics: [458.6, nan, 367.2, 248.4]\n";
  EXPECT_THROW(io::read_euroc_camera(yaml.string(), nullptr), io::ParseError);
  std::ofstream(yaml) << "T_BS:\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\ncamera_model: omni\nintrinsics: [1, 1, 1, 1]\n";
  try {
    io::read_euroc_camera(yaml.string(), nullptr);
    ADD_FAILURE() << "omni accepted";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.line(), 3u) << e.what();
  }
  std::ofstream(yaml) << "T_BS:\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n";
  EXPECT_THROW(io::read_euroc_camera(yaml.string(), nullptr), io::ParseError);  // no intrinsics
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cairn::test
