// Graph SLAM with SE(3) poses and 3D point landmarks (backend/landmark_graph_3d.hpp) on the
// simulator's 3D landmark world: exact recovery of the truth from noise-free measurements,
// Schur elimination against the joint factorisation, the chi-square of the optimum against its
// degrees of freedom on noisy worlds, and malformed graphs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <cmath>
#include <numbers>
#include <string>

#include "cairn/core/so3.hpp"
#include "cairn/sim/landmark_world_3d_graph.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::landmarks {
namespace {

using backend::LandmarkElimination;
using backend::LandmarkGraph3D;
using backend::LandmarkGraph3DOptions;
using sim::Errors3D;
using sim::LandmarkSensor3D;
using sim::WorldGraph3D;
using sim::errors;
using sim::graph_from_world;

sim::LandmarkWorld3DOptions world_options(LandmarkSensor3D sensor) {
  sim::LandmarkWorld3DOptions options;
  options.poses = 150;
  options.laps = 1;
  options.landmarks = 200;
  options.sensor = sensor;
  return options;
}

// A world whose measurements are exact but whose covariances are the noisy world's.
sim::LandmarkWorld3D noise_free_world(sim::LandmarkWorld3DOptions options, std::uint64_t seed) {
  const sim::LandmarkWorld3D noisy = sim::simulate_landmark_world_3d(options, seed);
  options.point_sigma_m = options.range_sigma_m = options.angle_sigma_rad = 0.0;
  options.odometry_translation_sigma_m = options.odometry_rotation_sigma_rad = 0.0;
  sim::LandmarkWorld3D exact = sim::simulate_landmark_world_3d(options, seed);
  exact.odometry_covariance = noisy.odometry_covariance;
  exact.observation_covariance = noisy.observation_covariance;
  return exact;
}

double max_pose_difference(const LandmarkGraph3D& a, const LandmarkGraph3D& b) {
  double worst = 0.0;
  for (std::size_t k = 0; k < a.poses.size(); ++k) {
    worst = std::max(worst, (a.poses[k].inverse() * b.poses[k]).log().lpNorm<Eigen::Infinity>());
  }
  for (std::size_t l = 0; l < a.landmarks.size(); ++l) {
    worst = std::max(worst, (a.landmarks[l] - b.landmarks[l]).lpNorm<Eigen::Infinity>());
  }
  return worst;
}

TEST(LandmarkGraph3D, ExactMeasurementsRecoverTheTruthFromAPerturbedStart) {
  for (const LandmarkSensor3D sensor : {LandmarkSensor3D::kPoint, LandmarkSensor3D::kRangeBearingElevation}) {
    for (const LandmarkElimination elimination : {LandmarkElimination::kSchur, LandmarkElimination::kJoint}) {
      const sim::LandmarkWorld3D world = noise_free_world(world_options(sensor), 3);
      WorldGraph3D built = graph_from_world(world);
      ASSERT_EQ(built.graph.check(), "");
      ASSERT_GT(built.graph.observations.size(), 1000u);
      // Perturb every free pose (up to 0.3 m / 0.1 rad per axis) and every landmark (0.5 m).
      sim::Random random(11);
      for (std::size_t k = 1; k < built.graph.poses.size(); ++k) {
        Vector6 delta;
        for (int c = 0; c < 6; ++c) delta(c) = random.uniform(-1.0, 1.0) * (c < 3 ? 0.3 : 0.1);
        built.graph.poses[k] = built.graph.poses[k] * core::SE3::exp(delta);
      }
      for (Vector3& p : built.graph.landmarks) p += Vector3(random.uniform(-0.5, 0.5), random.uniform(-0.5, 0.5), random.uniform(-0.5, 0.5));
      const Errors3D start = errors(world, built, built.graph);
      LandmarkGraph3DOptions options;
      options.elimination = elimination;
      const backend::LandmarkGraphSummary summary = backend::optimize(built.graph, options);
      const Errors3D end = errors(world, built, built.graph);
      SCOPED_TRACE(std::string(sensor == LandmarkSensor3D::kPoint ? "point" : "range-bearing-elevation") +
                   (elimination == LandmarkElimination::kSchur ? ", Schur" : ", joint"));
      EXPECT_TRUE(summary.usable()) << summary.message;
      EXPECT_GT(start.position_rms_m, 0.1);
      EXPECT_LT(end.position_rms_m, 1e-6);
      EXPECT_LT(end.rotation_rms_rad, 1e-7);
      EXPECT_LT(end.landmark_rms_m, 1e-6);
      EXPECT_LT(summary.final_cost, 1e-10);
      const std::size_t free_pose_variables = 6 * (built.graph.poses.size() - 1);
      EXPECT_EQ(summary.factorised_variables, elimination == LandmarkElimination::kSchur
                                                  ? free_pose_variables
                                                  : free_pose_variables + 3 * built.graph.landmarks.size());
    }
  }
}

TEST(LandmarkGraph3D, SchurEliminationAndJointFactorisationReachTheSameOptimum) {
  for (const LandmarkSensor3D sensor : {LandmarkSensor3D::kPoint, LandmarkSensor3D::kRangeBearingElevation}) {
    const sim::LandmarkWorld3D world = sim::simulate_landmark_world_3d(world_options(sensor), 5);
    WorldGraph3D schur = graph_from_world(world);
    LandmarkGraph3D joint = schur.graph;
    LandmarkGraph3DOptions options;
    const backend::LandmarkGraphSummary a = backend::optimize(schur.graph, options);
    options.elimination = LandmarkElimination::kJoint;
    const backend::LandmarkGraphSummary b = backend::optimize(joint, options);
    ASSERT_TRUE(a.usable() && b.usable());
    EXPECT_LT(a.final_cost, a.initial_cost);
    EXPECT_NEAR(a.final_cost, b.final_cost, 1e-8 * b.final_cost);
    EXPECT_LT(max_pose_difference(schur.graph, joint), 1e-6);
  }
}

// At the optimum of a correctly weighted problem the cost is chi-square distributed with
// m - n degrees of freedom (residuals minus unknowns), mean m - n and standard deviation
// sqrt(2 (m - n)); the estimate must also beat dead reckoning by far.
TEST(LandmarkGraph3D, NoisyWorldsEndAtTheChiSquareOfTheirDegreesOfFreedom) {
  for (const LandmarkSensor3D sensor : {LandmarkSensor3D::kPoint, LandmarkSensor3D::kRangeBearingElevation}) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      sim::LandmarkWorld3DOptions options = world_options(sensor);
      options.poses = 200;
      options.laps = 2;
      if (sensor == LandmarkSensor3D::kPoint) options.field_of_view_rad = std::numbers::pi / 2.0;  // camera-like
      const sim::LandmarkWorld3D world = sim::simulate_landmark_world_3d(options, seed);
      WorldGraph3D built = graph_from_world(world);
      ASSERT_EQ(built.graph.check(), "");
      const Errors3D dead_reckoning = errors(world, built, built.graph);
      const backend::LandmarkGraphSummary summary = backend::optimize(built.graph);
      const Errors3D optimised = errors(world, built, built.graph);
      const double dof = 6.0 * static_cast<double>(built.graph.odometry.size()) +
                         3.0 * static_cast<double>(built.graph.observations.size()) -
                         6.0 * static_cast<double>(built.graph.poses.size() - 1) -
                         3.0 * static_cast<double>(built.graph.landmarks.size());
      SCOPED_TRACE("sensor " + std::to_string(static_cast<int>(sensor)) + " seed " + std::to_string(seed) +
                   ": cost " + std::to_string(summary.final_cost) + ", dof " + std::to_string(dof) +
                   ", position rms " + std::to_string(optimised.position_rms_m) + " (dead reckoning " +
                   std::to_string(dead_reckoning.position_rms_m) + ")");
      ASSERT_EQ(summary.status, backend::LandmarkGraphStatus::kConverged) << summary.message;
      ASSERT_GT(dof, 500.0);
      // 4 standard deviations either side.
      EXPECT_NEAR(summary.final_cost, dof, 4.0 * std::sqrt(2.0 * dof));
      // The gauge is pose 0, so errors grow along the run; against dead reckoning (and landmarks
      // placed from it) the optimum must be at least 4x better on every axis (measured 5.2x to
      // 27x; the weakest is the 90-degree point sensor on seed 1, which sees few landmarks).
      EXPECT_LT(optimised.position_rms_m, 0.25 * dead_reckoning.position_rms_m);
      EXPECT_LT(optimised.rotation_rms_rad, 0.25 * dead_reckoning.rotation_rms_rad);
      EXPECT_LT(optimised.landmark_rms_m, 0.25 * dead_reckoning.landmark_rms_m);
      std::printf("[ 3D world ] %s seed %d: cost %.1f dof %.0f | position rms %.3f m (dead reckoning %.3f), rotation rms %.4f rad (%.4f), landmarks %.3f m (%.3f)\n",
                  sensor == LandmarkSensor3D::kPoint ? "point 90deg" : "range-bearing-elevation", static_cast<int>(seed),
                  summary.final_cost, dof, optimised.position_rms_m, dead_reckoning.position_rms_m, optimised.rotation_rms_rad,
                  dead_reckoning.rotation_rms_rad, optimised.landmark_rms_m, dead_reckoning.landmark_rms_m);
    }
  }
}

