// Visual SLAM on rendered stereo pairs with exact ground truth (synthetic_world.hpp): tracking
// accuracy in a textured corridor, and its failure modes: aliasing (two rooms with identical
// textures), a texture-less wall filling the view, fast motion, and a kidnap into the look-alike
// room (only one room mapped: undecidable; both mapped: relocalisation must refuse). Thresholds were measured on this code (numbers beside them) and given a margin. The
// SLAM's options are its defaults throughout, plus a vocabulary for place recognition where the
// test is about it, trained on another world's images (other seeds), never on a test's.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <tuple>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cairn/eval/ape.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/sim/imu.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "inertial_flight.hpp"
#include "synthetic_world.hpp"

namespace cairn::vslam {
namespace {

using test::StereoCamera;
using test::SurfaceTexture;
using test::SyntheticWorld;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Heights shared by every world: camera at y = 0, floor 1.3 m below it (y points down),
// corridor ceiling 1.0 m above, room ceiling 1.5 m above.
constexpr double kFloorY = 1.3, kCorridorCeilingY = -1.0, kRoomCeilingY = -1.5;

SurfaceTexture seeded(std::uint64_t seed) {
  SurfaceTexture t;
  t.seed = seed;
  return t;
}

test::RoomTextures room_textures(std::uint64_t seed) {
  return {seeded(seed + 1), seeded(seed + 2), seeded(seed + 3), seeded(seed + 4), seeded(seed + 5), seeded(seed + 6)};
}

// A closing wall across a corridor along z at `z`.
void end_wall(SyntheticWorld& world, double half_width, double z, std::uint64_t seed) {
  world.add_wall(2, Eigen::Vector3d(-half_width, kCorridorCeilingY, z), Eigen::Vector3d(half_width, kFloorY, z), seeded(seed),
                 Eigen::Vector3d(-half_width, kCorridorCeilingY, z));
}

// Corridor0 (z -4..0) | room A (z 0..4) | corridor1 (4..10) | room B (10..14) | corridor2 (14..20).
// Rooms A and B: 4 m x 2.8 m x 4 m with the SAME textures (each measured from its own corner), so
// from inside they look the same except through their doors; the corridors differ.
// `room_seed` / `corridor_seed` let the vocabulary's training world differ from the test's.
SyntheticWorld aliasing_world(std::uint64_t room_seed, std::uint64_t corridor_seed) {
  SyntheticWorld world;
  const double door_half = 0.8;
  for (const double z0 : {0.0, 10.0}) {
    const Eigen::Vector3d lower(-2.0, kRoomCeilingY, z0), upper(2.0, kFloorY, z0 + 4.0);
    world.add_room(lower, upper, room_textures(room_seed), lower, door_half, kCorridorCeilingY);
  }
  world.add_corridor_z(Eigen::Vector3d(-door_half, kCorridorCeilingY, -4.0), Eigen::Vector3d(door_half, kFloorY, 0.0), corridor_seed);
  world.add_corridor_z(Eigen::Vector3d(-door_half, kCorridorCeilingY, 4.0), Eigen::Vector3d(door_half, kFloorY, 10.0), corridor_seed + 100);
  world.add_corridor_z(Eigen::Vector3d(-door_half, kCorridorCeilingY, 14.0), Eigen::Vector3d(door_half, kFloorY, 20.0), corridor_seed + 200);
  end_wall(world, door_half, -4.0, corridor_seed + 300);
  end_wall(world, door_half, 20.0, corridor_seed + 400);
  return world;
}

// A straight corridor 2 m wide along z from -1 to 22 m, closed at both ends; the part of the
// right wall (x = +1) with z in [grey_from_z, grey_to_z] is texture-less grey when grey_to_z > grey_from_z.
SyntheticWorld corridor_world(std::uint64_t seed, double grey_from_z = 0.0, double grey_to_z = 0.0) {
  SyntheticWorld world;
  const double half = 1.0, z0 = -1.0, z1 = 22.0;
  const Eigen::Vector3d lower(-half, kCorridorCeilingY, z0), upper(half, kFloorY, z1);
  // Left wall, floor, ceiling.
  world.add_wall(0, lower, Eigen::Vector3d(-half, kFloorY, z1), seeded(seed + 1), lower);
  world.add_wall(1, Eigen::Vector3d(-half, kCorridorCeilingY, z0), Eigen::Vector3d(half, kCorridorCeilingY, z1), seeded(seed + 2), lower);
  world.add_wall(1, Eigen::Vector3d(-half, kFloorY, z0), Eigen::Vector3d(half, kFloorY, z1), seeded(seed + 3), lower);
  // Right wall, with the grey piece cut out and added on its own.
  if (grey_to_z > grey_from_z) {
    const Eigen::Vector3d opening_lower(half, kCorridorCeilingY, grey_from_z), opening_upper(half, kFloorY, grey_to_z);
    world.add_wall(0, Eigen::Vector3d(half, kCorridorCeilingY, z0), upper, seeded(seed + 4), lower, &opening_lower, &opening_upper);
    SurfaceTexture grey;
    grey.textured = false;
    grey.grey = 128.0;
    world.add_wall(0, opening_lower, opening_upper, grey, lower);
  } else {
    world.add_wall(0, Eigen::Vector3d(half, kCorridorCeilingY, z0), upper, seeded(seed + 4), lower);
  }
  end_wall(world, half, z0, seed + 5);
  end_wall(world, half, z1, seed + 6);
  return world;
}

struct SlamRun {
  std::unique_ptr<VisualSlam> slam;
  std::vector<FrameResult> results;
  std::vector<core::SE3> truth;  ///< T_world_camera of each frame in the synthetic world
  double render_s = 0.0;
  double slam_s = 0.0;
};

SlamRun run_stereo(const SyntheticWorld& world, const std::vector<core::SE3>& truth, const VisualSlamOptions& options,
               const StereoCamera& camera = {}) {
  SlamRun run;
  run.truth = truth;
  run.slam = std::make_unique<VisualSlam>(camera.calibration(), io::SequenceKind::kStereo, options);
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto [left, right] = world.render_stereo(truth[k], camera);
    const auto t1 = std::chrono::steady_clock::now();
    FrameResult r = run.slam->add_stereo(core::Timestamp::from_seconds(0.1 * static_cast<double>(k)), left, right);
    const auto t2 = std::chrono::steady_clock::now();
    run.render_s += std::chrono::duration<double>(t1 - t0).count();
    run.slam_s += std::chrono::duration<double>(t2 - t1).count();
    r.keypoints.clear();
    r.keypoint_states.clear();
    run.results.push_back(std::move(r));
  }
  return run;
}

// cairn's world is the first camera: the truth in that frame is T_gt0^-1 T_gt_k.
core::SE3 truth_in_first_camera(const SlamRun& run, std::size_t k) { return run.truth.front().inverse() * run.truth[k]; }

double position_error(const SlamRun& run, std::size_t k, const core::SE3& estimate) {
  return (truth_in_first_camera(run, k).translation() - estimate.translation()).norm();
}

// The position error of frame k within its map segment (as reported with the frame): a segment
// started after tracking loss is placed where the motion model guessed, so only the motion since
// the segment's first frame can be compared with the truth. For the first segment that is the
// absolute error.
double segment_error(const SlamRun& run, std::size_t k) {
  std::size_t first = 0;
  while (first < k && run.results[first].segment != run.results[k].segment) ++first;
  const core::SE3 truth = run.truth[first].inverse() * run.truth[k];
  const core::SE3 estimate = run.results[first].T_world_camera.inverse() * run.results[k].T_world_camera;
  return (truth.translation() - estimate.translation()).norm();
}

const char* health_name(TrackingHealth h) { return h == TrackingHealth::kOk ? "ok" : h == TrackingHealth::kDegraded ? "degraded" : "lost"; }

void print_summary(const char* what, const SlamRun& run) {
  const VisualSlamSummary& s = run.slam->summary();
  std::printf("%s: %zu frames: %zu ok, %zu degraded, %zu lost; %zu keyframes (%zu culled), %zu map points; %zu relocalisations; %zu loop "
              "queries, %zu candidates verified, %zu accepted; render %.2f s, SLAM %.2f s\n",
              what, s.frames, s.frames_ok, s.frames_degraded, s.frames_lost, s.keyframes, s.keyframes_culled, run.slam->map_points().size(),
              s.relocalisations, s.loop_queries, s.loops.size(), s.loops_accepted, run.render_s, run.slam_s);
}

// A vocabulary trained on images of a world the tests never use (other seeds), 20 views.
std::shared_ptr<const vision::Vocabulary> training_vocabulary() {
  static const std::shared_ptr<const vision::Vocabulary> vocabulary = [] {
    const SyntheticWorld world = aliasing_world(7001, 7501);
    const StereoCamera camera;
    const vision::OrbExtractor orb(vision::OrbOptions{});
    std::vector<cv::Mat> descriptors;
    std::vector<core::SE3> views = test::walk(Eigen::Vector3d(0.0, 0.0, -3.0), Eigen::Vector3d(0.0, 0.0, 18.0), 1.5, 0.0, 25.0 * kDeg, 0.3);
    test::append(views, test::turn(Eigen::Vector3d(0.0, 0.0, 12.0), kPi * 0.5, kPi * 1.5, 30.0 * kDeg));
    for (const core::SE3& view : views) descriptors.push_back(orb.extract(world.render(view, camera)).descriptors);
    vision::VocabularyOptions options;
    options.branching = 10;
    options.depth = 4;
    return std::make_shared<const vision::Vocabulary>(vision::Vocabulary::train(descriptors, options));
  }();
  return vocabulary;
}

// --- The world itself ------------------------------------------------------------------------

TEST(SyntheticWorld, RendersIdenticalRoomsIdenticallyAndBlankWallsBlank) {
  const SyntheticWorld world = aliasing_world(11, 21);
  const StereoCamera camera;
  // The same room-relative pose in A and B, looking at the side wall: the same picture.
  const core::SE3 in_a = test::camera_pose(Eigen::Vector3d(0.5, 0.0, 2.0), -70.0 * kDeg);
  const core::SE3 in_b = test::camera_pose(Eigen::Vector3d(0.5, 0.0, 12.0), -70.0 * kDeg);
  const auto t0 = std::chrono::steady_clock::now();
  const cv::Mat a = world.render(in_a, camera);
  const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const cv::Mat b = world.render(in_b, camera);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  std::printf("one 640x480 image: %.1f ms\n", 1e3 * render_s);
  // Textured enough for ORB.
  const vision::Features features = vision::OrbExtractor().extract(a);
  std::printf("ORB features in a room view: %zu\n", features.keypoints.size());
  EXPECT_GT(features.keypoints.size(), 1000u);
  // Depth: a fronto-parallel wall 2 m ahead reads 2 m (5000 units per metre) everywhere.
  const cv::Mat depth = world.render_depth(test::camera_pose(Eigen::Vector3d(0.0, 0.0, 2.0), 90.0 * kDeg), camera);
  EXPECT_EQ(depth.at<std::uint16_t>(240, 320), 10000);
  EXPECT_EQ(depth.at<std::uint16_t>(10, 10), 10000);
  // The grey wall of the texture-less corridor fills the view 0.7 m in front of it.
  const SyntheticWorld grey = corridor_world(31, 4.0, 7.0);
  const core::SE3 facing = test::camera_pose(Eigen::Vector3d(0.3, 0.0, 5.5), 90.0 * kDeg);
  EXPECT_EQ(grey.textured_fraction(facing, camera), 0.0);
  cv::Mat blank = grey.render(facing, camera);
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(blank, &lo, &hi);
  EXPECT_EQ(lo, 128.0);
  EXPECT_EQ(hi, 128.0);
}

// --- a. Tracking accuracy --------------------------------------------------------------------

TEST(VisualSlamSynthetic, TracksATexturedCorridorAgainstExactGroundTruth) {
  const SyntheticWorld world = corridor_world(101);
  // 12 m at 0.15 m per frame, yaw swaying +-8 deg and x +-0.2 m: 81 frames.
  const std::vector<core::SE3> truth = test::walk(Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.0, 0.0, 12.0), 0.15, 0.0, 8.0 * kDeg, 0.2);
  const SlamRun run = run_stereo(world, truth, VisualSlamOptions{});
  print_summary("corridor", run);
  std::size_t tracked = 0;
  for (const FrameResult& r : run.results) tracked += r.tracked ? 1 : 0;
  const std::vector<core::SE3> estimate = run.slam->trajectory();
  ASSERT_EQ(estimate.size(), truth.size());
  double sum_sq = 0.0, max_error = 0.0, max_rotation_deg = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const double e = position_error(run, k, estimate[k]);
    sum_sq += e * e;
    max_error = std::max(max_error, e);
    const core::SE3 d = truth_in_first_camera(run, k).inverse() * estimate[k];
    max_rotation_deg = std::max(max_rotation_deg, Eigen::AngleAxisd(d.rotation_matrix()).angle() / kDeg);
  }
  const double rmse = std::sqrt(sum_sq / static_cast<double>(truth.size()));
  const double final_error = position_error(run, truth.size() - 1, estimate.back());
  const double path_m = 12.0;
  std::printf("corridor: %zu / %zu frames tracked; translation RMSE %.4f m, max %.4f m, final %.4f m (%.3f %% of %.0f m); "
              "max rotation error %.3f deg\n",
              tracked, truth.size(), rmse, max_error, final_error, 100.0 * final_error / path_m, path_m, max_rotation_deg);
  // Measured (2026-11-25, three runs while visual_slam.cpp changed): RMSE 0.014-0.019 m, final
  // 0.025-0.031 m, max rotation error 0.14-0.42 deg. Limits about 2.5 x that.
  EXPECT_EQ(tracked, truth.size());
  EXPECT_LT(rmse, 0.05);
  EXPECT_LT(final_error, 0.08);
  EXPECT_LT(max_rotation_deg, 1.0);
}

