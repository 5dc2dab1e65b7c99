// Generalized-ICP (lidar3d/gicp.hpp): a synthetic scene with a known motion, a guess with no
// overlap, real KITTI key-frame pairs against the GNSS/INS reference, and hostile input.

#include <gtest/gtest.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/gicp.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"
#include "kitti_key_frames.hpp"
#include "test_data.hpp"

namespace cairn::lidar3d {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// `count` points drawn uniformly on the faces of the axis-aligned box [low, high], each moved by
// Gaussian noise of `noise_m` per axis.
void sample_box(const Eigen::Vector3d& low, const Eigen::Vector3d& high, int count, double noise_m, std::mt19937& rng,
                std::vector<Eigen::Vector3d>& points) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_m);
  const Eigen::Vector3d size = high - low;
  const double areas[3] = {size.y() * size.z(), size.x() * size.z(), size.x() * size.y()};
  const double total = 2.0 * (areas[0] + areas[1] + areas[2]);
  for (int i = 0; i < count; ++i) {
    double pick = unit(rng) * total;
    int axis = 0;
    while (axis < 2 && pick > 2.0 * areas[axis]) pick -= 2.0 * areas[axis++];
    Eigen::Vector3d p = low + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).cwiseProduct(size);
    p(axis) = unit(rng) < 0.5 ? low(axis) : high(axis);
    points.push_back(p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
}

// A room (8 x 6 x 3 m) with three boxes of different sizes in it: every direction constrained.
// Each call samples new points, so a target and a source share no point.
std::vector<Eigen::Vector3d> scene(std::mt19937& rng, double noise_m = 0.002) {
  std::vector<Eigen::Vector3d> points;
  sample_box({-4.0, -3.0, -1.5}, {4.0, 3.0, 1.5}, 12000, noise_m, rng, points);
  sample_box({1.0, 0.5, -1.5}, {2.0, 1.5, -0.5}, 1500, noise_m, rng, points);
  sample_box({-2.5, -2.0, -1.5}, {-2.0, 0.0, 0.0}, 1500, noise_m, rng, points);
  sample_box({-1.0, 1.8, -1.5}, {0.2, 2.4, -1.1}, 1000, noise_m, rng, points);
  return points;
}

std::vector<Eigen::Vector3d> transform(const core::SE3& T, std::vector<Eigen::Vector3d> points) {
  for (Eigen::Vector3d& p : points) p = T * p;
  return points;
}

double translation_error_m(const core::SE3& reference, const core::SE3& estimate) {
  return (reference.inverse() * estimate).translation().norm();
}
double rotation_error_rad(const core::SE3& reference, const core::SE3& estimate) {
  return (reference.inverse() * estimate).so3().log().norm();
}

struct SyntheticPair {
  GicpCloud target, source;
  core::SE3 T_target_source;
};

SyntheticPair synthetic_pair(const GicpOptions& options) {
  std::mt19937 rng(42);
  const core::SE3 T_target_source(core::SO3::from_rpy(0.02, -0.015, 0.12), Eigen::Vector3d(0.3, -0.2, 0.05));
  GicpCloud target(scene(rng), options);
  GicpCloud source(transform(T_target_source.inverse(), scene(rng)), options);
  return {std::move(target), std::move(source), T_target_source};
}

// The guess is 0.5 m and 5 deg from the truth, so correspondences must reach 1.5 m at the walls.
GicpOptions synthetic_options() {
  GicpOptions options;
  options.max_correspondence_m = 1.5;
  return options;
}
const core::SE3 kGuessOffset(core::SO3::exp(Eigen::Vector3d(1.0, -2.0, 2.0).normalized() * 5.0 * kDeg),
                             Eigen::Vector3d(0.3, 0.4, 0.0));