TEST(LandmarkGraph3D, MalformedGraphsAreNamed) {
  const sim::LandmarkWorld3D world = sim::simulate_landmark_world_3d(world_options(LandmarkSensor3D::kRangeBearingElevation), 2);
  const LandmarkGraph3D good = graph_from_world(world).graph;
  ASSERT_EQ(good.check(), "");
  const auto expect_problem = [](const LandmarkGraph3D& graph, const std::string& words) {
    const std::string problem = graph.check();
    EXPECT_NE(problem.find(words), std::string::npos) << "got: '" << problem << "', expected it to say '" << words << "'";
  };
  LandmarkGraph3D g = good;
  g.landmarks[3].x() = std::numeric_limits<double>::quiet_NaN();
  expect_problem(g, "landmark 3 is not finite");
  g = good;
  g.observations[7].landmark = g.landmarks.size();
  expect_problem(g, "observation factor 7 names a missing landmark");
  g = good;
  g.observations[2].z.x() = -1.0;
  expect_problem(g, "observation factor 2 has a range <= 0");
  g = good;
  g.observations[4].z.y() = std::numeric_limits<double>::infinity();
  expect_problem(g, "observation factor 4 has a non-finite measurement");
  g = good;
  g.observations[5].information.setZero();
  expect_problem(g, "observation factor 5 has an information matrix that is not positive definite");
  g = good;
  g.odometry[9].information(0, 0) = -1.0;
  expect_problem(g, "odometry factor 9 has an information matrix that is not positive definite");
  g = good;
  g.odometry[1].to = g.poses.size();
  expect_problem(g, "odometry factor 1 names a missing pose");
  g = good;
  g.landmarks.push_back(Vector3::Zero());
  expect_problem(g, "is never observed");
  g = LandmarkGraph3D{};
  expect_problem(g, "no poses");
}

}  // namespace
}  // namespace cairn::landmarks
