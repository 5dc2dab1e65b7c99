// Graph SLAM with landmarks: factor Jacobians against central differences on random cases,
// convergence from a perturbed start to the noise-free optimum, marginals against a dense inverse.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Dense>

#include "cairn/backend/landmark_graph.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::backend {
namespace {

constexpr double kPi = std::numbers::pi;

Vector3 random_pose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> position(-20.0, 20.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  return {position(rng), position(rng), angle(rng)};
}

// Central differences of f over the additive increments the optimiser uses (angles wrapped).
template <int Out, int In, typename F>
Eigen::Matrix<double, Out, In> numeric_jacobian(F f, const Eigen::Matrix<double, In, 1>& x) {
  constexpr double h = 1e-6;
  Eigen::Matrix<double, Out, In> J;
  for (int c = 0; c < In; ++c) {
    Eigen::Matrix<double, In, 1> plus = x;
    Eigen::Matrix<double, In, 1> minus = x;
    plus(c) += h;
    minus(c) -= h;
    Eigen::Matrix<double, Out, 1> d = f(plus) - f(minus);
    if constexpr (Out >= 2) d(Out - 1) = core::wrap_angle(d(Out - 1));  // the last residual is an angle
    J.col(c) = d / (2 * h);
  }
  return J;
}

TEST(LandmarkGraphFactors, OdometryJacobiansMatchNumericOn1000RandomCases) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> small(-2.0, 2.0);
  double worst = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const Vector3 pose_i = random_pose(rng);
    const Vector3 pose_j = random_pose(rng);
    const Vector3 u(small(rng), small(rng), small(rng));
    Matrix3 J_i;
    Matrix3 J_j;
    odometry_residual_2d(pose_i, pose_j, u, &J_i, &J_j);
    const Matrix3 N_i = numeric_jacobian<3, 3>([&](const Vector3& x) { return odometry_residual_2d(x, pose_j, u); }, pose_i);
    const Matrix3 N_j = numeric_jacobian<3, 3>([&](const Vector3& x) { return odometry_residual_2d(pose_i, x, u); }, pose_j);
    worst = std::max({worst, (J_i - N_i).cwiseAbs().maxCoeff() / (1.0 + N_i.cwiseAbs().maxCoeff()),
                      (J_j - N_j).cwiseAbs().maxCoeff() / (1.0 + N_j.cwiseAbs().maxCoeff())});
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(LandmarkGraphFactors, RangeBearingJacobiansMatchNumericOn1000RandomCases) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> offset(-10.0, 10.0);
  double worst = 0.0;
  int cases = 0;
  while (cases < 1000) {
    const Vector3 pose = random_pose(rng);
    const Vector2 p = pose.head<2>() + Vector2(offset(rng), offset(rng));
    if ((p - pose.head<2>()).norm() < 0.3) continue;  // the Jacobian grows as 1 / range
    ++cases;
    const Vector2 z(5.0, 0.3);
    Matrix23 J_p;
    Matrix2 J_l;
    range_bearing_residual_2d(pose, p, z, &J_p, &J_l);
    const Matrix23 N_p = numeric_jacobian<2, 3>([&](const Vector3& x) { return range_bearing_residual_2d(x, p, z); }, pose);
    const Matrix2 N_l = numeric_jacobian<2, 2>([&](const Vector2& x) { return range_bearing_residual_2d(pose, x, z); }, p);
    worst = std::max({worst, (J_p - N_p).cwiseAbs().maxCoeff() / (1.0 + N_p.cwiseAbs().maxCoeff()),
                      (J_l - N_l).cwiseAbs().maxCoeff() / (1.0 + N_l.cwiseAbs().maxCoeff())});
  }
  EXPECT_LT(worst, 1e-6);
}

// A small world: a circle of poses and a ring of landmarks, measurements exact from the truth.
LandmarkGraph2D exact_graph(std::vector<Vector3>* truth_poses, std::vector<Vector2>* truth_landmarks) {
  LandmarkGraph2D graph;
  for (int k = 0; k < 40; ++k) {
    const double a = 2 * kPi * k / 40.0;
    truth_poses->emplace_back(5 * std::cos(a), 5 * std::sin(a), core::wrap_angle(a + kPi / 2));
  }
  for (int l = 0; l < 12; ++l) {
    const double a = 2 * kPi * l / 12.0 + 0.1;
    const double r = l % 2 == 0 ? 8.0 : 2.5;
    truth_landmarks->emplace_back(r * std::cos(a), r * std::sin(a));
  }
  graph.poses = *truth_poses;
  graph.landmarks = *truth_landmarks;
  for (std::size_t k = 1; k < truth_poses->size(); ++k) {
    OdometryFactor2D f;
    f.from = k - 1;
    f.to = k;
    const Vector3& a = (*truth_poses)[k - 1];
    const Vector3& b = (*truth_poses)[k];
    const double c = std::cos(a.z());
    const double s = std::sin(a.z());
    const Vector2 d = b.head<2>() - a.head<2>();
    f.u = Vector3(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), core::wrap_angle(b.z() - a.z()));
    f.information = Vector3(1e4, 1e4, 1e4).asDiagonal();
    graph.odometry.push_back(f);
  }
  for (std::size_t k = 0; k < truth_poses->size(); ++k) {
    for (std::size_t l = 0; l < truth_landmarks->size(); ++l) {
      const Vector2 d = (*truth_landmarks)[l] - (*truth_poses)[k].head<2>();
      if (d.norm() > 7.0) continue;
      RangeBearingFactor2D f;
      f.pose = k;
      f.landmark = l;
      f.z = Vector2(d.norm(), core::wrap_angle(std::atan2(d.y(), d.x()) - (*truth_poses)[k].z()));
      f.information = Vector2(400.0, 1e4).asDiagonal();
      graph.observations.push_back(f);
    }
  }
  return graph;
}

