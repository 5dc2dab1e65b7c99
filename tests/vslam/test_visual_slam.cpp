// Stereo visual SLAM on the 51 real KITTI frames against their ground truth.

#include <gtest/gtest.h>

#include <cstdio>

#include "cairn/eval/ape.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "test_data.hpp"

namespace cairn::vslam {
namespace {

TEST(VisualSlamKitti, TracksEveryFrameAndKeepsTheShapeOfTheGroundTruth) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const io::ImageSequence seq = io::read_kitti_stereo(test::data_path("visual/kitti_extract_seq2").string());
  VisualSlam slam(seq.calibration, seq.kind);
  std::size_t tracked = 0, keyframes = 0;
  for (const io::ImageFrame& frame : seq.frames) {
    const FrameResult r = slam.add_stereo(frame.time, vision::read_gray_image(frame.image), vision::read_gray_image(frame.right_image));
    tracked += r.tracked ? 1 : 0;
    keyframes += r.keyframe ? 1 : 0;
    if (r.frame > 0) {
      EXPECT_GT(r.inliers, 50) << "frame " << r.frame;
    }
  }
  EXPECT_EQ(tracked, seq.frames.size());
  io::Trajectory estimate;
  estimate.stamps = seq.ground_truth->stamps;
  estimate.poses = slam.trajectory();
  // Shape: Sim(3)-aligned ATE. Scale: the SE(3)-aligned one. (This extract's motion is 3.6 %
  // shorter than its stereo calibration measures; docs/vslam.md.)
  eval::ApeOptions sim3;
  sim3.alignment.method = eval::AlignmentMethod::kSim3;
  const eval::ApeResult shape = eval::evaluate_ape(*seq.ground_truth, estimate, sim3);
  eval::ApeOptions se3;
  se3.alignment.method = eval::AlignmentMethod::kSE3;
  const eval::ApeResult rigid = eval::evaluate_ape(*seq.ground_truth, estimate, se3);
  eval::RpeOptions rpe;
  rpe.relation = eval::PoseRelation::kRotationAngleDeg;
  const eval::RpeResult rotation = eval::evaluate_rpe(*seq.ground_truth, estimate, rpe);
  ASSERT_TRUE(shape.outcome.ok() && rigid.outcome.ok() && rotation.outcome.ok());
  std::printf("51 KITTI frames: %zu keyframes, %zu map points; ATE Sim(3)-aligned %.3f m (scale %.4f), SE(3)-aligned %.3f m; "
              "RPE rotation %.4f deg RMSE\n",
              keyframes, slam.map_points().size(), shape.statistics.rmse, shape.alignment.scale, rigid.statistics.rmse,
              rotation.statistics.rmse);
  EXPECT_LT(shape.statistics.rmse, 0.10);
  EXPECT_LT(rotation.statistics.rmse, 0.2);
  EXPECT_LT(rigid.statistics.rmse, 1.0);
}

TEST(VisualSlam, RefusesBadCalibrationsAndImages) {
  io::CameraCalibration camera;
  EXPECT_THROW(VisualSlam(camera, io::SequenceKind::kStereo), std::invalid_argument);  // fx = 0
  camera.fx = camera.fy = 500.0;
  EXPECT_THROW(VisualSlam(camera, io::SequenceKind::kStereo), std::invalid_argument);  // no baseline
  EXPECT_THROW(VisualSlam(camera, io::SequenceKind::kMonocular), std::invalid_argument);
  camera.baseline_m = 0.1;
  VisualSlam slam(camera, io::SequenceKind::kStereo);
  const cv::Mat a(100, 200, CV_8UC1, cv::Scalar(0)), b(100, 201, CV_8UC1, cv::Scalar(0)), c(100, 200, CV_8UC3);
  EXPECT_THROW(slam.add_stereo(core::Timestamp(), a, b), std::invalid_argument);
  EXPECT_THROW(slam.add_stereo(core::Timestamp(), a, c), std::invalid_argument);
  EXPECT_THROW(slam.add_rgbd(core::Timestamp(), a, a), std::logic_error);
  // A blank pair: no features, no map; said, not crashed.
  const FrameResult r = slam.add_stereo(core::Timestamp(), a, a);
  EXPECT_FALSE(r.tracked);
  EXPECT_EQ(r.health, TrackingHealth::kLost);
  EXPECT_NE(r.note.find("too few"), std::string::npos) << r.note;
}

}  // namespace
}  // namespace cairn::vslam
