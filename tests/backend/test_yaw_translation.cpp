// The 4-DoF pose graph's pieces (backend/yaw_translation.hpp): Jacobians through the yaw-and-
// translation manifold against central differences, and a ring of poses whose yaw and position
// drifted, closed by a loop edge: the correction keeps every pose's gravity direction, as a
// visual-inertial map's loop closure must (VINS-Mono Sec. VIII-B; ORB-SLAM3 Sec. VII-B). The
// expected values are the drift-free ring the test builds itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "backend/factor_jacobian_check.hpp"
#include "cairn/backend/relative_pose_factor.hpp"
#include "cairn/backend/yaw_translation.hpp"

namespace cairn::backend {
namespace {

Eigen::Vector3d random3(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return Eigen::Vector3d(u(rng), u(rng), u(rng)) * scale;
}

std::vector<double> values_of(const core::SE3& T) {
  std::vector<double> v(7);
  se3_to_values(T, v.data());
  return v;
}

TEST(YawTranslation, AdaptedJacobiansMatchNumericOnRandomCases) {
  std::mt19937 rng(404);
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const YawTranslationManifold manifold(random3(rng, 1.0) + Eigen::Vector3d(0.0, 0.0, 0.1));
    PoseEdge<core::SE3> edge;
    edge.T_i_j = core::SE3(core::SO3::exp(random3(rng, 3.0)), random3(rng, 5.0));
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
    edge.sqrt_information = A + 3.0 * Eigen::Matrix<double, 6, 6>::Identity();
    // Every other trial only the first pose on the 4-DoF manifold (the other as SE(3)).
    const bool both = trial % 2 == 0;
    const YawTranslationAdapter factor(std::make_unique<RelativePoseFactor>(edge), {&manifold, both ? &manifold : nullptr});
    const core::SE3 T_i(core::SO3::exp(random3(rng, 3.0)), random3(rng, 20.0));
    const core::SE3 T_j(core::SO3::exp(random3(rng, 3.0)), random3(rng, 20.0));
    const Manifold* second = both ? static_cast<const Manifold*>(&manifold) : &se3_manifold();
    worst = std::max(worst, test::jacobian_error(factor, {values_of(T_i), values_of(T_j)}, {&manifold, second}));
  }
  EXPECT_LT(worst, 1e-6);
  RecordProperty("worst_relative_difference", std::to_string(worst));
}

// 24 poses round a 10 m ring, each tilted a little (a vehicle pitching and rolling), yaw and
// position drifting along the way (what a visual-inertial odometry leaves: its tilt is right,
// gravity sees it); the chain's edges are the drifted relative poses, the loop edge the true one.
struct RingResult {
  double max_tilt_change_rad = 0.0;
  double max_position_error_m = 0.0;
  double final_cost = 0.0;
  double loop_gap_before_m = 0.0, loop_gap_after_m = 0.0;  // the loop edge's translation residual
};

RingResult correct_ring(bool four_dof, double* drifted_error_m = nullptr) {
  std::mt19937 rng(7);
  const int n = 24;
  const Eigen::Vector3d up(0.0, 0.0, 1.0);
  std::vector<core::SE3> truth, drifted;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    const core::SO3 R = core::SO3::exp(up * (a + M_PI / 2)) * core::SO3::exp(random3(rng, 0.1).cwiseProduct(Eigen::Vector3d(1, 1, 0)));
    truth.emplace_back(R, Eigen::Vector3d(5.0 * std::cos(a), 5.0 * std::sin(a), 0.2 * std::sin(3 * a)));
    // Drift: 0.6 deg of yaw and 2 cm per pose, about the first pose.
    const core::SO3 yaw = core::SO3::exp(up * (0.0105 * k));
    drifted.emplace_back(yaw * R, yaw * truth.back().translation() + Eigen::Vector3d(0.02 * k, -0.01 * k, 0.0));
  }
  if (drifted_error_m) {
    *drifted_error_m = 0.0;
    for (int k = 0; k < n; ++k) *drifted_error_m = std::max(*drifted_error_m, (drifted[k].translation() - truth[k].translation()).norm());
  }
  const YawTranslationManifold manifold(up);
  std::vector<std::array<double, 7>> values(n);
  LeastSquaresProblem problem;
  std::vector<int> var(n);
  for (int k = 0; k < n; ++k) {
    se3_to_values(drifted[k], values[k].data());
    var[k] = problem.add_variable(values[k].data(), four_dof ? static_cast<const Manifold&>(manifold) : se3_manifold());
  }
  problem.set_constant(var[0]);
  auto add = [&](int i, int j, const core::SE3& T_i_j) {
    PoseEdge<core::SE3> edge;
    edge.T_i_j = T_i_j;
    std::unique_ptr<Factor> f = std::make_unique<RelativePoseFactor>(edge);
    if (four_dof) f = std::make_unique<YawTranslationAdapter>(std::move(f), std::vector<const YawTranslationManifold*>{&manifold, &manifold});
    problem.add_factor(std::move(f), {var[i], var[j]});
  };
  for (int k = 0; k + 1 < n; ++k) add(k, k + 1, drifted[k].inverse() * drifted[k + 1]);
  // The loop's measured relative pose is tilted by 1 degree (a visual loop's rotation error).
  const core::SE3 loop = truth[n - 1].inverse() * truth[0] * core::SE3(core::SO3::exp(Eigen::Vector3d(0.0175, 0.0, 0.0)), Eigen::Vector3d::Zero());
  add(n - 1, 0, loop);
  LeastSquaresOptions options;
  options.linear_solver = LinearSolverType::kSparseNormalCholesky;
  options.max_iterations = 50;
  const LeastSquaresSummary summary = solve(problem, options);
  EXPECT_TRUE(summary.is_solution_usable());
  RingResult r;
  r.final_cost = summary.final_cost;
  const auto loop_gap = [&](const core::SE3& a, const core::SE3& b) { return ((a.inverse() * b).translation() - loop.translation()).norm(); };
  r.loop_gap_before_m = loop_gap(drifted[n - 1], drifted[0]);
  r.loop_gap_after_m = loop_gap(se3_from_values(values[n - 1].data()), se3_from_values(values[0].data()));
  for (int k = 0; k < n; ++k) {
    const core::SE3 T = se3_from_values(values[k].data());
    const Eigen::Vector3d g_before = drifted[k].so3().inverse() * up, g_after = T.so3().inverse() * up;
    r.max_tilt_change_rad = std::max(r.max_tilt_change_rad, std::atan2(g_before.cross(g_after).norm(), g_before.dot(g_after)));
    r.max_position_error_m = std::max(r.max_position_error_m, (T.translation() - truth[k].translation()).norm());
  }
  return r;
}