// The yaw of a camera_pose (rotation about the world y axis).
double yaw_of(const core::SE3& T_world_camera) {
  const Eigen::Matrix3d R = T_world_camera.rotation_matrix();
  return std::atan2(R(0, 2), R(2, 2));
}

// --- b. Aliasing: no loop between look-alike rooms --------------------------------------------

// Every verified loop candidate with the true distance between the two cameras; returns the
// accepted loops and verified revisits joining cameras more than 1 m apart.
int print_loops_and_count_false(const SlamRun& run) {
  int false_loops = 0;
  for (const LoopRecord& loop : run.slam->summary().loops) {
    const double metres = (run.truth[loop.frame].translation() - run.truth[loop.candidate_frame].translation()).norm();
    std::printf("  loop candidate frame %zu -> %zu: score %.3f (min covisible %.3f), consistency %d, %d PnP inliers, %d matches, "
                "%s (%s), correction %.3f m %.2f deg; true z %.2f -> %.2f m, true distance %.2f m\n",
                loop.frame, loop.candidate_frame, loop.score, loop.min_covisible_score, loop.consistency, loop.pnp_inliers, loop.matches,
                loop.decision.c_str(), loop.reason.c_str(), loop.correction_m, loop.correction_deg, run.truth[loop.frame].translation().z(),
                run.truth[loop.candidate_frame].translation().z(), metres);
    if ((loop.decision == "accepted" || loop.decision == "revisit") && metres > 1.0) ++false_loops;
  }
  return false_loops;
}

TEST(VisualSlamSynthetic, NoLoopClosureBetweenIdenticalRooms) {
  const SyntheticWorld world = aliasing_world(11, 21);
  VisualSlamOptions options;
  options.vocabulary = training_vocabulary();
  // From corridor 0 into room A; 1 m in, look 60 deg left, 60 deg right and ahead again; walk
  // through room A, corridor 1 and into room B along the middle (yaw swaying +-10 deg with a 5 m
  // period), and 1 m into room B look around the same way: in room B the camera takes exactly
  // the room-relative poses it had in room A. (Corridor 0 and the look-around make the keyframes
  // loop detection waits for: it queries from the 20th keyframe on.)
  const auto look_around = [](double z) {
    std::vector<core::SE3> poses = test::turn(Eigen::Vector3d(0.0, 0.0, z), 0.0, -60.0 * kDeg, 6.0 * kDeg);
    test::append(poses, test::turn(Eigen::Vector3d(0.0, 0.0, z), -60.0 * kDeg, 60.0 * kDeg, 6.0 * kDeg));
    test::append(poses, test::turn(Eigen::Vector3d(0.0, 0.0, z), 60.0 * kDeg, 0.0, 6.0 * kDeg));
    return poses;
  };
  std::vector<core::SE3> truth = test::walk(Eigen::Vector3d(0.0, 0.0, -3.5), Eigen::Vector3d(0.0, 0.0, 1.0), 0.2);
  test::append(truth, look_around(1.0));
  test::append(truth, test::walk(Eigen::Vector3d(0.0, 0.0, 1.0), Eigen::Vector3d(0.0, 0.0, 11.0), 0.2, 0.0, 10.0 * kDeg, 0.0, 5.0));
  const std::size_t entering_b = truth.size() - 1;
  test::append(truth, look_around(11.0));
  test::append(truth, test::walk(Eigen::Vector3d(0.0, 0.0, 11.0), Eigen::Vector3d(0.0, 0.0, 12.6), 0.2, 0.0, 10.0 * kDeg, 0.0, 5.0));
  const SlamRun run = run_stereo(world, truth, options);
  print_summary("aliasing, A -> B", run);
  std::size_t keyframes_before_b = 0, tracked = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    keyframes_before_b += k < entering_b && run.results[k].keyframe ? 1 : 0;
    tracked += run.results[k].tracked ? 1 : 0;
  }
  std::printf("vocabulary: %s; %zu keyframes before room B (frame %zu); %zu / %zu frames tracked\n", options.vocabulary->description().c_str(),
              keyframes_before_b, entering_b, tracked, truth.size());
  const int false_loops = print_loops_and_count_false(run);
  const std::vector<core::SE3> estimate = run.slam->trajectory();
  double max_error = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k) max_error = std::max(max_error, position_error(run, k, estimate[k]));
  std::printf("aliasing, A -> B: %d accepted loops between places more than 1 m apart; max position error of the final "
              "trajectory %.3f m\n",
              false_loops, max_error);
  // Not vacuous: place recognition was asked in room B.
  EXPECT_GT(run.slam->summary().loop_queries, 0u);
  // The requirement. When this test was written (2026-11-25) it failed: frame 102
  // (corridor 1, 1.2 m before room B, looking in) was joined to frame 12 (corridor 0, 1.15 m
  // before room A, looking in) with 111 PnP inliers and 400 matches, and the map was corrected by
  // 10.0 m; the two views differ only in the corridor walls at the image borders. The drift bound
  // on a loop's correction (loop_drift_*) refuses it now: 9.99 m asked for against 1.0 m possible
  // over the 10 m travelled (re-measured 2026-11-25, second session).
  EXPECT_EQ(false_loops, 0);
}

TEST(VisualSlamSynthetic, ReportsWhetherARealRevisitClosesALoop) {
  const SyntheticWorld world = aliasing_world(11, 21);
  VisualSlamOptions options;
  options.vocabulary = training_vocabulary();
  // Room A -> corridor 1, turn round, back into room A, turn round again and look where it
  // looked first.
  std::vector<core::SE3> truth = test::walk(Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::Vector3d(0.0, 0.0, 7.0), 0.2, 0.0, 10.0 * kDeg, 0.0, 5.0);
  test::append(truth, test::turn(Eigen::Vector3d(0.0, 0.0, 7.0), yaw_of(truth.back()), kPi, 10.0 * kDeg));
  test::append(truth, test::walk(Eigen::Vector3d(0.0, 0.0, 7.0), Eigen::Vector3d(0.0, 0.0, 1.5), 0.2, kPi));
  test::append(truth, test::turn(Eigen::Vector3d(0.0, 0.0, 1.5), kPi, 2.0 * kPi, 10.0 * kDeg));
  test::append(truth, test::walk(Eigen::Vector3d(0.0, 0.0, 1.5), Eigen::Vector3d(0.0, 0.0, 6.0), 0.2, 2.0 * kPi));
  const SlamRun run = run_stereo(world, truth, options);
  print_summary("revisit A", run);
  const int false_loops = print_loops_and_count_false(run);
  int true_loops = 0;
  for (const LoopRecord& loop : run.slam->summary().loops) true_loops += loop.decision == "accepted" ? 1 : 0;
  true_loops -= false_loops;
  std::size_t tracked = 0;
  for (const FrameResult& r : run.results) tracked += r.tracked ? 1 : 0;
  const std::vector<core::SE3> estimate = run.slam->trajectory();
  double max_error = 0.0, max_online_error = 0.0;
  std::size_t worst = 0, worst_online = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const double e = position_error(run, k, estimate[k]), online = position_error(run, k, run.results[k].T_world_camera);
    if (run.results[k].keyframe) {
      std::printf("  keyframe at frame %3zu: %-8s loop %d error %.3f m (final trajectory), %.3f m (as reported)\n", k,
                  health_name(run.results[k].health), run.results[k].loop_closed ? 1 : 0, e, online);
    }
    if (e > max_error) {
      max_error = e;
      worst = k;
    }
    if (online > max_online_error) {
      max_online_error = online;
      worst_online = k;
    }
  }
  // After the (first) loop closure, as reported frame by frame.
  std::size_t loop_frame = truth.size();
  for (std::size_t k = 0; k < truth.size() && loop_frame == truth.size(); ++k) {
    if (run.results[k].loop_closed) loop_frame = k;
  }
  double max_error_after_loop = 0.0;
  for (std::size_t k = loop_frame + 1; k < truth.size(); ++k) {
    max_error_after_loop = std::max(max_error_after_loop, position_error(run, k, run.results[k].T_world_camera));
  }
  std::printf("revisit A: %zu / %zu tracked, %d true loops accepted, %d false; max position error %.3f m (frame %zu) in the final "
              "trajectory, %.3f m (frame %zu) as reported frame by frame; loop closed at frame %zu, after it max error %.3f m "
              "over %zu frames\n",
              tracked, truth.size(), true_loops, false_loops, max_error, worst, max_online_error, worst_online, loop_frame,
              max_error_after_loop, truth.size() - std::min(truth.size(), loop_frame + 1));
  EXPECT_EQ(tracked, truth.size());
  EXPECT_EQ(false_loops, 0);
  // The revisit is found (in every run so far, 2026-11-25: frame 105 or 106 -> 16 or 18, true
  // distance 0.15-0.55 m) and removes the drift of the two turns: measured 0.43 m before the loop,
  // at most 0.011 m after it. The final trajectory() follows the corrected keyframes (a keyframe
  // frame takes its keyframe's final pose since 2026-11-25; before, the loop frame kept 0.43 m);
  // what remains, up to 0.23 m before the loop, is the drift the pose graph spreads.
  EXPECT_GE(true_loops, 1);
  EXPECT_LT(loop_frame + 1, truth.size());
  EXPECT_LT(max_error_after_loop, 0.05);
}

// --- c. A texture-less wall fills the view ------------------------------------------------------

