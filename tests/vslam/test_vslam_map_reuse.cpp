// Localisation in a saved visual map (issue 42, item 4) on the real TUM fr1/desk frames (every
// 4th): the first half is mapped, saved and read back; the second half, which comes back to the
// desk the first half started at, is localised in that map without changing it. Ground truth:
// TUM's motion capture, put into the map's frame by the SE(3) alignment of the MAPPING run's
// tracked frames only, so a localised pose is judged by a transform it had no part in.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

#include "cairn/eval/ape.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/image_file.hpp"
#include "cairn/vslam/map_file.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "test_data.hpp"
#include "tum_desk.hpp"

namespace cairn::vslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// The first half's map, its bytes, and the transform from the map's frame to the ground truth's.
struct DeskMap {
  io::ImageSequence seq;
  std::shared_ptr<const vision::Vocabulary> vocabulary;
  std::size_t half = 0;
  std::string bytes;
  core::SE3 T_truth_map;
  double mapping_ate_m = 0.0;
};

const DeskMap& desk_map() {
  static const DeskMap map = [] {
    DeskMap m;
    m.seq = io::read_tum_rgbd(test::data_path("visual/tum_fr1_desk_every4th").string());
    m.vocabulary = test_tum::kitti_vocabulary();
    m.half = m.seq.frames.size() / 2;
    VisualSlam mapper(test_tum::fr1_camera(), io::SequenceKind::kRgbd, test_tum::rgbd_options(m.vocabulary));
    std::vector<FrameResult> results;
    for (std::size_t k = 0; k < m.half; ++k) {
      const io::ImageFrame& frame = m.seq.frames[k];
      results.push_back(mapper.add_rgbd(frame.time, vision::read_gray_image(frame.image), vision::read_depth_image(frame.depth_image)));
    }
    io::Trajectory tracked;
    const std::vector<core::SE3> poses = mapper.trajectory();
    const std::vector<int> segments = mapper.frame_segments();
    for (std::size_t k = 0; k < results.size(); ++k) {
      if (!results[k].tracked || segments[k] != mapper.main_segment()) continue;
      tracked.stamps.push_back(results[k].time);
      tracked.poses.push_back(poses[k]);
    }
    eval::ApeOptions se3;
    se3.alignment.method = eval::AlignmentMethod::kSE3;
    se3.association.max_time_difference_s = 0.02;
    const eval::ApeResult ape = eval::evaluate_ape(*m.seq.ground_truth, tracked, se3);
    if (!ape.outcome.ok()) throw std::runtime_error(ape.outcome.message);
    m.T_truth_map = ape.alignment.T_reference_estimate();
    m.mapping_ate_m = ape.statistics.rmse;
    m.bytes = encode_saved_map(mapper.saved_map("{}", "tum_fr1_desk_every4th, first half"));
    std::printf("map of frames 0-%zu: %zu of them in the main map, ATE %.4f m; %zu bytes\n", m.half - 1, tracked.size(), m.mapping_ate_m,
                m.bytes.size());
    return m;
  }();
  return map;
}

struct PoseError {
  double metres = 0.0, degrees = 0.0;
};

PoseError error_of(const DeskMap& m, const FrameResult& r) {
  const core::SE3 truth = test_tum::nearest(*m.seq.ground_truth, r.time);
  const core::SE3 d = truth.inverse() * (m.T_truth_map * r.T_world_camera);
  return {d.translation().norm(), Eigen::AngleAxisd(d.rotation_matrix()).angle() * 180.0 / kPi};
}

FrameResult localise(VisualSlam& localiser, const io::ImageFrame& frame) {
  FrameResult r = localiser.add_rgbd(frame.time, vision::read_gray_image(frame.image), vision::read_depth_image(frame.depth_image));
  r.keypoints.clear();
  r.keypoint_states.clear();
  return r;
}