TEST(Gicp, RecoversAKnownMotionFromAGuessHalfAMetreAndFiveDegreesOff) {
  const GicpOptions options = synthetic_options();
  const SyntheticPair pair = synthetic_pair(options);
  const core::SE3 guess = pair.T_target_source * kGuessOffset;
  ASSERT_NEAR(translation_error_m(pair.T_target_source, guess), 0.5, 1e-9);
  ASSERT_NEAR(rotation_error_rad(pair.T_target_source, guess), 5.0 * kDeg, 1e-9);
  const GicpResult r = register_gicp(pair.target, pair.source, guess, options);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(r.iterations, options.max_iterations);
  std::printf("synthetic: %d iterations, error %.2e m %.2e deg\n", r.iterations,
              translation_error_m(pair.T_target_source, r.T_target_source),
              rotation_error_rad(pair.T_target_source, r.T_target_source) / kDeg);
  EXPECT_LT(translation_error_m(pair.T_target_source, r.T_target_source), 1e-3);
  EXPECT_LT(rotation_error_rad(pair.T_target_source, r.T_target_source), 0.01 * kDeg);
  EXPECT_EQ(r.source_points, pair.source.size());
  EXPECT_GT(r.fitness, 0.99);
  // Independent uniform samples of the same surfaces: a point's nearest other-sample point lies at
  // an RMS distance of 1/sqrt(pi rho) = 6.9 cm at the walls' rho = 12000 / 180 m^2.
  EXPECT_LT(r.inlier_rmse_m, 0.08);
  // J^T W J of a fully constrained scene: symmetric positive definite.
  EXPECT_TRUE(r.hessian.isApprox(r.hessian.transpose()));
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6>(r.hessian).eigenvalues()(0), 0.0);
}

TEST(Gicp, SameResultOnAnyThreadsConcurrentlyAndAfterMovingTheClouds) {
  const GicpOptions options = synthetic_options();
  // Fresh clouds for every run, so that each computes its covariances as it goes.
  SyntheticPair a = synthetic_pair(options), b = synthetic_pair(options), c = synthetic_pair(options);
  const core::SE3 guess = a.T_target_source * kGuessOffset;
  GicpResult one, two, first, second;
  tbb::task_arena(1).execute([&] { one = register_gicp(a.target, a.source, guess, options); });
  tbb::task_arena(2).execute([&] { two = register_gicp(b.target, b.source, guess, options); });
  EXPECT_EQ(one.T_target_source.matrix(), two.T_target_source.matrix());
  EXPECT_EQ(one.iterations, two.iterations);
  // Two registrations sharing the same clouds at once, racing to fill the same covariances.
  tbb::task_arena(2).execute([&] {
    tbb::parallel_invoke([&] { first = register_gicp(c.target, c.source, guess, options); },
                         [&] { second = register_gicp(c.target, c.source, guess, options); });
  });
  EXPECT_EQ(first.T_target_source.matrix(), one.T_target_source.matrix());
  EXPECT_EQ(second.T_target_source.matrix(), one.T_target_source.matrix());
  // The k-d trees refer to the points' buffers, which a move hands over.
  std::vector<GicpCloud> moved;
  moved.push_back(std::move(a.target));
  moved.push_back(std::move(a.source));
  const GicpResult again = register_gicp(moved[0], moved[1], guess, options);
  EXPECT_EQ(again.T_target_source.matrix(), one.T_target_source.matrix());
}

// Coarse to fine over the source's points (GicpOptions::sparse_stride): every 4th point first,
// then all of them. The same truth is recovered as closely, the result's statistics are those of
// all points, and the sparse iterations count towards the limit.
TEST(Gicp, SparseFirstIterationsRecoverTheKnownMotionAndReportOnAllPoints) {
  GicpOptions options = synthetic_options();
  options.sparse_stride = 4;
  const SyntheticPair pair = synthetic_pair(options);
  const core::SE3 guess = pair.T_target_source * kGuessOffset;
  const GicpResult r = register_gicp(pair.target, pair.source, guess, options);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(translation_error_m(pair.T_target_source, r.T_target_source), 1e-3);
  EXPECT_LT(rotation_error_rad(pair.T_target_source, r.T_target_source), 0.01 * kDeg);
  EXPECT_EQ(r.source_points, pair.source.size());
  EXPECT_GT(r.correspondences, pair.source.size() * 99 / 100);  // all points paired, not a quarter
  EXPECT_GT(r.fitness, 0.99);

  options.max_iterations = 2;  // ends in the sparse phase: fitness over the points it paired
  const GicpResult cut = register_gicp(pair.target, pair.source, guess, options);
  EXPECT_FALSE(cut.converged);
  EXPECT_EQ(cut.iterations, 2);
  EXPECT_LT(cut.correspondences, pair.source.size() / 3);
  EXPECT_LE(cut.fitness, 1.0);

  GicpOptions bad;
  bad.sparse_stride = 0;
  bad.sparse_tolerance_factor = 0.5;
  std::string why;
  EXPECT_FALSE(bad.is_valid(&why));
  EXPECT_EQ(why, "sparse_stride must be >= 1; sparse_tolerance_factor must be finite and >= 1");
}