TEST(VisualSlamSynthetic, FailsLoudlyFacingABlankWall) {
  const SyntheticWorld world = corridor_world(201, 4.0, 7.0);
  const StereoCamera camera;
  const Eigen::Vector3d stop(0.3, 0.0, 5.5);  // 0.7 m from the grey wall at x = 1
  std::vector<core::SE3> truth = test::walk(Eigen::Vector3d(0.3, 0.0, 0.0), stop, 0.15);
  test::append(truth, test::turn(stop, 0.0, 90.0 * kDeg, 6.0 * kDeg));
  test::append(truth, test::hold(truth.back(), 6));
  test::append(truth, test::turn(stop, 90.0 * kDeg, 0.0, 6.0 * kDeg));
  test::append(truth, test::walk(stop, Eigen::Vector3d(0.3, 0.0, 9.0), 0.15));
  const SlamRun run = run_stereo(world, truth, VisualSlamOptions{}, camera);
  print_summary("blank wall", run);
  std::size_t blank = 0, blank_ok = 0, last_blank = 0, wrong_ok = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const FrameResult& r = run.results[k];
    const double fraction = world.textured_fraction(truth[k], camera);
    const double e = position_error(run, k, r.T_world_camera);
    std::printf("  frame %3zu: textured %5.1f %%, %-8s tracked %d reloc %d new map %d inliers %4d, error %.3f m %s\n", k,
                100.0 * fraction, health_name(r.health), r.tracked ? 1 : 0, r.relocalised ? 1 : 0, r.new_map ? 1 : 0, r.inliers, e,
                r.note.c_str());
    if (fraction == 0.0) {
      ++blank;
      last_blank = k;
      blank_ok += r.health == TrackingHealth::kOk ? 1 : 0;
      EXPECT_NE(r.health, TrackingHealth::kOk) << "frame " << k << " sees only a grey wall";
    }
    if (r.health == TrackingHealth::kOk && e > 0.5) ++wrong_ok;
  }
  EXPECT_GT(blank, 0u);
  EXPECT_EQ(wrong_ok, 0u) << "frames reported ok more than 0.5 m from the truth";
  // After the wall: did tracking come back, and where?
  std::size_t recovered_at = 0;
  for (std::size_t k = last_blank + 1; k < truth.size() && recovered_at == 0; ++k) {
    if (run.results[k].tracked) recovered_at = k;
  }
  std::size_t tracked_after = 0;
  double max_error_after = 0.0;
  for (std::size_t k = recovered_at; recovered_at > 0 && k < truth.size(); ++k) {
    if (!run.results[k].tracked) continue;
    ++tracked_after;
    max_error_after = std::max(max_error_after, position_error(run, k, run.results[k].T_world_camera));
  }
  std::printf("blank wall: %zu blank frames (%zu reported ok), %zu ok frames off by > 0.5 m; recovered at frame %zu (%zu frames "
              "after the last blank one, relocalised %d, new map %d), %zu of the %zu frames from there tracked, max error %.3f m\n",
              blank, blank_ok, wrong_ok, recovered_at, recovered_at - last_blank, run.results[recovered_at].relocalised ? 1 : 0,
              run.results[recovered_at].new_map ? 1 : 0, tracked_after, truth.size() - recovered_at, max_error_after);
  // Recovery, the desired behaviour, is what it does (2026-11-25): relocalised 2 frames after the
  // last blank one (11 % of the view textured again), every later frame tracked, error <= 0.025 m.
  EXPECT_GT(recovered_at, 0u);
  EXPECT_LE(recovered_at - last_blank, 5u);
  EXPECT_EQ(tracked_after, truth.size() - recovered_at);
  EXPECT_LT(max_error_after, 0.1);
}

// --- Fast motion ------------------------------------------------------------------------------

TEST(VisualSlamSynthetic, FastMotionIsTrackedOrDeclaredLostNeverWrong) {
  const SyntheticWorld world = corridor_world(301);
  // 3 m at 0.15 m per frame, then 9 m at 0.9 m per frame with the yaw swinging +-20 deg over
  // 3.6 m (up to ~30 deg between frames), then 0.15 m per frame again.
  std::vector<core::SE3> truth = test::walk(Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.0, 0.0, 3.0), 0.15);
  const std::size_t fast_from = truth.size();
  test::append(truth, test::walk(Eigen::Vector3d(0.0, 0.0, 3.0), Eigen::Vector3d(0.0, 0.0, 12.0), 0.9, 0.0, 20.0 * kDeg, 0.0, 3.6));
  const std::size_t fast_to = truth.size();
  test::append(truth, test::walk(Eigen::Vector3d(0.0, 0.0, 12.0), Eigen::Vector3d(0.0, 0.0, 15.0), 0.15));
  const SlamRun run = run_stereo(world, truth, VisualSlamOptions{});
  print_summary("fast motion", run);
  std::size_t ok_wrong = 0, tracked_wrong = 0, lost = 0, tracked_right = 0;
  double max_tracked_error = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const FrameResult& r = run.results[k];
    const double absolute = position_error(run, k, r.T_world_camera);
    const double e = segment_error(run, k);
    if (k + 1 >= fast_from) {
      std::printf("  frame %3zu%s: %-8s tracked %d reloc %d new map %d segment %d ref %d inliers %4d, error %.3f m in its "
                  "segment, %.3f m absolute %s\n",
                  k, k >= fast_from && k < fast_to ? " (fast)" : "       ", health_name(r.health), r.tracked ? 1 : 0, r.relocalised ? 1 : 0,
                  r.new_map ? 1 : 0, r.segment, r.used_reference ? 1 : 0, r.inliers, e, absolute, r.note.c_str());
    }
    if (!r.tracked) {
      ++lost;
      continue;
    }
    max_tracked_error = std::max(max_tracked_error, e);
    if (e > 0.5) {
      ++tracked_wrong;
      ok_wrong += r.health == TrackingHealth::kOk ? 1 : 0;
    } else {
      ++tracked_right;
    }
  }
  std::size_t tracked_at_the_end = 0;
  for (std::size_t k = truth.size() - 15; k < truth.size(); ++k) tracked_at_the_end += run.results[k].tracked ? 1 : 0;
  std::printf("fast motion: %zu frames (%zu fast): %zu tracked within 0.5 m (in their map segment), %zu lost, %zu tracked more "
              "than 0.5 m off (%zu of them ok); max error of a tracked frame %.3f m; %zu new map segments; %zu of the last 15 frames "
              "tracked, the last %.3f m from the truth in absolute terms\n",
              truth.size(), fast_to - fast_from, tracked_right, lost, tracked_wrong, ok_wrong, max_tracked_error,
              run.slam->summary().maps_started, tracked_at_the_end, position_error(run, truth.size() - 1, run.results.back().T_world_camera));
  // Measured (2026-11-25): of the 10 fast frames 6 are lost, 3 start new map segments (reported
  // degraded) and the rest are tracked within 0.015 m of the truth in their segment; back at
  // 0.15 m per frame every frame is tracked (in segment 3, whose placement is the motion model's
  // guess: 7-11 m off in absolute terms, since without a vocabulary segments are never merged).
  EXPECT_EQ(ok_wrong, 0u) << "frames reported ok more than 0.5 m from the truth (in their map segment)";
  EXPECT_LT(max_tracked_error, 0.1);
  EXPECT_EQ(tracked_at_the_end, 15u);
}

// --- d. Kidnapped into the look-alike room -----------------------------------------------------

// Only room A is mapped, then the camera is carried into room B, an exact copy: this case
// CANNOT be resolved by appearance. Every picture in B is a picture of A; any method that
// decides from what the camera sees (bag of words, PnP, the local map, a uniqueness test over
// the map) must take B for A, because the map holds no second place to compare with. The test
// prints the count and asserts only what is decidable (room A tracked, the jump not absorbed).
// The detectable version, both rooms in the map, is the next test.

TEST(VisualSlamSynthetic, CountsWrongRelocalisationsAfterAKidnapIntoTheLookAlikeRoom) {
  const SyntheticWorld world = aliasing_world(11, 21);
  VisualSlamOptions options;
  options.vocabulary = training_vocabulary();
  std::vector<core::SE3> truth = test::walk(Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::Vector3d(0.0, 0.0, 3.0), 0.15, 0.0, 10.0 * kDeg);
  test::append(truth, test::turn(Eigen::Vector3d(0.0, 0.0, 3.0), 0.0, -60.0 * kDeg, 6.0 * kDeg));
  const std::size_t jump = truth.size();
  // The kidnap: room B, 0.6 m right of the middle, 1.2 m in, looking 30 deg right.
  test::append(truth, test::walk(Eigen::Vector3d(0.6, 0.0, 11.2), Eigen::Vector3d(0.6, 0.0, 12.8), 0.1, 30.0 * kDeg));
  const SlamRun run = run_stereo(world, truth, options);
  print_summary("kidnap", run);
  double max_error_before = 0.0;
  std::size_t tracked_before = 0;
  for (std::size_t k = 0; k < jump; ++k) {
    const FrameResult& r = run.results[k];
    tracked_before += r.tracked ? 1 : 0;
    max_error_before = std::max(max_error_before, position_error(run, k, r.T_world_camera));
  }
  std::size_t lost = 0, right = 0, wrong = 0, wrong_relocalised = 0;
  for (std::size_t k = jump; k < truth.size(); ++k) {
    const FrameResult& r = run.results[k];
    const double e = position_error(run, k, r.T_world_camera);
    // Where it would be if room B were room A: the pose shifted back by the 10 m.
    const double e_in_a = (truth_in_first_camera(run, k).translation() - Eigen::Vector3d(0.0, 0.0, 10.0) - r.T_world_camera.translation()).norm();
    std::printf("  frame %3zu (after jump %2zu): %-8s tracked %d reloc %d new map %d ref %d inliers %4d, error %.3f m (vs. the same "
                "place in room A %.3f m) %s\n",
                k, k - jump, health_name(r.health), r.tracked ? 1 : 0, r.relocalised ? 1 : 0, r.new_map ? 1 : 0, r.used_reference ? 1 : 0,
                r.inliers, e, e_in_a, r.note.c_str());
    if (!r.tracked) {
      ++lost;
    } else if (e <= 1.0) {
      ++right;
    } else {
      ++wrong;
      wrong_relocalised += r.relocalised ? 1 : 0;
    }
  }
  std::printf("kidnap: before the jump %zu / %zu tracked, max error %.3f m; after it, %zu frames: %zu lost, %zu tracked where "
              "they are, %zu tracked more than 1 m off (%zu of them flagged relocalised)\n",
              tracked_before, jump, max_error_before, truth.size() - jump, lost, right, wrong, wrong_relocalised);
  // Room A is tracked (measured: every frame, max error 0.007 m), and the jump itself is not
  // silently absorbed: the first frame in room B is not reported ok.
  EXPECT_EQ(tracked_before, jump);
  EXPECT_LT(max_error_before, 0.05);
  EXPECT_NE(run.results[jump].health, TrackingHealth::kOk);
  // Not asserted: zero wrong relocalisations. Measured (2026-11-25): the frame after the jump is
  // relocalised into room A (0.06 m from the look-alike place there, 9.98 m from the truth) and the
  // 15 frames after it are tracked on, all about 10 m off. This cannot be resolved by appearance:
  // room B is an exact copy of the only room in the map, so the relocalisation's uniqueness test
  // has no second place to find, and no other appearance-based test could do better. Only the
  // door views differ, and they show corridors the map does not hold either.
}

// The route that maps both look-alike rooms: corridor 0 looking at its closed end, a turn, room A
// (with a look-around), corridor 1, room B (the same look-around, so B is mapped from the
// room-relative poses A was), then into corridor 2.
std::vector<core::SE3> both_rooms_route() {
  const auto look_around = [](double z) {
    std::vector<core::SE3> poses = test::turn(Eigen::Vector3d(0.0, 0.0, z), 0.0, -60.0 * kDeg, 10.0 * kDeg);
    test::append(poses, test::turn(Eigen::Vector3d(0.0, 0.0, z), -60.0 * kDeg, 60.0 * kDeg, 10.0 * kDeg));
    test::append(poses, test::turn(Eigen::Vector3d(0.0, 0.0, z), 60.0 * kDeg, 0.0, 10.0 * kDeg));
    return poses;
  };
  std::vector<core::SE3> route = test::turn(Eigen::Vector3d(0.0, 0.0, -2.0), kPi, 2.0 * kPi, 10.0 * kDeg);
  test::append(route, test::walk(Eigen::Vector3d(0.0, 0.0, -2.0), Eigen::Vector3d(0.0, 0.0, 2.0), 0.2));
  test::append(route, look_around(2.0));
  test::append(route, test::walk(Eigen::Vector3d(0.0, 0.0, 2.0), Eigen::Vector3d(0.0, 0.0, 12.0), 0.2, 0.0, 10.0 * kDeg, 0.0, 5.0));
  test::append(route, look_around(12.0));
  test::append(route, test::walk(Eigen::Vector3d(0.0, 0.0, 12.0), Eigen::Vector3d(0.0, 0.0, 16.0), 0.2));
  return route;
}

struct Kidnap {
  const char* name;
  Eigen::Vector3d at;  ///< where the camera is put down (world)
  double yaw_rad;
};

struct KidnapOutcome {
  std::size_t lost = 0, right = 0, wrong = 0, wrong_ok = 0, wrong_relocalised = 0, relocalised_right = 0, refusals = 0;
  std::size_t first_relocalised = 0;  ///< frames after the jump; 0: none
  double max_error_before = 0.0;
};

