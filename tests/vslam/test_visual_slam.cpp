// Stereo visual SLAM on the 51 real KITTI frames against their ground truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "cairn/eval/ape.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "test_data.hpp"
#include "tum_desk.hpp"

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

// Triangulation between keyframes (off by default): more points, and the per-frame rotation
// error it lowers (measured 0.096 -> 0.045 degrees; docs/vslam.md says what it costs).
TEST(VisualSlamKitti, TriangulationBetweenKeyframesAddsPointsAndSteadiesRotation) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const io::ImageSequence seq = io::read_kitti_stereo(test::data_path("visual/kitti_extract_seq2").string());
  std::size_t points[2] = {0, 0};
  double rotation[2] = {0.0, 0.0};
  for (const int keyframes : {0, 10}) {
    VisualSlamOptions options;
    options.triangulation_keyframes = keyframes;
    VisualSlam slam(seq.calibration, seq.kind, options);
    std::size_t tracked = 0;
    for (const io::ImageFrame& frame : seq.frames) {
      tracked += slam.add_stereo(frame.time, vision::read_gray_image(frame.image), vision::read_gray_image(frame.right_image)).tracked ? 1 : 0;
    }
    EXPECT_EQ(tracked, seq.frames.size());
    io::Trajectory estimate;
    estimate.stamps = seq.ground_truth->stamps;
    estimate.poses = slam.trajectory();
    eval::RpeOptions rpe;
    rpe.relation = eval::PoseRelation::kRotationAngleDeg;
    const eval::RpeResult r = eval::evaluate_rpe(*seq.ground_truth, estimate, rpe);
    ASSERT_TRUE(r.outcome.ok());
    const std::size_t i = keyframes == 0 ? 0 : 1;
    points[i] = slam.summary().map_points;
    rotation[i] = r.statistics.rmse;
  }
  std::printf("map points created: %zu without, %zu with triangulation; RPE rotation %.4f -> %.4f deg\n", points[0], points[1],
              rotation[0], rotation[1]);
  EXPECT_GT(points[1], points[0] * 3 / 2);
  EXPECT_LT(rotation[1], 0.08);
}

// Monocular on the KITTI left images: two-view initialisation (homography or essential matrix),
// then tracking at an unobservable scale: judged after Sim(3) alignment over the tracked frames.
TEST(VisualSlamKitti, MonocularInitialisesAndTracksUpToScale) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const io::ImageSequence seq = io::read_kitti_stereo(test::data_path("visual/kitti_extract_seq2").string());
  VisualSlam slam(seq.calibration, io::SequenceKind::kMonocular);
  std::vector<FrameResult> results;
  std::optional<std::size_t> initialised;
  for (const io::ImageFrame& frame : seq.frames) {
    results.push_back(slam.add_monocular(frame.time, vision::read_gray_image(frame.image)));
    if (results.back().tracked && !initialised) {
      initialised = results.back().frame;
      std::printf("%s\n", results.back().note.c_str());
    }
  }
  ASSERT_TRUE(initialised.has_value()) << "never initialised";
  io::Trajectory tracked, truth;
  const std::vector<core::SE3> poses = slam.trajectory();
  for (std::size_t k = 0; k < results.size(); ++k) {
    if (!results[k].tracked) continue;
    tracked.poses.push_back(poses[k]);
    truth.poses.push_back(seq.ground_truth->poses[k]);
  }
  eval::ApeOptions sim3;
  sim3.alignment.method = eval::AlignmentMethod::kSim3;
  const eval::ApeResult ape = eval::evaluate_ape(truth, tracked, sim3);
  ASSERT_TRUE(ape.outcome.ok()) << ape.outcome.message;
  std::printf("monocular: initialised at frame %zu, %zu of %zu frames tracked, ATE Sim(3)-aligned %.3f m (scale %.2f)\n", *initialised,
              tracked.size(), results.size(), ape.statistics.rmse, ape.alignment.scale);
  EXPECT_GE(tracked.size(), 25u);
  EXPECT_LT(ape.statistics.rmse, 0.3);
}