TEST(LandmarkGraph, ConvergesToTheExactSolutionFromAPerturbedStart) {
  std::vector<Vector3> truth_poses;
  std::vector<Vector2> truth_landmarks;
  LandmarkGraph2D graph = exact_graph(&truth_poses, &truth_landmarks);
  ASSERT_EQ(graph.check(), "");
  EXPECT_LT(graph.cost(), 1e-18);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (std::size_t k = 1; k < graph.poses.size(); ++k) graph.poses[k] += Vector3(noise(rng), noise(rng), 0.3 * noise(rng));
  for (Vector2& p : graph.landmarks) p += Vector2(noise(rng), noise(rng));
  const LandmarkGraphSummary summary = optimize(graph);
  EXPECT_EQ(summary.status, LandmarkGraphStatus::kConverged) << summary.message;
  EXPECT_GT(summary.initial_cost, 1.0);
  EXPECT_LT(summary.final_cost, 1e-12);
  for (std::size_t k = 0; k < graph.poses.size(); ++k) {
    EXPECT_LT((graph.poses[k].head<2>() - truth_poses[k].head<2>()).norm(), 1e-6);
    EXPECT_LT(std::abs(core::wrap_angle(graph.poses[k].z() - truth_poses[k].z())), 1e-6);
  }
  for (std::size_t l = 0; l < graph.landmarks.size(); ++l) EXPECT_LT((graph.landmarks[l] - truth_landmarks[l]).norm(), 1e-6);
}

// Marginals against the dense inverse of a Hessian built here from numeric Jacobians.
TEST(LandmarkGraph, MarginalsMatchTheDenseInverseOfANumericHessian) {
  std::vector<Vector3> truth_poses;
  std::vector<Vector2> truth_landmarks;
  const LandmarkGraph2D graph = exact_graph(&truth_poses, &truth_landmarks);
  const int free_poses = static_cast<int>(graph.poses.size()) - 1;
  const int n = 3 * free_poses + 2 * static_cast<int>(graph.landmarks.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  const auto pose_col = [](std::size_t k) { return 3 * (static_cast<int>(k) - 1); };
  const auto landmark_col = [&](std::size_t l) { return 3 * free_poses + 2 * static_cast<int>(l); };
  for (const OdometryFactor2D& f : graph.odometry) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, n);
    if (f.from > 0) {
      J.middleCols(pose_col(f.from), 3) = numeric_jacobian<3, 3>(
          [&](const Vector3& x) { return odometry_residual_2d(x, graph.poses[f.to], f.u); }, graph.poses[f.from]);
    }
    J.middleCols(pose_col(f.to), 3) = numeric_jacobian<3, 3>(
        [&](const Vector3& x) { return odometry_residual_2d(graph.poses[f.from], x, f.u); }, graph.poses[f.to]);
    H += J.transpose() * f.information * J;
  }
  for (const RangeBearingFactor2D& f : graph.observations) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2, n);
    if (f.pose > 0) {
      J.middleCols(pose_col(f.pose), 3) = numeric_jacobian<2, 3>(
          [&](const Vector3& x) { return range_bearing_residual_2d(x, graph.landmarks[f.landmark], f.z); }, graph.poses[f.pose]);
    }
    J.middleCols(landmark_col(f.landmark), 2) = numeric_jacobian<2, 2>(
        [&](const Vector2& x) { return range_bearing_residual_2d(graph.poses[f.pose], x, f.z); }, graph.landmarks[f.landmark]);
    H += J.transpose() * f.information * J;
  }
  const Eigen::MatrixXd Sigma = H.inverse();
  const LandmarkGraphMarginals marginals = marginal_covariances(graph, {0, 17, 39}, {0, 5, 11});
  ASSERT_TRUE(marginals.ok);
  EXPECT_TRUE(marginals.poses[0].isZero());
  const double scale = Sigma.cwiseAbs().maxCoeff();
  EXPECT_LT((marginals.poses[1] - Sigma.block(pose_col(17), pose_col(17), 3, 3)).cwiseAbs().maxCoeff(), 1e-5 * scale);
  EXPECT_LT((marginals.poses[2] - Sigma.block(pose_col(39), pose_col(39), 3, 3)).cwiseAbs().maxCoeff(), 1e-5 * scale);
  for (int k = 0; k < 3; ++k) {
    const std::size_t l = std::vector<std::size_t>{0, 5, 11}[static_cast<std::size_t>(k)];
    EXPECT_LT((marginals.landmarks[static_cast<std::size_t>(k)] - Sigma.block(landmark_col(l), landmark_col(l), 2, 2))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-5 * scale);
  }
}

TEST(LandmarkGraph, CheckNamesBadFactors) {
  LandmarkGraph2D graph;
  EXPECT_NE(graph.check(), "");
  graph.poses.push_back(Vector3::Zero());
  graph.poses.push_back(Vector3(1, 0, 0));
  graph.landmarks.push_back(Vector2(3, 0));
  EXPECT_EQ(graph.check(), "");
  graph.observations.push_back({1, 4, Vector2(2, 0), Matrix2::Identity()});
  EXPECT_NE(graph.check().find("missing"), std::string::npos);
  graph.observations.back().landmark = 0;
  graph.observations.back().z.x() = std::nan("");
  EXPECT_NE(graph.check().find("not finite"), std::string::npos);
  graph.observations.back().z.x() = -1.0;
  EXPECT_NE(graph.check().find("range <= 0"), std::string::npos);
}

}  // namespace
}  // namespace cairn::backend