// Maps both rooms (rendered once per world: `route_images`), then is kidnapped, once per entry of
// `kidnaps`: 8 frames walking 0.7 m from `at`. A tracked frame is wrong when it is more than 0.5 m
// from the truth in its map segment (a segment started after a jump is placed where the motion
// model guessed: only its own motion can be compared; the main segment's frames are compared
// absolutely).
std::vector<KidnapOutcome> run_kidnaps(const SyntheticWorld& world, const std::vector<core::SE3>& route,
                                       const std::vector<std::pair<cv::Mat, cv::Mat>>& route_images, const std::vector<Kidnap>& kidnaps,
                                       double& slam_s) {
  VisualSlamOptions options;
  options.vocabulary = training_vocabulary();
  const StereoCamera camera;
  std::vector<core::SE3> truth = route;
  std::vector<std::size_t> jumps;
  for (const Kidnap& kidnap : kidnaps) {
    jumps.push_back(truth.size());
    const Eigen::Vector3d heading(std::sin(kidnap.yaw_rad), 0.0, std::cos(kidnap.yaw_rad));
    const std::vector<core::SE3> walk = test::walk(kidnap.at, kidnap.at + 0.7 * heading, 0.1, kidnap.yaw_rad);
    truth.insert(truth.end(), walk.begin(), walk.end());
  }
  jumps.push_back(truth.size());
  SlamRun run;
  run.truth = truth;
  run.slam = std::make_unique<VisualSlam>(camera.calibration(), io::SequenceKind::kStereo, options);
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const auto [left, right] = k < route.size() ? route_images[k] : world.render_stereo(truth[k], camera);
    FrameResult r = run.slam->add_stereo(core::Timestamp::from_seconds(0.1 * static_cast<double>(k)), left, right);
    r.keypoints.clear();
    r.keypoint_states.clear();
    run.results.push_back(std::move(r));
  }
  slam_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  print_summary(kidnaps.front().name, run);
  double max_error_before = 0.0;
  for (std::size_t k = 0; k < route.size(); ++k) {
    max_error_before = std::max(max_error_before, position_error(run, k, run.results[k].T_world_camera));
  }
  std::vector<KidnapOutcome> outcomes;
  for (std::size_t n = 0; n < kidnaps.size(); ++n) {
    const Kidnap& kidnap = kidnaps[n];
    KidnapOutcome out;
    out.max_error_before = max_error_before;
    for (std::size_t k = jumps[n]; k < jumps[n + 1]; ++k) {
      const FrameResult& r = run.results[k];
      const double e = segment_error(run, k);
      std::printf("  %s frame %3zu (after jump %zu): %-8s tracked %d reloc %d new map %d segment %d inliers %4d, error %.3f m in its "
                  "segment, %.3f m absolute %s\n",
                  kidnap.name, k, k - jumps[n], health_name(r.health), r.tracked ? 1 : 0, r.relocalised ? 1 : 0, r.new_map ? 1 : 0,
                  r.segment, r.inliers, e, position_error(run, k, r.T_world_camera), r.note.c_str());
      const bool ambiguous = r.note.find("ambiguous relocalisation") != std::string::npos;
      out.refusals += ambiguous ? 1 : 0;
      // The refusal is flagged, not only written: report.json's relocalisations_refused reads it.
      if (ambiguous) {
        EXPECT_TRUE(r.relocalisation_refused && !r.tracked) << kidnap.name << " frame " << k;
      }
      if (!r.tracked) {
        ++out.lost;
      } else if (e <= 0.5) {
        ++out.right;
        if (r.relocalised) {
          ++out.relocalised_right;
          if (out.first_relocalised == 0) out.first_relocalised = k - jumps[n];
        }
      } else {
        ++out.wrong;
        out.wrong_ok += r.health == TrackingHealth::kOk ? 1 : 0;
        out.wrong_relocalised += r.relocalised ? 1 : 0;
      }
    }
    for (const LoopRecord& loop : run.slam->summary().loops) {
      if (loop.frame < jumps[n] || loop.frame >= jumps[n + 1]) continue;
      std::printf("  %s loop/merge frame %zu -> %zu: %d PnP inliers, %d matches, %s (%s); true distance %.2f m\n", kidnap.name,
                  loop.frame, loop.candidate_frame, loop.pnp_inliers, loop.matches, loop.decision.c_str(), loop.reason.c_str(),
                  (truth[loop.frame].translation() - truth[loop.candidate_frame].translation()).norm());
    }
    std::printf("%s: %zu frames after the jump: %zu lost (%zu refused as ambiguous), %zu tracked right (%zu relocalised, first %zu "
                "frames after the jump), %zu tracked wrong (%zu ok, %zu relocalised); route max error %.3f m\n",
                kidnap.name, jumps[n + 1] - jumps[n], out.lost, out.refusals, out.right, out.relocalised_right, out.first_relocalised,
                out.wrong, out.wrong_ok, out.wrong_relocalised, max_error_before);
    outcomes.push_back(out);
  }
  const VisualSlamSummary& s = run.slam->summary();
  std::printf("%s: %zu relocalisations, %zu refused as ambiguous; %zu loops / merges refused as ambiguous, %zu accepted\n",
              kidnaps.front().name, s.relocalisations, s.relocalisations_ambiguous, s.loops_ambiguous, s.loops_accepted);
  return outcomes;
}

// Both look-alike rooms are in the map (the camera walked A, corridor 1, B), then it is carried
// off into one of them: every view of A now has a twin in the map, and relocalisation must find
// both and refuse (the uniqueness test, tracking.cpp relocalisation_rival) instead of guessing.
// Over two worlds (texture seeds) and two kidnap poses each, one into A and one into B, no
// frame may be tracked wrong and reported ok, and no relocalisation may be wrong. A kidnap into
// corridor 0, looking at its closed end (mapped, and like nothing else), must still relocalise,
// and correctly. Corridor 1 is no such place: from it the camera sees through a door the far
// wall of room A or B, whose twin is in the map, and a relocalisation there was refused in 3
// of 4 tries (rival 50-85 inliers against 86-132, docs/vslam.md).
TEST(VisualSlamSynthetic, RefusesToRelocaliseBetweenTwoMappedLookAlikeRooms) {
  const std::vector<core::SE3> route = both_rooms_route();
  const StereoCamera camera;
  double render_s = 0.0, slam_s = 0.0;
  std::size_t wrong_ok = 0, wrong_relocalised = 0, refusals = 0, distinct_relocalised = 0, runs = 0;
  for (const std::uint64_t seed : {11u, 12u}) {
    const SyntheticWorld world = aliasing_world(seed, seed + 10);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::pair<cv::Mat, cv::Mat>> images;
    for (const core::SE3& pose : route) images.push_back(world.render_stereo(pose, camera));
    render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // Into a room, in room coordinates (x, z - z0): (0.6, 1.2) looking 30 deg right (the far
    // wall and its door, the right wall) or (0.3, 1.8) looking 50 deg left (the left wall and a
    // corner); seed 11 goes into A then B, seed 12 into B then A. Then on into corridor 0,
    // looking at its closed end (mapped, like nothing else in the world).
    const double first_room = seed == 11u ? 0.0 : 10.0, second_room = seed == 11u ? 10.0 : 0.0;
    const std::string tag = "seed " + std::to_string(seed);
    const std::string into_first = tag + (seed == 11u ? ", into A" : ", into B"), into_second = tag + (seed == 11u ? ", into B" : ", into A");
    const std::string into_corridor = tag + ", then into corridor 0";
    const Kidnap to_corridor{into_corridor.c_str(), Eigen::Vector3d(-0.2, 0.0, -1.5), 190.0 * kDeg};
    for (const Kidnap& into_room : {Kidnap{into_first.c_str(), Eigen::Vector3d(0.6, 0.0, first_room + 1.2), 30.0 * kDeg},
                                   Kidnap{into_second.c_str(), Eigen::Vector3d(0.3, 0.0, second_room + 1.8), -50.0 * kDeg}}) {
      const std::vector<KidnapOutcome> outs = run_kidnaps(world, route, images, {into_room, to_corridor}, slam_s);
      ++runs;
      // The route must be tracked within the 0.5 m this test calls right, or "wrong" would mean
      // nothing (measured 2026-11-25: 0.21-0.22 m, drift after the turn at the start).
      EXPECT_LT(outs[0].max_error_before, 0.5) << into_room.name;
      for (std::size_t n = 0; n < outs.size(); ++n) {
        const KidnapOutcome& out = outs[n];
        const char* name = n == 0 ? into_room.name : to_corridor.name;
        wrong_ok += out.wrong_ok;
        wrong_relocalised += out.wrong_relocalised;
        EXPECT_EQ(out.wrong_ok, 0u) << name << ": frames reported ok more than 0.5 m from the truth";
        EXPECT_EQ(out.wrong_relocalised, 0u) << name << ": wrong relocalisations";
      }
      // Not vacuous: the relocalisation saw the two rooms and said so ...
      refusals += outs[0].refusals;
      EXPECT_GT(outs[0].refusals, 0u) << into_room.name << ": no relocalisation was refused as ambiguous";
      // ... and it still relocalises where the place is unique, within 3 frames, correctly.
      distinct_relocalised += outs[1].relocalised_right > 0 ? 1 : 0;
      EXPECT_GT(outs[1].relocalised_right, 0u) << into_room.name << ": corridor 0 was not relocalised";
      EXPECT_LE(outs[1].first_relocalised, 3u) << into_room.name;
    }
  }
  std::printf("both rooms mapped, %zu runs (a kidnap into a room, then into corridor 0): %zu wrong ok frames, %zu wrong relocalisations, "
              "%zu ambiguous refusals, corridor 0 relocalised in %zu of %zu; render %.1f s, SLAM %.1f s\n",
              runs, wrong_ok, wrong_relocalised, refusals, distinct_relocalised, runs, render_s, slam_s);
}


// --- Keyframe culling (ORB-SLAM2 LocalMapping::KeyFrameCulling) ---------------------------------

// A camera that paces up and down room A (2 m, 0.08 m per frame, four times, looking at the far
// wall with the yaw swaying +-20 degrees) sees the same walls again and again; keyframes still come
// every 10 frames or sooner. The same rendered frames go through two runs, culling off and on.
// With ORB-SLAM2's 90 % the rule culls nothing here: cairn does not fuse duplicate points
// (ORB-SLAM2's SearchInNeighbors), so each keyframe holds points that were created again instead
// of matched, seen by one or two keyframes (measured 2026-11-25, the redundant share of a
// keyframe's close points: up to 70 % in the last 26 checks on this route, at most 88 % with the
// camera creeping at 0.02 m per frame, 10-40 % in KITTI's last 15 checks, at most 31 % on TUM
// fr1/desk). The "on" run therefore takes 60 %, to exercise the removal itself: the covisibility
// graph, the points' observations, the parent chain of the trajectory.
TEST(VisualSlamSynthetic, KeyframeCullingThinsARoomSeenAgainAndAgain) {
  const SyntheticWorld world = aliasing_world(11, 21);
  const Eigen::Vector3d near(0.0, 0.0, 1.0), far(0.0, 0.0, 3.0);
  std::vector<core::SE3> truth = test::walk(near, far, 0.08, 0.0, 20.0 * kDeg, 0.3, 2.0);
  test::append(truth, test::walk(far, near, 0.08, 0.0, 20.0 * kDeg, 0.3, 2.0));
  test::append(truth, test::walk(near, far, 0.08, 0.0, 20.0 * kDeg, 0.3, 2.0));
  test::append(truth, test::walk(far, near, 0.08, 0.0, 20.0 * kDeg, 0.3, 2.0));
  const StereoCamera camera;
  std::vector<std::pair<cv::Mat, cv::Mat>> images;
  const auto t0 = std::chrono::steady_clock::now();
  for (const core::SE3& T : truth) images.push_back(world.render_stereo(T, camera));
  const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  struct Outcome {
    std::size_t keyframes_made = 0, keyframes_in_map = 0, culled = 0, tracked = 0;
    double rmse = 0.0, max_error = 0.0;
  };
  auto run = [&](bool culling) {
    VisualSlamOptions options;
    options.keyframe_culling = culling;
    options.keyframe_culling_redundancy = 0.6;
    VisualSlam slam(camera.calibration(), io::SequenceKind::kStereo, options);
    Outcome o;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const FrameResult r = slam.add_stereo(core::Timestamp::from_seconds(0.1 * static_cast<double>(k)), images[k].first, images[k].second);
      o.tracked += r.tracked ? 1 : 0;
    }
    const std::vector<core::SE3> estimate = slam.trajectory();
    EXPECT_EQ(estimate.size(), truth.size());  // every frame keeps a pose, culled reference keyframe or not
    double sum_sq = 0.0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const double e = ((truth.front().inverse() * truth[k]).translation() - estimate[k].translation()).norm();
      sum_sq += e * e;
      o.max_error = std::max(o.max_error, e);
    }
    o.rmse = std::sqrt(sum_sq / static_cast<double>(truth.size()));
    o.keyframes_made = slam.summary().keyframes;
    o.culled = slam.summary().keyframes_culled;
    o.keyframes_in_map = slam.keyframe_frames().size();
    EXPECT_EQ(slam.keyframe_poses().size(), o.keyframes_in_map);
    return o;
  };
  const Outcome off = run(false), on = run(true);
  for (const auto& [name, o] : {std::pair<const char*, const Outcome&>{"off", off}, {"on", on}}) {
    std::printf("culling %-3s: %zu frames, %zu tracked; %zu keyframes made, %zu culled, %zu in the map; position RMSE %.4f m, max %.4f m\n",
                name, truth.size(), o.tracked, o.keyframes_made, o.culled, o.keyframes_in_map, o.rmse, o.max_error);
  }
  std::printf("render %.1f s\n", render_s);
  EXPECT_EQ(off.culled, 0u);
  EXPECT_EQ(off.keyframes_in_map, off.keyframes_made);
  EXPECT_EQ(on.keyframes_in_map, on.keyframes_made - on.culled);
  EXPECT_EQ(on.tracked, truth.size());
  EXPECT_EQ(off.tracked, truth.size());
  // Measured (2026-11-25): off 14 keyframes, RMSE 0.0037 m, max 0.0103 m; on 3 of 14 culled,
  // RMSE 0.0035 m, max 0.0091 m. Limits: about 2.5 x the RMSE and max, and no worse than off by
  // more than 2 mm RMSE.
  EXPECT_LT(on.keyframes_in_map, off.keyframes_in_map);
  EXPECT_LT(on.rmse, 0.01);
  EXPECT_LT(on.max_error, 0.025);
  EXPECT_LT(on.rmse, off.rmse + 0.002);
}

}  // namespace
}  // namespace cairn::vslam