TEST(VisualSlam, RefusesBadCalibrationsAndImages) {
  io::CameraCalibration camera;
  EXPECT_THROW(VisualSlam(camera, io::SequenceKind::kStereo), std::invalid_argument);  // fx = 0
  camera.fx = camera.fy = 500.0;
  EXPECT_THROW(VisualSlam(camera, io::SequenceKind::kStereo), std::invalid_argument);  // no baseline
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


// RGB-D on TUM fr1/desk (every 4th frame) with a vocabulary trained on the KITTI images (never
// on TUM's): place recognition may close the desk loop and relocalise after fast turns, but every
// accepted loop must join keyframes whose true poses see the same place, and every
// relocalisation must land where the ground truth is (after aligning the tracked trajectory).
void run_tum_place_recognition(bool bow_restricted) {
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/image_l");
  auto vocabulary = test_tum::kitti_vocabulary();
  const io::ImageSequence seq = io::read_tum_rgbd(test::data_path("visual/tum_fr1_desk_every4th").string());
  const io::CameraCalibration camera = test_tum::fr1_camera();
  VisualSlamOptions options = test_tum::rgbd_options(vocabulary);
  options.bow_restricted_matching = bow_restricted;
  VisualSlam slam(camera, io::SequenceKind::kRgbd, options);
  std::vector<FrameResult> results;
  for (const io::ImageFrame& frame : seq.frames) {
    results.push_back(slam.add_rgbd(frame.time, vision::read_gray_image(frame.image), vision::read_depth_image(frame.depth_image)));
    results.back().keypoints.clear();
  }
  const VisualSlamSummary& s = slam.summary();
  std::printf("TUM fr1/desk (%s matching), %zu frames: %zu ok, %zu degraded, %zu lost; %zu relocalisations; %zu loop queries, %zu candidates "
              "verified, %zu loops accepted; vocabulary %s\n",
              bow_restricted ? "bag-of-words-node" : "brute-force", s.frames, s.frames_ok, s.frames_degraded, s.frames_lost, s.relocalisations, s.loop_queries, s.loops.size(),
              s.loops_accepted, vocabulary->description().c_str());
  const io::Trajectory& truth = *seq.ground_truth;
  std::size_t returns_verified = 0;
  for (const LoopRecord& loop : s.loops) {
    const core::SE3 a = test_tum::nearest(truth, seq.frames[loop.frame].time), b = test_tum::nearest(truth, seq.frames[loop.candidate_frame].time);
    const core::SE3 d = a.inverse() * b;
    const double metres = d.translation().norm();
    const double degrees = Eigen::AngleAxisd(d.rotation_matrix()).angle() * 180.0 / 3.14159265358979323846;
    std::printf("  loop candidate frame %zu -> %zu: score %.3f, %d PnP inliers, %d matches, %s (%s); true offset %.2f m, %.1f deg\n",
                loop.frame, loop.candidate_frame, loop.score, loop.pnp_inliers, loop.matches, loop.decision.c_str(), loop.reason.c_str(),
                metres, degrees);
    if (loop.decision == "accepted" || loop.decision == "revisit") {
      EXPECT_LT(metres, 1.0) << "a loop joined places " << metres << " m apart";
      EXPECT_LT(degrees, 45.0);
    }
    // The return of SOURCE.txt (frames 87..125 of rgb.txt come back to views of 12..43, about
    // 14 s later), recognised and verified: as a loop, or as a revisit when tracking the local
    // map had already joined it (decision "revisit"; nothing left to correct). Not a merge
    // proposed by recency (score -1: the keyframes tracked just before a new segment).
    const double apart_s = seq.frames[loop.frame].time.seconds() - seq.frames[loop.candidate_frame].time.seconds();
    if ((loop.decision == "accepted" || loop.decision == "revisit") && loop.score >= 0.0 && apart_s > 5.0 && metres < 0.5) ++returns_verified;
  }
  std::printf("the desk's return recognised and verified %zu times (loops or revisits > 5 s apart within 0.5 m)\n", returns_verified);
  EXPECT_GE(returns_verified, 1u) << "the revisit of the desk was neither closed as a loop nor verified as a revisit";
  // Relocalised poses: after SE(3)-aligning the tracked frames on the ground truth, within 0.3 m.
  // Frames of the main map (segments merged into the first keyframe's); the frames of other
  // segments live in frames of their own.
  io::Trajectory tracked;
  const std::vector<core::SE3> poses = slam.trajectory();
  const std::vector<int> segments = slam.frame_segments();
  std::size_t in_other_maps = 0;
  for (std::size_t k = 0; k < results.size(); ++k) {
    if (!results[k].tracked) continue;
    if (segments[k] != slam.main_segment()) {
      ++in_other_maps;
      continue;
    }
    tracked.stamps.push_back(results[k].time);
    tracked.poses.push_back(poses[k]);
  }
  eval::ApeOptions se3;
  se3.alignment.method = eval::AlignmentMethod::kSE3;
  se3.association.max_time_difference_s = 0.02;
  const eval::ApeResult ape = eval::evaluate_ape(truth, tracked, se3);
  ASSERT_TRUE(ape.outcome.ok()) << ape.outcome.message;
  std::printf("ATE (SE(3)-aligned) over the %zu frames of the main map: %.4f m RMSE, max %.3f m; %zu tracked frames in %zu other "
              "map segments (%zu started, %zu merged)\n",
              tracked.size(), ape.statistics.rmse, ape.statistics.max, in_other_maps, s.maps_started - s.maps_merged, s.maps_started,
              s.maps_merged);
  // Coverage and the accuracy target (ATE <= 0.025 m at every 4th frame). Measured
  // 2026-11-25 (docs/vslam.md): 147 of 149 frames in the main map at 0.0165 m (brute force) and
  // 0.0169 m (vocabulary nodes), 0.0163 m and 0.0172 m once a merge joins the segments before
  // its global bundle adjustment (second session); before the image-alignment start and the fusion of duplicates
  // the main map held 60 frames, so these bounds are what those two changes brought.
  EXPECT_GT(tracked.size() + in_other_maps, seq.frames.size() * 3 / 4);
  EXPECT_GE(tracked.size(), seq.frames.size() * 9 / 10);
  EXPECT_LE(ape.statistics.rmse, 0.025);
  EXPECT_LT(ape.statistics.max, 0.5) << "a tracked or relocalised pose far from the truth";
}

TEST(VisualSlamTum, PlaceRecognitionNeverJoinsDifferentPlaces) { run_tum_place_recognition(false); }

TEST(VisualSlamTum, PlaceRecognitionWithBowRestrictedMatchingNeverJoinsDifferentPlaces) { run_tum_place_recognition(true); }

}  // namespace
}  // namespace cairn::vslam