TEST(Gicp, AGuessWithNoOverlapIsNotConvergedAndLeavesTheGuess) {
  const GicpOptions options = synthetic_options();
  const SyntheticPair pair = synthetic_pair(options);
  const core::SE3 guess = pair.T_target_source * core::SE3(core::SO3(), Eigen::Vector3d(50.0, 0.0, 0.0));
  const GicpResult r = register_gicp(pair.target, pair.source, guess, options);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.correspondences, 0u);
  EXPECT_EQ(r.fitness, 0.0);
  EXPECT_EQ(r.T_target_source.matrix(), guess.matrix());
}

// Bench recipe (bench/registration_vs_peers.cpp): crop to 100 m, one point per voxel.
std::vector<Eigen::Vector3d> crop(const io::PointCloud& cloud) {
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector3f& p : cloud.points) {
    const double range = p.cast<double>().norm();
    if (range > 0.0 && range <= 100.0) points.push_back(p.cast<double>());
  }
  return points;
}

TEST(Gicp, RealKittiKeyFramePairsMatchTheGnssInsReference) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const test::KittiKeyFrames k = test::read_kitti_key_frames(6);
  ASSERT_EQ(k.files.size(), 6u);
  // The bench's clouds (target at 0.5 m, source at 1 m, correspondences within 1 m, the guess the
  // previous pair's motion, identity for the first); the source's covariances come from its scan
  // at 0.5 m, which then serves as the next target.
  // Once with all points in every iteration, once coarse to fine (every 4th point first, as the
  // localiser registers): both within the bounds below.
  for (const int stride : {1, 4}) {
  GicpOptions options;
  options.sparse_stride = stride;
  std::vector<Eigen::Vector3d> target = voxel_downsample(crop(io::read_point_cloud(k.files[0])), 0.5);
  double translation_sum = 0.0, rotation_sum = 0.0;
  core::SE3 guess;
  for (std::size_t i = 0; i + 1 < k.files.size(); ++i) {
    std::vector<Eigen::Vector3d> next = voxel_downsample(crop(io::read_point_cloud(k.files[i + 1])), 0.5);
    const GicpCloud target_cloud(std::move(target), options);
    const GicpCloud source_cloud(voxel_downsample(next, 1.0), next, options);
    const core::SE3 reference = k.T_enu_velo[i].inverse() * k.T_enu_velo[i + 1];
    const GicpResult r = register_gicp(target_cloud, source_cloud, guess, options);
    EXPECT_TRUE(r.converged) << "pair " << i;
    EXPECT_GT(r.fitness, 0.8) << "pair " << i;
    translation_sum += std::pow(translation_error_m(reference, r.T_target_source), 2);
    rotation_sum += std::pow(rotation_error_rad(reference, r.T_target_source) / kDeg, 2);
    target = std::move(next);
    guess = reference;
  }
  const double translation_rmse_m = std::sqrt(translation_sum / 5.0), rotation_rmse_deg = std::sqrt(rotation_sum / 5.0);
  std::printf("5 KITTI pairs, GICP (sparse stride %d): RMSE %.4f m %.4f deg\n", stride, translation_rmse_m, rotation_rmse_deg);
  // The bound is the one test_odometry.cpp sets on the step errors of these key frames (5 cm,
  // 0.2 deg), for the same reason: the reference is GNSS/INS interpolated to the scan times,
  // whose rotation is no better than about 0.1 deg (issue 42), and the scans are not deskewed
  // (0.7 m of travel per sweep at ~7 m/s), so a few centimetres of every method's error on these
  // pairs (3.3-4.9 cm median for GICP, ICP, PCL and Open3D, docs/benchmarks.md) is the
  // reference's and the scans', not the registration's.
  EXPECT_LT(translation_rmse_m, 0.05) << "sparse stride " << stride;
  EXPECT_LT(rotation_rmse_deg, 0.2) << "sparse stride " << stride;
  }
}