// --- Monocular loop route (scratch, for Sim(3) loop closure) ------------------------------------

namespace cairn::vslam {
namespace {

// A 16 m x 16 m room (x, z in [-8, 8], floor 1.3 m below the camera, ceiling 1.5 m above) with a
// textured pillar (1.2 m square, floor to ceiling) at its centre and two low crates beside it;
// every face has its own seed (no aliasing).
SyntheticWorld monocular_loop_world() {
  SyntheticWorld world;
  const Eigen::Vector3d room_lower(-8.0, kRoomCeilingY, -8.0), room_upper(8.0, kFloorY, 8.0);
  world.add_room(room_lower, room_upper, room_textures(400), room_lower);
  // A box [lower, upper] seen from outside: four sides and its top (when below the ceiling).
  std::uint64_t seed = 420;
  auto box = [&](const Eigen::Vector3d& lower, const Eigen::Vector3d& upper) {
    for (int axis : {0, 2}) {
      for (double side : {lower[axis], upper[axis]}) {
        Eigen::Vector3d l = lower, u = upper;
        l[axis] = u[axis] = side;
        world.add_wall(axis, l, u, seeded(++seed), lower);
      }
    }
    if (lower.y() > kRoomCeilingY) {
      world.add_wall(1, lower, Eigen::Vector3d(upper.x(), lower.y(), upper.z()), seeded(++seed), lower);
    }
  };
  box(Eigen::Vector3d(-0.6, kRoomCeilingY, -0.6), Eigen::Vector3d(0.6, kFloorY, 0.6));  // the pillar
  box(Eigen::Vector3d(0.8, 0.5, 0.5), Eigen::Vector3d(1.5, kFloorY, 1.2));             // crates, tops 0.5 and 0.2 m below the camera
  box(Eigen::Vector3d(-1.4, 0.2, -1.3), Eigen::Vector3d(-0.7, kFloorY, -0.8));
  return world;
}

// A closed loop of four straight legs joined by right turns of radius `corner_m` (a rounded
// rectangle whose legs are `leg_x_m` and `leg_z_m` long, corners excluded), starting half way
// along a leg at `start` heading `yaw0_rad`; the camera looks along the direction of travel plus
// `yaw_offset_rad`. Poses every step_m of arc length from 0 to `length_m` (past one circuit it
// goes round again).
// The camera on a rounded rectangle at arc length s (the route rounded_loop samples): legs of
// leg_x_m and leg_z_m joined by right turns of radius corner_m, from `start` heading yaw0_rad,
// started half way along a leg, looking yaw_offset_rad off the direction of travel.
core::SE3 rounded_loop_pose(const Eigen::Vector3d& start, double yaw0_rad, double leg_x_m, double leg_z_m, double corner_m, double s,
                            double yaw_offset_rad = 0.0) {
  struct Piece {
    double length;
    bool arc;
  };
  const double quarter = 0.5 * kPi * corner_m;
  const Piece pieces[] = {{0.5 * leg_x_m, false}, {quarter, true}, {leg_z_m, false}, {quarter, true}, {leg_x_m, false},
                          {quarter, true},        {leg_z_m, false}, {quarter, true}, {0.5 * leg_x_m, false}};
  double circuit = 0.0;
  for (const Piece& piece : pieces) circuit += piece.length;
  s = std::fmod(s, circuit);
  Eigen::Vector3d p = start;
  double yaw = yaw0_rad;
  for (const Piece& piece : pieces) {
    const double l = std::min(s, piece.length);
    const Eigen::Vector3d forward(std::sin(yaw), 0.0, std::cos(yaw)), right(std::cos(yaw), 0.0, -std::sin(yaw));
    if (!piece.arc) {
      p += l * forward;
    } else {
      const Eigen::Vector3d c = p + corner_m * right;
      const double turned = l / corner_m;
      p = c - corner_m * Eigen::Vector3d(std::cos(yaw + turned), 0.0, -std::sin(yaw + turned));
      yaw += turned;
    }
    s -= l;
    if (s <= 0.0) break;
  }
  return test::camera_pose(p, yaw + yaw_offset_rad);
}

// rounded_loop_pose every step_m (rounded to fit length_m) from 0 to length_m.
std::vector<core::SE3> rounded_loop(const Eigen::Vector3d& start, double yaw0_rad, double leg_x_m, double leg_z_m, double corner_m,
                                    double step_m, double length_m, double yaw_offset_rad = 0.0) {
  const int steps = std::max(1, static_cast<int>(std::lround(length_m / step_m)));
  std::vector<core::SE3> poses;
  for (int k = 0; k <= steps; ++k) {
    poses.push_back(rounded_loop_pose(start, yaw0_rad, leg_x_m, leg_z_m, corner_m, static_cast<double>(k) / static_cast<double>(steps) * length_m,
                                      yaw_offset_rad));
  }
  return poses;
}

// Sum of the distances between consecutive positions of frames [from, to).
double path_length(const std::vector<Eigen::Vector3d>& p, std::size_t from, std::size_t to) {
  double s = 0.0;
  for (std::size_t k = from + 1; k < to; ++k) s += (p[k] - p[k - 1]).norm();
  return s;
}

// What drifted by a frame: the estimate (frames from the initialisation's reference frame on)
// aligned to the truth by the Sim(3) (Umeyama, with scale) of the first quarter of the circuit.
struct MonocularDrift {
  double scale_first_quarter = 0.0;  ///< metres per map unit over the first quarter
  double error_at_end = 0.0, mean_error_last10 = 0.0, max_error = 0.0;
  double ratio_early = 0.0, ratio_last10 = 0.0;  ///< estimated / true distance travelled
  double scale_drift() const { return ratio_last10 / ratio_early; }
};

// `reference`: the initialisation's reference frame (the map's origin); `init`: the first tracked
// frame; `quarter_end`: the first quarter ends there; `end`: the drift is measured at frames up to it.
MonocularDrift monocular_drift(const char* name, const std::vector<core::SE3>& truth, const std::vector<core::SE3>& estimate,
                               std::size_t reference, std::size_t init, std::size_t quarter_end, std::size_t end) {
  std::vector<Eigen::Vector3d> est, gt;
  for (std::size_t k = reference; k <= end; ++k) {
    est.push_back(estimate[k].translation());
    gt.push_back(truth[k].translation());
  }
  const std::size_t n = est.size(), quarter = quarter_end - reference;
  Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(quarter)), b(3, static_cast<Eigen::Index>(quarter));
  for (std::size_t k = 0; k < quarter; ++k) {
    a.col(static_cast<Eigen::Index>(k)) = est[k];
    b.col(static_cast<Eigen::Index>(k)) = gt[k];
  }
  const Eigen::Matrix4d sim3 = Eigen::umeyama(a, b, true);
  MonocularDrift d;
  d.scale_first_quarter = sim3.block<3, 1>(0, 0).norm();
  std::vector<double> errors;
  for (std::size_t k = 0; k < n; ++k) {
    const double e = (sim3.block<3, 3>(0, 0) * est[k] + sim3.block<3, 1>(0, 3) - gt[k]).norm();
    errors.push_back(e);
    d.max_error = std::max(d.max_error, e);
    d.error_at_end = e;
  }
  for (std::size_t k = n - 10; k < n; ++k) d.mean_error_last10 += errors[k] / 10.0;
  const std::size_t early = init - reference + 10;
  d.ratio_early = path_length(est, early, early + 11) / path_length(gt, early, early + 11);
  d.ratio_last10 = path_length(est, n - 11, n) / path_length(gt, n - 11, n);
  std::printf("%s: Sim(3) of frames %zu-%zu: %.4f m per map unit; at frame %zu: error %.3f m, mean over its last 10 frames %.3f m, max "
              "on the way %.3f m; distance estimated / true, frames %zu-%zu %.4f, last 10 %.4f: scale drift %.3f\n",
              name, reference, quarter_end - 1, d.scale_first_quarter, end, d.error_at_end, d.mean_error_last10, d.max_error, init + 10,
              init + 20, d.ratio_early, d.ratio_last10, d.scale_drift());
  std::printf("%s: scale along the way (distance estimated / true per 20 frames, relative to frames %zu-%zu):", name, init + 10, init + 20);
  for (std::size_t k = init - reference; k + 20 < n; k += 20) {
    std::printf(" %zu: %.3f", k + reference, path_length(est, k, k + 21) / path_length(gt, k, k + 21) / d.ratio_early);
  }
  std::printf("\n");
  return d;
}

// The monocular loop route: a rounded square about the room's centre (legs of 4 m, corners of
// radius 1.5 m, 25.4 m round), 0.15 m per frame, started half way along the leg at z = -3.5
// heading -x (the centre to the right) and continued 1.5 m past the start; the camera looks
// `yaw_offset_rad` off the direction of travel. `circuit_m` gets the length of one circuit.
std::vector<core::SE3> monocular_loop_route(double yaw_offset_rad, double& circuit_m, double& extra_m) {
  const double mid = 3.5, corner = 1.5, leg = 2.0 * mid - 2.0 * corner, step = 0.15;
  extra_m = 1.5;
  circuit_m = 4.0 * leg + 2.0 * kPi * corner;
  return rounded_loop(Eigen::Vector3d(0.0, 0.0, -mid), -0.5 * kPi, leg, leg, corner, step, circuit_m + extra_m, yaw_offset_rad);
}

// ATE after a Sim(3) alignment of the whole of frames [from, to] (cairn eval's, as
// evo_ape --align --correct_scale): RMSE and max of the position error.
std::pair<double, double> ate_sim3(const std::vector<core::SE3>& truth, const std::vector<core::SE3>& estimate, std::size_t from,
                                   std::size_t to) {
  io::Trajectory reference, estimated;  // no stamps: paired by index
  reference.poses.assign(truth.begin() + static_cast<std::ptrdiff_t>(from), truth.begin() + static_cast<std::ptrdiff_t>(to) + 1);
  estimated.poses.assign(estimate.begin() + static_cast<std::ptrdiff_t>(from), estimate.begin() + static_cast<std::ptrdiff_t>(to) + 1);
  eval::ApeOptions sim3;
  sim3.alignment.method = eval::AlignmentMethod::kSim3;
  const eval::ApeResult ape = eval::evaluate_ape(reference, estimated, sim3);
  EXPECT_TRUE(ape.outcome.ok()) << ape.outcome.message;
  return {ape.statistics.rmse, ape.statistics.max};
}

// Monocular SLAM round a closed loop with visible drift (scale drift above all), for Sim(3) loop
// closure. The route: a rounded square in the middle of the room (centre line 7 m a side: legs
// of 4 m joined by right turns of radius 1.5 m, 25.4 m round), 0.15 m per frame, started half way
// along a leg and continued 1.5 m past the start; the camera looks 60 degrees left of the
// direction of travel, outward at the walls 4.5-11 m away (a monocular camera cannot turn on the
// spot; here it always translates, partly sideways, and turns 5.7 degrees per frame in the
// corners). Back at the start (frame 169) it stands where it started, looking the same way.
// Tried first (2026-11-25, loops off): looking inward at the pillar (orbit, radius 2.5 m) or along
// a 2 m ring corridor round a 5 m block: every frame tracked, drift at the return only 0.002 and
// 0.16 m, scale drift 1.00 and 1.03; looking outward from a 2.5 m orbit: 0.13 m, 1.09; along the
// ring looking at its outer wall 1 m away, or 45 degrees left in it: lost for 107 and 147 frames.
// This route looking 90 degrees left: 0.13 m, 1.02; 75 left: 0.18 m, 1.03; 45 left: every frame
// "ok" but the scale collapses (distance per frame 0.01 of the start's by the end, error 8 m).
// The images are rendered once and run twice: with loop closure (what is printed frame by frame,
// and every loop candidate) and without (the drift at the return that a loop has to remove).
TEST(VisualSlamSynthetic, MonocularLoopIsClosedOverSim3) {
  const SyntheticWorld world = monocular_loop_world();
  double circuit_m = 0.0, extra = 0.0;
  const std::vector<core::SE3> truth = monocular_loop_route(-60.0 * kDeg, circuit_m, extra);
  const std::size_t return_frame =
      static_cast<std::size_t>(std::lround(circuit_m / (circuit_m + extra) * static_cast<double>(truth.size() - 1)));
  // Within a centimetre of the start (frames fall every step_m of the whole route, not of the circuit).
  ASSERT_LT((truth[return_frame].translation() - truth.front().translation()).norm(), 0.02);
  const StereoCamera camera;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<cv::Mat> images;
  for (const core::SE3& pose : truth) images.push_back(world.render(pose, camera));
  const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  auto run_monocular = [&](bool loop_closure, bool verbose) {
    VisualSlamOptions options;
    options.vocabulary = training_vocabulary();
    options.loop_closure = loop_closure;
    SlamRun run;
    run.truth = truth;
    run.render_s = render_s;
    run.slam = std::make_unique<VisualSlam>(camera.calibration(), io::SequenceKind::kMonocular, options);
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const auto t1 = std::chrono::steady_clock::now();
      FrameResult r = run.slam->add_monocular(core::Timestamp::from_seconds(0.1 * static_cast<double>(k)), images[k]);
      run.slam_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      if (verbose) {
        std::printf("  frame %3zu (yaw %6.1f deg): %-8s kf %d loop %d features %4d motion matches %4d%s%s inliers %4d %s\n", k,
                    yaw_of(truth[k]) / kDeg, health_name(r.health), r.keyframe ? 1 : 0, r.loop_closed ? 1 : 0, r.features,
                    r.motion_matches, r.used_reference ? " (reference)" : "", r.used_image_alignment ? " (image alignment)" : "", r.inliers,
                    r.note.c_str());
      }
      r.keypoints.clear();
      r.keypoint_states.clear();
      run.results.push_back(std::move(r));
    }
    return run;
  };