TEST(YawTranslation, LoopCorrectionOfARingKeepsEveryPosesGravityDirection) {
  double drifted_m = 0.0;
  const RingResult four = correct_ring(true, &drifted_m), six = correct_ring(false);
  std::printf("ring of 24 poses, drifted up to %.3f m, the loop edge 1 deg off in roll: 4-DoF: loop gap %.3f -> %.4f m, largest error "
              "%.3f m, tilt changed at most %.2e rad; 6-DoF: loop gap -> %.4f m, largest error %.3f m, tilt changed up to %.2f deg\n",
              drifted_m, four.loop_gap_before_m, four.loop_gap_after_m, four.max_position_error_m, four.max_tilt_change_rad,
              six.loop_gap_after_m, six.max_position_error_m, six.max_tilt_change_rad * 180.0 / M_PI);
  EXPECT_LT(four.max_tilt_change_rad, 1e-9);  // roll and pitch untouched, by construction
  EXPECT_LT(four.loop_gap_after_m, 0.02 * four.loop_gap_before_m);  // the loop is closed ...
  EXPECT_LT(four.max_position_error_m, 0.5 * drifted_m);              // ... and the drift spread out
  EXPECT_GT(six.max_tilt_change_rad, 0.25 * 0.0175);  // a 6-DoF correction spreads the loop's roll into the poses' tilts
}

}  // namespace
}  // namespace cairn::backend