TEST(Gicp, RejectsNonFiniteInputAndInvalidOptions) {
  std::vector<Eigen::Vector3d> points = {{1.0, 2.0, 3.0}, {0.0, std::numeric_limits<double>::quiet_NaN(), 0.0}};
  EXPECT_THROW(GicpCloud{points}, std::invalid_argument);
  EXPECT_THROW(GicpCloud({{1.0, 2.0, 3.0}}, points), std::invalid_argument);  // NaN in the support
  points[1].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(GicpCloud{points}, std::invalid_argument);

  GicpOptions bad;
  bad.covariance_neighbours = 2;
  bad.max_correspondence_m = std::numeric_limits<double>::quiet_NaN();
  bad.max_iterations = 0;
  std::string why;
  EXPECT_FALSE(bad.is_valid(&why));
  EXPECT_EQ(why,
            "covariance_neighbours must be >= 3; max_correspondence_m must be finite and > 0; "
            "max_iterations must be >= 1");
  EXPECT_THROW(GicpCloud({{1.0, 2.0, 3.0}}, bad), std::invalid_argument);
  EXPECT_TRUE(GicpOptions{}.is_valid(nullptr));

  const GicpCloud cloud({{1.0, 2.0, 3.0}, {2.0, 2.0, 3.0}, {1.0, 3.0, 3.0}});
  core::SE3 nan_guess(core::SO3(), Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  EXPECT_THROW(register_gicp(cloud, cloud, nan_guess), std::invalid_argument);
  EXPECT_THROW(register_gicp(cloud, cloud, core::SE3(), bad), std::invalid_argument);
}

TEST(Gicp, EmptyTinyAndDegenerateCloudsAreNotConvergedOrStayFinite) {
  std::mt19937 rng(3);
  const GicpCloud room(scene(rng));
  const GicpCloud empty(std::vector<Eigen::Vector3d>{});
  EXPECT_TRUE(empty.empty());
  for (const auto& [target, source] : {std::pair{&empty, &room}, std::pair{&room, &empty}, std::pair{&empty, &empty}}) {
    const GicpResult r = register_gicp(*target, *source, core::SE3());
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.correspondences, 0u);
    EXPECT_EQ(r.fitness, 0.0);
  }
  // Fewer points than covariance_neighbours: each covariance comes from all of them.
  const GicpCloud five({{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {1.0, 1.0, 0.0}, {0.5, 0.5, 0.0}});
  ASSERT_EQ(five.size(), 5u);
  for (std::size_t i = 0; i < five.size(); ++i) {
    const Eigen::Matrix3d C = five.covariance(i);
    EXPECT_TRUE(C.allFinite());
    EXPECT_NEAR(C(2, 2), GicpOptions{}.covariance_epsilon, 1e-9);  // the points' plane is z = 0
  }
  const GicpResult few = register_gicp(five, five, core::SE3());
  EXPECT_FALSE(few.converged);  // 5 correspondences cannot fix 6 unknowns
  EXPECT_EQ(few.correspondences, 5u);
  // Every point the same: no plane anywhere, a singular system; any answer, but a finite one.
  const GicpCloud same(std::vector<Eigen::Vector3d>(30, Eigen::Vector3d(1.0, 2.0, 3.0)));
  const GicpResult r = register_gicp(same, same, core::SE3());
  EXPECT_TRUE(r.T_target_source.matrix().allFinite());
}

}  // namespace
}  // namespace cairn::lidar3d