  const SlamRun run = run_monocular(true, true);
  print_summary("monocular loop route", run);
  const VisualSlamSummary& s = run.slam->summary();
  for (const LoopRecord& loop : s.loops) {
    std::printf("  loop candidate frame %zu -> %zu: score %.3f, %d Sim(3) RANSAC inliers, %d matches, %s (%s), correction %.3f %.2f deg (map "
                "units), scale %.4f; true distance %.2f m\n",
                loop.frame, loop.candidate_frame, loop.score, loop.pnp_inliers, loop.matches, loop.decision.c_str(), loop.reason.c_str(),
                loop.correction_m, loop.correction_deg, loop.scale, (truth[loop.frame].translation() - truth[loop.candidate_frame].translation()).norm());
  }

  // The first tracked frame initialised the map with an earlier reference frame (the map's origin).
  auto initialisation = [&](const SlamRun& r, std::size_t& reference) {
    std::size_t init = 0;
    while (init < truth.size() && !r.results[init].tracked) ++init;
    reference = init;
    if (init < truth.size()) {
      const std::string& note = r.results[init].note;
      const std::size_t at = note.find("with frame ");
      if (at != std::string::npos) reference = static_cast<std::size_t>(std::stoul(note.substr(at + 11)));
    }
    return init;
  };
  std::size_t reference = 0;
  const std::size_t init = initialisation(run, reference);
  ASSERT_LT(init, 15u) << "no monocular initialisation";
  std::size_t tracked = 0, ok = 0, longest_lost = 0, lost_run = 0, first_loop = truth.size(), weakest = init;
  std::vector<core::SE3> online;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const FrameResult& r = run.results[k];
    online.push_back(r.T_world_camera);
    if (r.loop_closed && first_loop == truth.size()) first_loop = k;
    if (k < init) continue;
    tracked += r.tracked ? 1 : 0;
    ok += r.health == TrackingHealth::kOk ? 1 : 0;
    lost_run = r.tracked ? 0 : lost_run + 1;
    longest_lost = std::max(longest_lost, lost_run);
    if (k > init && r.inliers < run.results[weakest].inliers) weakest = k;
  }
  const std::size_t after_init = truth.size() - init;
  const std::size_t quarter_end = reference + (return_frame - reference) / 4;
  // Loop closure on: as reported up to the frame before the first loop closure (or the return),
  // and the final trajectory (corrected by the loops) at the end.
  monocular_drift("loops on, as reported before the first loop", truth, online, reference, init, quarter_end,
                  std::min(return_frame, first_loop - 1));
  const MonocularDrift corrected =
      monocular_drift("loops on, final trajectory", truth, run.slam->trajectory(), reference, init, quarter_end, truth.size() - 1);
  // The same images without loop closure: the drift at the return that a loop has to remove.
  const SlamRun open = run_monocular(false, false);
  std::size_t open_reference = 0;
  const std::size_t open_init = initialisation(open, open_reference);
  ASSERT_EQ(open_init, init);
  std::vector<core::SE3> open_online;
  for (const FrameResult& r : open.results) open_online.push_back(r.T_world_camera);
  const MonocularDrift drift =
      monocular_drift("loops off, as reported", truth, open_online, open_reference, open_init, quarter_end, return_frame);
  monocular_drift("loops off, final trajectory", truth, open.slam->trajectory(), open_reference, open_init, quarter_end, return_frame);
  const auto [ate_loops, ate_loops_max] = ate_sim3(truth, run.slam->trajectory(), init, truth.size() - 1);
  const auto [ate_open, ate_open_max] = ate_sim3(truth, open.slam->trajectory(), init, truth.size() - 1);
  std::printf("monocular loop route, ATE after a Sim(3) alignment of every frame from %zu: with loop closure %.3f m RMSE (max %.3f m), "
              "without %.3f m (max %.3f m)\n",
              init, ate_loops, ate_loops_max, ate_open, ate_open_max);
  std::printf("monocular loop route: %zu frames, initialised at frame %zu (reference %zu); after it %zu / %zu tracked, %zu ok (longest "
              "lost run %zu; fewest inliers %d at frame %zu); %zu ok, %zu degraded, %zu lost in all; %zu keyframes; %zu loop queries, %zu "
              "candidates, %zu accepted (first loop closed at frame %zu); circuit %.2f m; without loops at the return (frame %zu): "
              "error %.3f m, scale drift %.3f; with loops, final trajectory: error at the end %.3f m, max %.3f m; render %.1f s, SLAM "
              "%.1f s + %.1f s\n",
              truth.size(), init, reference, tracked, after_init, ok, longest_lost, run.results[weakest].inliers, weakest, s.frames_ok,
              s.frames_degraded, s.frames_lost, s.keyframes, s.loop_queries, s.loops.size(), s.loops_accepted, first_loop, circuit_m,
              return_frame, drift.error_at_end, drift.scale_drift(), corrected.error_at_end, corrected.max_error, render_s, run.slam_s,
              open.slam_s);
  // Measured 2026-11-25 (docs/vslam.md), with the keyframe on a turn of 0.2 x the field of view:
  // every frame after the first ok; without loop closure 0.236 m off at the return, scale drift
  // 1.079, Sim(3) ATE 0.075 m; with it the loop 159 -> 0 verified over Sim(3) (43 RANSAC inliers,
  // 339 matches, scale 1.047), the end 0.006 m
  // off and the ATE 0.034 m (0.037 m once each frame's pose relative to its keyframe is scaled
  // with the keyframe's Sim(3) correction; re-measured the same day). (Before that keyframe rule: 0.42 m, 1.075 and 0.122 m without
  // loops; loop 158 -> 1 with scale 1.030, 0.005 m and 0.062 m with them.) What this does not
  // show: that the scale of the correction matters. Forced to 1 (tried once, before the keyframe
  // rule), the loop gave 0.006 m, 1.004 and 0.063 m: at the loop the two maps' units differed by
  // 3 % only, and the essential graph, the fusion and the global BA after it fixed the rest.
  EXPECT_GE(10 * tracked, 9 * after_init);
  EXPECT_GT(drift.error_at_end, 0.15) << "the route must drift for the loop to have something to correct";
  int true_loops = 0;
  for (const LoopRecord& loop : s.loops) {
    if (loop.decision != "accepted") continue;
    // The views' true distance: keyframes looking outward at walls 4.5-11 m away see the same
    // place from up to about 2 m apart.
    const double apart = (truth[loop.frame].translation() - truth[loop.candidate_frame].translation()).norm();
    EXPECT_LT(apart, 2.5) << "a loop between frames " << loop.frame << " and " << loop.candidate_frame;
    true_loops += apart < 2.5 ? 1 : 0;
  }
  EXPECT_GE(true_loops, 1);
  EXPECT_LT(corrected.error_at_end, 0.1);
  EXPECT_LT(std::abs(corrected.scale_drift() - 1.0), 0.03);
  EXPECT_LT(ate_loops, 0.75 * ate_open);
}

// The monocular loop route looking 45 degrees left of the travel instead of 60, loop closure off:
// here ORB-SLAM2's keyframe rules alone let the scale collapse in the corners (measured
// 2026-11-25: the distance per frame fell to 0.013 of its early value, the error reached 8 m,
// every frame `ok`; mechanism in docs/vslam.md), and the keyframe on a turn of 0.2 x the field
// of view (VisualSlamOptions::monocular_keyframe_turn_fov) holds it. Both runs on one rendering.
TEST(VisualSlamSynthetic, MonocularScaleHoldsThroughFastTurns) {
  const SyntheticWorld world = monocular_loop_world();
  double circuit_m = 0.0, extra = 0.0;
  const std::vector<core::SE3> truth = monocular_loop_route(-45.0 * kDeg, circuit_m, extra);
  const StereoCamera camera;
  std::vector<cv::Mat> images;
  for (const core::SE3& pose : truth) images.push_back(world.render(pose, camera));
  struct Outcome {
    double scale_drift, ate, ate_max;
    std::size_t ok, keyframes;
  };
  auto run = [&](double turn_fov) {
    VisualSlamOptions options;
    options.loop_closure = false;
    options.monocular_keyframe_turn_fov = turn_fov;
    VisualSlam slam(camera.calibration(), io::SequenceKind::kMonocular, options);
    std::vector<core::SE3> online;
    std::size_t init = truth.size();
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const FrameResult r = slam.add_monocular(core::Timestamp::from_seconds(0.1 * static_cast<double>(k)), images[k]);
      if (r.tracked && init == truth.size()) init = k;
      online.push_back(r.T_world_camera);
    }
    EXPECT_LT(init, 15u) << "no monocular initialisation";
    const MonocularDrift d = monocular_drift(turn_fov > 0.0 ? "turn rule on" : "turn rule off", truth, online, 0, init,
                                             init + (truth.size() - init) / 4, truth.size() - 1);
    const auto [ate, ate_max] = ate_sim3(truth, slam.trajectory(), init, truth.size() - 1);
    return Outcome{d.scale_drift(), ate, ate_max, slam.summary().frames_ok, slam.summary().keyframes};
  };
  const Outcome off = run(0.0), on = run(0.2);
  std::printf("monocular, 45 degrees left, loops off: without the turn rule scale drift %.3f, Sim(3) ATE %.3f m (max %.3f m), %zu ok, %zu "
              "keyframes; with it %.3f, %.3f m (max %.3f m), %zu ok, %zu keyframes\n",
              off.scale_drift, off.ate, off.ate_max, off.ok, off.keyframes, on.scale_drift, on.ate, on.ate_max, on.ok, on.keyframes);
  EXPECT_GT(on.scale_drift, 0.8);
  EXPECT_LT(on.scale_drift, 1.25);
  EXPECT_LT(on.ate, 0.3);
}