/// "" when the two maps hold the same keyframes, keypoints, points and covisibility (bit for bit),
/// else the first difference.
std::string first_difference(const SavedVisualMap& a, const SavedVisualMap& b) {
  if (a.keyframes.size() != b.keyframes.size()) return "keyframe count";
  for (std::size_t k = 0; k < a.keyframes.size(); ++k) {
    const SavedKeyframe &ka = a.keyframes[k], &kb = b.keyframes[k];
    if (ka.T_world_camera.translation() != kb.T_world_camera.translation() ||
        ka.T_world_camera.unit_quaternion().coeffs() != kb.T_world_camera.unit_quaternion().coeffs()) {
      return "keyframe " + std::to_string(k) + " pose";
    }
    if (ka.keypoints.size() != kb.keypoints.size()) return "keyframe " + std::to_string(k) + " keypoint count";
    for (std::size_t i = 0; i < ka.keypoints.size(); ++i) {
      if (ka.keypoints[i].map_point != kb.keypoints[i].map_point || ka.keypoints[i].descriptor != kb.keypoints[i].descriptor) {
        return "keyframe " + std::to_string(k) + " keypoint " + std::to_string(i);
      }
    }
  }
  if (a.points.size() != b.points.size()) return "point count " + std::to_string(a.points.size()) + " vs " + std::to_string(b.points.size());
  for (std::size_t p = 0; p < a.points.size(); ++p) {
    const SavedMapPoint &pa = a.points[p], &pb = b.points[p];
    const std::string what = "point " + std::to_string(p);
    if (pa.p_world != pb.p_world || pa.normal != pb.normal) return what + " position or normal";
    if (pa.descriptor != pb.descriptor) return what + " descriptor";
    if (pa.visible != pb.visible || pa.found != pb.found) return what + " statistics";
    if (pa.reference_keyframe != pb.reference_keyframe) return what + " reference keyframe";
    if (pa.observations.size() != pb.observations.size()) return what + " observation count";
    for (std::size_t o = 0; o < pa.observations.size(); ++o) {
      if (pa.observations[o].keyframe != pb.observations[o].keyframe || pa.observations[o].keypoint != pb.observations[o].keypoint) return what + " observations";
    }
  }
  if (a.covisibility.size() != b.covisibility.size()) return "covisibility";
  return "";
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

TEST(VisualMapReuse, TheDesksSecondHalfLocalisesInTheFirstHalfsMapWhichNeverChanges) {
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/image_l");
  const DeskMap& m = desk_map();
  const SavedVisualMap map = decode_saved_map(m.bytes, "the desk map");
  VisualSlam localiser(map, test_tum::rgbd_options(m.vocabulary));
  ASSERT_TRUE(localiser.localization_only());
  std::vector<double> metres, degrees;
  double sum_squares = 0.0;
  std::size_t localised = 0, relocalisations = 0;
  double worst_m = 0.0;
  for (std::size_t k = m.half; k < m.seq.frames.size(); ++k) {
    const FrameResult r = localise(localiser, m.seq.frames[k]);
    if (!r.tracked) continue;
    ++localised;
    relocalisations += r.relocalised ? 1 : 0;
    const PoseError e = error_of(m, r);
    metres.push_back(e.metres);
    degrees.push_back(e.degrees);
    sum_squares += e.metres * e.metres;
    worst_m = std::max(worst_m, e.metres);
    EXPECT_LT(e.metres, 0.15) << "frame " << k << " localised " << e.metres << " m from the truth (" << r.note << ")";
    EXPECT_LT(e.degrees, 10.0) << "frame " << k;
    EXPECT_EQ(r.keyframe, false);
  }
  const std::size_t frames = m.seq.frames.size() - m.half;
  const double ate_m = localised > 0 ? std::sqrt(sum_squares / static_cast<double>(localised)) : 0.0;
  std::printf("localised %zu of the %zu frames %zu-%zu (%zu relocalisations): ATE %.4f m (in the mapping run's alignment), error median "
              "%.4f m / %.2f deg, worst %.4f m\n",
              localised, frames, m.half, m.seq.frames.size() - 1, relocalisations, ate_m, median(metres), median(degrees), worst_m);
  // The target: ATE <= 0.03 m. Measured 2026-11-30: 45 of 75 frames, ATE 0.018 m, worst 0.042 m. The
  // frames left lost look at what the first half's main map segment never saw (the first half
  // ends with 43 of its 74 frames in the main map; its other segments are not saved).
  EXPECT_GE(localised, frames / 2);
  EXPECT_LE(ate_m, 0.03);
  // Never a change to the map: what it would save now is, byte for byte, what it was given.
  EXPECT_EQ(first_difference(localiser.saved_map(), map), "");
  EXPECT_TRUE(encode_saved_map(localiser.saved_map("{}", "tum_fr1_desk_every4th, first half")) == m.bytes);
  EXPECT_EQ(localiser.summary().keyframes, 0u);
}

// Every frame a kidnapping: the second half's frames in a shuffled order, each to a localiser that
// must relocalise it with no prior (a shuffled neighbour is not a motion the constant-velocity
// model can follow). A frame may stay lost; one placed must be placed right.
TEST(VisualMapReuse, FramesInShuffledOrderAreNeverPlacedWrong) {
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/image_l");
  const DeskMap& m = desk_map();
  const SavedVisualMap map = decode_saved_map(m.bytes, "the desk map");
  std::vector<std::size_t> order(m.seq.frames.size() - m.half);
  std::iota(order.begin(), order.end(), m.half);
  std::mt19937 rng(42);
  std::shuffle(order.begin(), order.end(), rng);
  VisualSlam localiser(map, test_tum::rgbd_options(m.vocabulary));
  std::size_t placed = 0;
  for (const std::size_t k : order) {
    const FrameResult r = localise(localiser, m.seq.frames[k]);
    if (!r.tracked) continue;
    ++placed;
    const PoseError e = error_of(m, r);
    EXPECT_LT(e.metres, 0.15) << "frame " << k << " placed " << e.metres << " m from the truth (" << r.note << ")";
    EXPECT_LT(e.degrees, 10.0) << "frame " << k;
  }
  std::printf("shuffled: %zu of %zu frames placed\n", placed, order.size());
  EXPECT_GE(placed, order.size() / 4);
}

TEST(VisualMapReuse, RefusesImagesTheMapCannotTake) {
  SavedVisualMap map;
  map.kind = io::SequenceKind::kRgbd;
  map.camera = test_tum::fr1_camera();
  map.camera.width = 640;
  map.camera.height = 480;
  map.vocabulary.words = 100;
  map.vocabulary.fingerprint = 7;
  io::CameraCalibration other = map.camera;
  EXPECT_NE(map_incompatibility(map, other, io::SequenceKind::kRgbd, nullptr).find("give one (--vocabulary)"), std::string::npos);
  other.fx = 525.0;
  const std::string why = map_incompatibility(map, other, io::SequenceKind::kStereo, nullptr);
  EXPECT_NE(why.find("made from rgbd images, these are stereo"), std::string::npos) << why;
  EXPECT_NE(why.find("is not this calibration"), std::string::npos) << why;
  other = map.camera;
  other.width = 320;
  EXPECT_NE(map_incompatibility(map, other, io::SequenceKind::kRgbd, nullptr).find("640 x 480, these 320 x 480"), std::string::npos);
  EXPECT_THROW(VisualSlam(SavedVisualMap{}, VisualSlamOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::vslam