// The monocular loop route (monocular_loop_route) looking `yaw_offset_rad` off the travel, flown
// at 1.5 m/s with the simulator's IMU (ADIS16448, seed 7) on the camera's body (inertial_flight.hpp's
// mounting): the frames' true poses and period, the IMU's readings, the rendered images.
// `route_mismatch_m`: the closed-form path the IMU flies against the route's frame 10 (0 when
// both are the same route).
struct InertialLoopFlight {
  std::vector<core::SE3> truth;
  double frame_s = 0.0;
  double route_mismatch_m = 0.0;
  sim::ImuSimulationOptions imu;
  sim::SimulatedImu simulated;
  std::vector<cv::Mat> images;
};

InertialLoopFlight fly_inertial_loop(const SyntheticWorld& world, const StereoCamera& camera, double yaw_offset_rad) {
  InertialLoopFlight flight;
  double circuit_m = 0.0, extra = 0.0;
  flight.truth = monocular_loop_route(yaw_offset_rad, circuit_m, extra);
  const double mid = 3.5, corner = 1.5, leg = 2.0 * mid - 2.0 * corner, speed_mps = 1.5;  // monocular_loop_route's
  const double duration_s = (circuit_m + extra) / speed_mps;
  flight.frame_s = duration_s / static_cast<double>(flight.truth.size() - 1);
  const auto camera_at = [&](double t) {
    return rounded_loop_pose(Eigen::Vector3d(0.0, 0.0, -mid), -0.5 * kPi, leg, leg, corner, speed_mps * t, yaw_offset_rad);
  };
  flight.route_mismatch_m = (camera_at(flight.frame_s * 10.0).translation() - flight.truth[10].translation()).norm();
  flight.imu = *sim::imu_preset("adis16448");
  flight.imu.seed = 7;
  flight.simulated = sim::simulate_imu([&](double t) { return test::kinematics_of(camera_at, t); }, 0.0, duration_s + 0.2, flight.imu);
  for (const core::SE3& pose : flight.truth) flight.images.push_back(world.render(pose, camera));
  return flight;
}

// Options with the flight's IMU on (its noise, the camera's mounting).
VisualSlamOptions with_flight_imu(VisualSlamOptions options, const InertialLoopFlight& flight) {
  options.inertial.enabled = true;
  options.inertial.T_body_camera = test::T_body_camera();
  options.inertial.noise = flight.imu.noise;
  return options;
}

// The IMU's readings up to the first at or after frame k's time (the prediction's last interval);
// `next` is the first reading not given yet.
void feed_imu_to_frame(VisualSlam& slam, const InertialLoopFlight& flight, std::size_t k, std::size_t& next) {
  const double t = flight.frame_s * static_cast<double>(k);
  while (next < flight.simulated.samples.size()) {
    slam.add_imu(flight.simulated.samples[next]);
    if (flight.simulated.samples[next++].stamp.seconds() >= t) break;
  }
}

// Issue 40: a monocular scale collapse flagged by the IMU. The route of the test above (45 degrees
// left, loops off) flown at 1.5 m/s with the simulator's IMU (ADIS16448, seed 7) on the camera's
// body (inertial_flight.hpp's mounting): without the turn rule the scale collapses (above); the
// inertial estimate at each keyframe, which also estimates the scale, must then flag frames
// `degraded`, and the run with the rule, whose scale holds, must flag none. Those two runs keep
// the IMU out of the pose optimisation and the local BA (inertial.pose_optimisation and
// inertial.local_ba off); with it in, the collapse does not happen.
TEST(VisualSlamSynthetic, MonocularScaleCollapseIsFlaggedByTheImu) {
  const SyntheticWorld world = monocular_loop_world();
  const StereoCamera camera;
  const InertialLoopFlight flight = fly_inertial_loop(world, camera, -45.0 * kDeg);
  ASSERT_LT(flight.route_mismatch_m, 1e-9);
  const std::vector<core::SE3>& truth = flight.truth;
  struct Outcome {
    double scale_drift, ate;  // the map's scale over the last quarter relative to the first
    std::size_t flagged, first_flagged;
    VisualSlamSummary summary;
  };
  auto run = [&](double turn_fov, bool imu_in_optimisations) {
    VisualSlamOptions options = with_flight_imu({}, flight);
    options.loop_closure = false;
    options.monocular_keyframe_turn_fov = turn_fov;
    options.inertial.local_ba = imu_in_optimisations;
    options.inertial.pose_optimisation = imu_in_optimisations;
    VisualSlam slam(camera.calibration(), io::SequenceKind::kMonocular, options);
    std::size_t init = truth.size(), first_flagged = truth.size(), next = 0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      feed_imu_to_frame(slam, flight, k, next);
      const FrameResult r = slam.add_monocular(core::Timestamp::from_seconds(flight.frame_s * static_cast<double>(k)), flight.images[k]);
      if (r.tracked && init == truth.size()) init = k;
      if (first_flagged == truth.size() && r.note.find("monocular scale drift") != std::string::npos) first_flagged = k;
    }
    EXPECT_LT(init, 15u) << "no monocular initialisation";
    const std::vector<core::SE3> final_poses = slam.trajectory();
    const auto [ate, ate_max] = ate_sim3(truth, final_poses, init, truth.size() - 1);
    // Metres per map unit over the first and the last quarter of the final trajectory (the first
    // inertial estimate rescales the map during the run, so the online poses change unit there).
    auto unit = [&](std::size_t from, std::size_t to) {
      Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(to - from)), b(3, static_cast<Eigen::Index>(to - from));
      for (std::size_t k = from; k < to; ++k) {
        a.col(static_cast<Eigen::Index>(k - from)) = final_poses[k].translation();
        b.col(static_cast<Eigen::Index>(k - from)) = truth[k].translation();
      }
      return Eigen::umeyama(a, b, true).block<3, 1>(0, 0).norm();
    };
    const std::size_t quarter = (truth.size() - init) / 4;
    const double first_unit = unit(init, init + quarter), last_unit = unit(truth.size() - quarter, truth.size());
    std::printf("  turn rule %s, IMU in the pose optimisation and the local BA %s: metres per map unit %.3f over the first quarter, %.3f over the last; Sim(3) ATE %.3f m (max %.3f m)\n",
                turn_fov > 0.0 ? "on" : "off", imu_in_optimisations ? "on" : "off", first_unit, last_unit, ate, ate_max);
    return Outcome{first_unit / last_unit, ate, slam.summary().frames_scale_drifted, first_flagged, slam.summary()};
  };
  // The IMU only watching (inertial.local_ba and inertial.pose_optimisation off) without and with
  // the turn rule, then with its factors in the pose optimisation and the local bundle adjustment
  // (the default) without and with it.
  const Outcome off = run(0.0, false), on = run(0.2, false), off_ba = run(0.0, true), on_ba = run(0.2, true);
  for (const auto& [name, o] : {std::pair<const char*, const Outcome&>{"off", off}, {"on", on}, {"off, IMU in the optimisations", off_ba},
                                {"on, IMU in the optimisations", on_ba}}) {
    std::printf("monocular-inertial, 45 degrees left, turn rule %s: the map's scale at the end %.3f of the start's; IMU: initial scale %.3f, "
                "%zu estimates (%zu refused, %zu unexcited), last judged scale %.3f, %zu frames flagged for scale drift (first at frame %zu)\n",
                name, o.scale_drift, o.summary.monocular_initial_scale, o.summary.inertial_estimates, o.summary.inertial_estimates_refused,
                o.summary.scale_estimates_unexcited, o.summary.monocular_scale_estimate, o.flagged, o.first_flagged);
  }
  // The flag follows the truth: frames flagged when the scale drifted by more than a quarter
  // (max_scale_drift), none when it held within 10 %.
  for (const Outcome* o : {&off, &on, &on_ba}) {
    if (std::abs(o->scale_drift - 1.0) > 0.25) {
      EXPECT_GE(o->flagged, 1u);
    }
    if (std::abs(o->scale_drift - 1.0) < 0.1) {
      EXPECT_EQ(o->flagged, 0u);
    }
  }
  EXPECT_LT(off.scale_drift, 0.75);  // the scenario: the scale does collapse without the rule
  EXPECT_NEAR(on.scale_drift, 1.0, 0.1);  // and holds with it
  // With the IMU's factors in the pose optimisation and the local BA (ORB-SLAM3's remedy) the
  // scale holds without the rule too. Measured, not asserted: without the rule the windowed scale
  // estimates still judge the turns' windows off and flag frames although the scale holds
  // (docs/vslam.md).
  EXPECT_NEAR(off_ba.scale_drift, 1.0, 0.1);
  EXPECT_NEAR(on_ba.scale_drift, 1.0, 0.1);
  EXPECT_EQ(on_ba.flagged, 0u);
  EXPECT_GT(off_ba.summary.inertial_local_bas, 0u);
  EXPECT_EQ(off.summary.inertial_local_bas, 0u);
}

// Issue 40: a visual-inertial map's loop is corrected in 4 DoF (yaw and position), keeping the
// gravity direction every keyframe has from the IMU. The monocular loop route looking 60 degrees
// left (MonocularLoopIsClosedOverSim3) flown at 1.5 m/s with the simulator's IMU, loops on, run
// with inertial.four_dof_loops on (the default) and off (the Sim(3) correction of a map without
// an IMU). Each frame's tilt error is the angle between gravity's direction in the camera as the
// run has it (the final gravity estimate, turned by the frame's rotation) and as the truth has it:
// no alignment is involved.
TEST(VisualSlamSynthetic, VisualInertialLoopIsCorrectedInFourDof) {
  const SyntheticWorld world = monocular_loop_world();
  const StereoCamera camera;
  const InertialLoopFlight flight = fly_inertial_loop(world, camera, -60.0 * kDeg);
  ASSERT_LT(flight.route_mismatch_m, 1e-9);
  const std::vector<core::SE3>& truth = flight.truth;
  const Eigen::Vector3d gravity_render = (test::R_render_imu() * Eigen::Vector3d(0.0, 0.0, -1.0)).normalized();
  struct Outcome {
    double ate_se3 = 0.0, ate_sim3 = 0.0, tilt_median_deg = 0.0, tilt_max_deg = 0.0;
    std::size_t accepted = 0, first_loop = 0;
    VisualSlamSummary summary;
  };
  auto run = [&](bool four_dof) {
    VisualSlamOptions options = with_flight_imu({}, flight);
    options.vocabulary = training_vocabulary();
    options.inertial.four_dof_loops = four_dof;
    VisualSlam slam(camera.calibration(), io::SequenceKind::kMonocular, options);
    Outcome o;
    o.first_loop = truth.size();
    std::size_t init = truth.size(), next = 0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      feed_imu_to_frame(slam, flight, k, next);
      const FrameResult r = slam.add_monocular(core::Timestamp::from_seconds(flight.frame_s * static_cast<double>(k)), flight.images[k]);
      if (r.tracked && init == truth.size()) init = k;
      if (r.loop_closed && o.first_loop == truth.size()) o.first_loop = k;
    }
    EXPECT_LT(init, 15u) << "no monocular initialisation";
    o.summary = slam.summary();
    for (const LoopRecord& loop : o.summary.loops) o.accepted += loop.decision == "accepted" ? 1 : 0;
    const std::vector<core::SE3> poses = slam.trajectory();
    io::Trajectory reference, estimated;
    reference.poses.assign(truth.begin() + static_cast<std::ptrdiff_t>(init), truth.end());
    estimated.poses.assign(poses.begin() + static_cast<std::ptrdiff_t>(init), poses.end());
    for (const eval::AlignmentMethod method : {eval::AlignmentMethod::kSE3, eval::AlignmentMethod::kSim3}) {
      eval::ApeOptions ape_options;
      ape_options.alignment.method = method;
      const eval::ApeResult ape = eval::evaluate_ape(reference, estimated, ape_options);
      EXPECT_TRUE(ape.outcome.ok()) << ape.outcome.message;
      (method == eval::AlignmentMethod::kSE3 ? o.ate_se3 : o.ate_sim3) = ape.statistics.rmse;
    }
    const Eigen::Vector3d g = slam.gravity_world().normalized();
    std::vector<double> tilt;
    for (std::size_t k = init; k < truth.size(); ++k) {
      const Eigen::Vector3d seen = poses[k].so3().inverse() * g, true_seen = truth[k].so3().inverse() * gravity_render;
      tilt.push_back(std::atan2(seen.cross(true_seen).norm(), seen.dot(true_seen)) / kDeg);
    }
    if (!tilt.empty()) {
      std::sort(tilt.begin(), tilt.end());
      o.tilt_median_deg = tilt[tilt.size() / 2];
      o.tilt_max_deg = *std::max_element(tilt.begin(), tilt.end());
    }
    std::printf("monocular-inertial loop route, 4-DoF loops %s: %zu loops accepted (first at frame %zu), %zu corrected in 4 DoF; SE(3) ATE "
                "%.3f m, Sim(3) ATE %.3f m; tilt error median %.2f deg, max %.2f deg\n",
                four_dof ? "on" : "off", o.accepted, o.first_loop, o.summary.loops_corrected_in_4dof, o.ate_se3, o.ate_sim3, o.tilt_median_deg,
                o.tilt_max_deg);
    return o;
  };
  const Outcome four = run(true), similarity = run(false);
  EXPECT_GE(four.accepted, 1u);
  EXPECT_EQ(four.summary.loops_corrected_in_4dof, four.accepted);
  EXPECT_EQ(similarity.summary.loops_corrected_in_4dof, 0u);
  EXPECT_GT(four.summary.inertial_local_bas, 0u);
  // Both close the loop well; neither is asserted better (measured: the 4-DoF correction cannot
  // take out the few percent of scale drift a Sim(3) one does: docs/vslam.md).
  for (const Outcome* o : {&four, &similarity}) {
    EXPECT_LT(o->ate_sim3, 0.1);
    EXPECT_LT(o->ate_se3, 0.5);
    EXPECT_LT(o->tilt_max_deg, 3.0);
  }
}

// A monocular run of `truth` with the lens covered (uniform grey images) where `covered` says so;
// frames for which `show` holds are printed. The results keep no keypoints.
std::vector<FrameResult> run_monocular_covered(VisualSlam& slam, const SyntheticWorld& world, const std::vector<core::SE3>& truth,
                                               const StereoCamera& camera, const std::function<bool(std::size_t)>& covered,
                                               const std::function<bool(std::size_t, const FrameResult&)>& show) {
  std::vector<FrameResult> results;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const cv::Mat image = covered(k) ? cv::Mat(camera.height, camera.width, CV_8UC1, cv::Scalar(128)) : world.render(truth[k], camera);
    FrameResult r = slam.add_monocular(core::Timestamp::from_seconds(0.1 * static_cast<double>(k)), image);
    if (show(k, r)) {
      std::printf("  frame %3zu%s: %-8s segment %d kf %d new map %d reloc %d loop %d inliers %4d %s\n", k, covered(k) ? " (covered)" : "",
                  health_name(r.health), r.segment, r.keyframe ? 1 : 0, r.new_map ? 1 : 0, r.relocalised ? 1 : 0, r.loop_closed ? 1 : 0,
                  r.inliers, r.note.c_str());
    }
    r.keypoints.clear();
    r.keypoint_states.clear();
    results.push_back(std::move(r));
  }
  return results;
}

// The tracked frames at the end of a run: how many, how many outside the first map, and the
// Sim(3) ATE (RMSE, max) of those in it against the truth.
struct MainMapResult {
  std::size_t tracked = 0, outside_main = 0, in_main = 0;
  double ate = 0.0, ate_max = 0.0;
};
MainMapResult main_map_against_truth(const VisualSlam& slam, const std::vector<FrameResult>& results, const std::vector<core::SE3>& truth) {
  const std::vector<int> segments = slam.frame_segments();
  const std::vector<core::SE3> estimate = slam.trajectory();
  std::vector<core::SE3> truth_tracked, estimate_tracked;
  MainMapResult m;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    if (!results[k].tracked) continue;
    ++m.tracked;
    if (segments[k] != slam.main_segment()) {
      ++m.outside_main;
      continue;
    }
    truth_tracked.push_back(truth[k]);
    estimate_tracked.push_back(estimate[k]);
  }
  m.in_main = truth_tracked.size();
  std::tie(m.ate, m.ate_max) = ate_sim3(truth_tracked, estimate_tracked, 0, truth_tracked.size() - 1);
  return m;
}

// Accepted loops and merges joining views more than 2.5 m apart (the loop test's rule: keyframes
// looking at walls 4.5-11 m away see the same place from up to about 2 m apart).
int far_joins(const VisualSlamSummary& s, const std::vector<core::SE3>& truth) {
  int n = 0;
  for (const LoopRecord& loop : s.loops) {
    if (loop.decision != "accepted") continue;
    n += (truth[loop.frame].translation() - truth[loop.candidate_frame].translation()).norm() > 2.5 ? 1 : 0;
  }
  return n;
}

// The Atlas for one camera: the monocular loop route (60 degrees left, as the loop test) with
// the lens covered for frames [45, 80) (5.2 m, the second corner included: uniform grey images).
// Tracking must say `lost` under the cover, start a new map segment by a two-view initialisation
// once the images come back (the view then is of walls the first map never saw), and merge it
// into the first map over Sim(3) when the camera comes back to the start; afterwards every
// tracked frame is in the first map, and no merge or loop joins views more than 2.5 m apart.
TEST(VisualSlamSynthetic, MonocularNewMapAfterTheLensIsCoveredMergesAtTheReturn) {
  const SyntheticWorld world = monocular_loop_world();
  double circuit_m = 0.0, extra = 0.0;
  const std::vector<core::SE3> truth = monocular_loop_route(-60.0 * kDeg, circuit_m, extra);
  const std::size_t cover_from = 45, cover_to = 80;
  const StereoCamera camera;
  VisualSlamOptions options;
  options.vocabulary = training_vocabulary();
  VisualSlam slam(camera.calibration(), io::SequenceKind::kMonocular, options);
  const std::vector<FrameResult> results = run_monocular_covered(
      slam, world, truth, camera, [&](std::size_t k) { return k >= cover_from && k < cover_to; },
      [&](std::size_t k, const FrameResult& r) {
        return k + 5 >= cover_from && (k < cover_to + 15 || r.new_map || r.loop_closed || r.health != TrackingHealth::kOk);
      });
  const VisualSlamSummary& s = slam.summary();
  for (const LoopRecord& loop : s.loops) {
    if (loop.decision == "rejected") continue;
    std::printf("  %s frame %zu -> %zu: %s (%s), scale %.4f, correction %.3f %.2f deg (map units); true distance %.2f m\n",
                loop.merge ? "merge" : "loop", loop.frame, loop.candidate_frame, loop.decision.c_str(), loop.reason.c_str(), loop.scale,
                loop.correction_m, loop.correction_deg, (truth[loop.frame].translation() - truth[loop.candidate_frame].translation()).norm());
  }
  std::size_t covered_ok = 0, new_map_at = truth.size(), merged_at = truth.size(), init = truth.size();
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const FrameResult& r = results[k];
    if (r.tracked && init == truth.size()) init = k;
    if (k >= cover_from && k < cover_to) covered_ok += r.health == TrackingHealth::kOk ? 1 : 0;
    if (k >= cover_to && r.new_map && new_map_at == truth.size()) new_map_at = k;
    if (k > new_map_at && r.loop_closed && merged_at == truth.size()) merged_at = k;
  }
  // Every tracked frame in the first map at the end, and the whole of them against the truth.
  const MainMapResult m = main_map_against_truth(slam, results, truth);
  const int far = far_joins(s, truth);
  std::printf("monocular, lens covered for frames %zu-%zu: initialised at %zu; %zu covered frames reported ok; new map at frame %zu, "
              "merged at frame %zu; %zu maps started, %zu merged, %zu relocalisations; %zu tracked frames, %zu outside the first map; "
              "Sim(3) ATE of the first map's %zu frames %.3f m (max %.3f m); %d joins of views > 2.5 m apart\n",
              cover_from, cover_to - 1, init, covered_ok, new_map_at, merged_at, s.maps_started, s.maps_merged, s.relocalisations, m.tracked,
              m.outside_main, m.in_main, m.ate, m.ate_max, far);
  EXPECT_LT(init, 15u);
  EXPECT_EQ(covered_ok, 0u) << "a frame of a covered lens reported ok";
  EXPECT_LE(new_map_at, cover_to + 10) << "no new map within 10 frames of the lens being uncovered";
  EXPECT_GE(s.maps_merged, 1u);
  EXPECT_EQ(far, 0) << "a merge or loop joined views more than 2.5 m apart";
  EXPECT_EQ(m.outside_main, 0u) << "tracked frames left outside the first map";
  EXPECT_GE(m.tracked, truth.size() - (cover_to - cover_from) - 25);
  EXPECT_LT(m.ate, 0.25);
}

// The merge whose querying keyframe lies in the older segment: two laps of the monocular loop
// route with the lens covered twice. Under the first cover (frames 45-79) tracking is lost and
// segment 1 starts after it; under the second (frames 150-174, in segment 1) it is lost again
// and, back at the start, relocalises into segment 0, which maps the second lap; when the second
// lap reaches the stretch only segment 1 saw, a keyframe of segment 0 recognises segment 1's
// keyframes and the younger segment 1 is moved onto segment 0.
TEST(VisualSlamSynthetic, MonocularMergeFromTheOlderSegmentMovesTheYoungerOne) {
  const SyntheticWorld world = monocular_loop_world();
  double circuit_m = 0.0, extra = 0.0;
  monocular_loop_route(-60.0 * kDeg, circuit_m, extra);
  const double mid = 3.5, corner = 1.5, leg = 2.0 * mid - 2.0 * corner;
  const std::vector<core::SE3> truth =
      rounded_loop(Eigen::Vector3d(0.0, 0.0, -mid), -0.5 * kPi, leg, leg, corner, 0.15, 2.0 * circuit_m + extra, -60.0 * kDeg);
  const auto covered = [](std::size_t k) { return (k >= 45 && k < 80) || (k >= 150 && k < 175); };
  const StereoCamera camera;
  VisualSlamOptions options;
  options.vocabulary = training_vocabulary();
  VisualSlam slam(camera.calibration(), io::SequenceKind::kMonocular, options);
  const std::vector<FrameResult> results =
      run_monocular_covered(slam, world, truth, camera, covered, [&](std::size_t k, const FrameResult& r) {
        return r.new_map || r.loop_closed || r.relocalised || (r.health == TrackingHealth::kLost && !covered(k));
      });
  const VisualSlamSummary& s = slam.summary();
  for (const LoopRecord& loop : s.loops) {
    if (loop.decision == "rejected") continue;
    std::printf("  %s frame %zu (segment %d) -> %zu (segment %d): %s (%s), scale %.4f; true distance %.2f m\n", loop.merge ? "merge" : "loop",
                loop.frame, results[loop.frame > 0 ? loop.frame - 1 : 0].segment, loop.candidate_frame, results[loop.candidate_frame].segment,
                loop.decision.c_str(), loop.reason.c_str(), loop.scale, (truth[loop.frame].translation() - truth[loop.candidate_frame].translation()).norm());
  }
  const MainMapResult m = main_map_against_truth(slam, results, truth);
  const core::SE3 first = slam.trajectory().front();
  // The older segment keeps its frame: the map's first pose (frame 0, the initialisation's
  // reference) stays where the initialisation put it, at the origin.
  const double origin_moved = first.translation().norm();
  const double origin_turned_deg = Eigen::AngleAxisd(first.rotation_matrix()).angle() / kDeg;
  const int far = far_joins(s, truth);
  int merges_from_older = 0;
  for (const LoopRecord& loop : s.loops) {
    merges_from_older +=
        loop.decision == "accepted" && loop.merge && results[loop.frame - 1].segment == 0 && results[loop.candidate_frame].segment == 1 ? 1 : 0;
  }
  std::printf("two laps, lens covered twice: %zu frames, %zu tracked, %zu outside the first map; %zu maps started, %zu merged (%d "
              "queried from segment 0), %zu relocalisations; frame 0 now %.4f map units and %.3f deg from the origin; Sim(3) ATE %.3f m "
              "(max %.3f m); %d joins of views > 2.5 m apart\n",
              truth.size(), m.tracked, m.outside_main, s.maps_started, s.maps_merged, merges_from_older, s.relocalisations, origin_moved,
              origin_turned_deg, m.ate, m.ate_max, far);
  ASSERT_GE(merges_from_older, 1) << "the scenario did not produce a merge queried from the older segment";
  EXPECT_EQ(far, 0);
  EXPECT_EQ(m.outside_main, 0u);
  EXPECT_LT(origin_moved, 0.05);
  EXPECT_LT(origin_turned_deg, 2.0);
  EXPECT_LT(m.ate, 0.25);
}

}  // namespace
}  // namespace cairn::vslam
