// Analytic Jacobians of both residuals against central differences on >= 1,000 random pose
// pairs per group and objective, with random information matrices and measurements.

#include <gtest/gtest.h>

#include <random>

#include "cairn/backend/factors.hpp"

namespace cairn::backend {
namespace {

template <class Group>
Group random_pose(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  typename Group::Tangent xi;
  for (int k = 0; k < Group::kDoF; ++k) xi[k] = n(rng) * scale;
  return Group::exp(xi);
}

template <class Group>
PoseEdge<Group> random_edge(std::mt19937_64& rng) {
  constexpr int D = Group::kDoF;
  PoseEdge<Group> edge;
  edge.T_i_j = random_pose<Group>(rng, 1.0);
  const Eigen::Matrix<double, D, D> A = Eigen::Matrix<double, D, D>::Random();
  edge.information = A * A.transpose() + Eigen::Matrix<double, D, D>::Identity();
  Eigen::LLT<Eigen::Matrix<double, D, D>> llt(edge.information);
  edge.sqrt_information = llt.matrixU();
  std::uniform_real_distribution<double> u(0.5, 20.0);
  edge.kappa = u(rng);
  edge.tau = u(rng);
  return edge;
}

// Central differences of the whitened residual with right perturbations T * exp(h e_k).
template <class Factor, class Group>
typename Factor::Jacobian numeric_jacobian(const Group& Ti, const Group& Tj, const PoseEdge<Group>& edge, bool wrt_i) {
  typename Factor::Jacobian J;
  constexpr double h = 1e-6;
  for (int k = 0; k < Group::kDoF; ++k) {
    typename Group::Tangent d = Group::Tangent::Zero();
    d[k] = h;
    const Group ip = wrt_i ? Ti * Group::exp(d) : Ti;
    const Group im = wrt_i ? Ti * Group::exp(-d) : Ti;
    const Group jp = wrt_i ? Tj : Tj * Group::exp(d);
    const Group jm = wrt_i ? Tj : Tj * Group::exp(-d);
    J.col(k) = (Factor::evaluate(ip, jp, edge, nullptr, nullptr) - Factor::evaluate(im, jm, edge, nullptr, nullptr)) / (2 * h);
  }
  return J;
}

template <class Factor, class Group>
void check_jacobians(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  double worst = 0.0;
  for (int sample = 0; sample < 1000; ++sample) {
    const PoseEdge<Group> edge = random_edge<Group>(rng);
    const Group Ti = random_pose<Group>(rng, 2.0);
    // Near the measurement (the usual case) half of the time, anywhere the other half; the
    // rotation error stays below pi where log is smooth.
    const Group Tj = sample % 2 == 0 ? Ti * edge.T_i_j * random_pose<Group>(rng, 0.1) : Ti * random_pose<Group>(rng, 0.5);
    typename Factor::Jacobian Ji;
    typename Factor::Jacobian Jj;
    Factor::evaluate(Ti, Tj, edge, &Ji, &Jj);
    const auto Ni = numeric_jacobian<Factor>(Ti, Tj, edge, true);
    const auto Nj = numeric_jacobian<Factor>(Ti, Tj, edge, false);
    const double scale = std::max(1.0, std::max(Ni.cwiseAbs().maxCoeff(), Nj.cwiseAbs().maxCoeff()));
    const double error = std::max((Ji - Ni).cwiseAbs().maxCoeff(), (Jj - Nj).cwiseAbs().maxCoeff()) / scale;
    worst = std::max(worst, error);
    ASSERT_LT(error, 1e-6) << "sample " << sample << "\nJi\n" << Ji << "\nnumeric\n" << Ni << "\nJj\n" << Jj
                           << "\nnumeric\n" << Nj;
  }
  ::testing::Test::RecordProperty("worst_relative_error", std::to_string(worst));
}

TEST(GeodesicFactor, JacobiansMatchCentralDifferencesSE2) { check_jacobians<GeodesicFactor<core::SE2>, core::SE2>(1); }
TEST(GeodesicFactor, JacobiansMatchCentralDifferencesSE3) { check_jacobians<GeodesicFactor<core::SE3>, core::SE3>(2); }
TEST(ChordalFactor, JacobiansMatchCentralDifferencesSE2) { check_jacobians<ChordalFactor<core::SE2>, core::SE2>(3); }
TEST(ChordalFactor, JacobiansMatchCentralDifferencesSE3) { check_jacobians<ChordalFactor<core::SE3>, core::SE3>(4); }

// The exact Hessian of ||r||^2 / 2 pulled back through T exp(delta), J^T J + S, against central
// second differences of that scalar, on 1,000 random pose pairs per group.
template <class Group>
void check_chordal_hessian(std::uint64_t seed) {
  using Factor = ChordalFactor<Group>;
  constexpr int D = Group::kDoF;
  std::mt19937_64 rng(seed);
  double worst = 0.0;
  for (int sample = 0; sample < 1000; ++sample) {
    const PoseEdge<Group> edge = random_edge<Group>(rng);
    const Group Ti = random_pose<Group>(rng, 2.0);
    const Group Tj = sample % 2 == 0 ? Ti * edge.T_i_j * random_pose<Group>(rng, 0.1) : Ti * random_pose<Group>(rng, 0.5);
    typename Factor::Jacobian Ji;
    typename Factor::Jacobian Jj;
    const typename Factor::Residual r = Factor::evaluate(Ti, Tj, edge, &Ji, &Jj);
    typename Factor::Hessian Sii;
    typename Factor::Hessian Sjj;
    Factor::second_order(Ti, Tj, edge, r, &Sii, &Sjj);
    for (const bool wrt_i : {true, false}) {
      const Eigen::Matrix<double, D, D> H = wrt_i ? Eigen::Matrix<double, D, D>(Ji.transpose() * Ji + Sii)
                                                  : Eigen::Matrix<double, D, D>(Jj.transpose() * Jj + Sjj);
      auto cost = [&](const typename Group::Tangent& delta) {
        const Group a = wrt_i ? Ti * Group::exp(delta) : Ti;
        const Group b = wrt_i ? Tj : Tj * Group::exp(delta);
        return 0.5 * Factor::evaluate(a, b, edge, nullptr, nullptr).squaredNorm();
      };
      constexpr double h = 1e-4;
      Eigen::Matrix<double, D, D> N;
      for (int p = 0; p < D; ++p) {
        for (int q = 0; q < D; ++q) {
          typename Group::Tangent ep = Group::Tangent::Zero();
          typename Group::Tangent eq = Group::Tangent::Zero();
          ep[p] = h;
          eq[q] = h;
          N(p, q) = (cost(ep + eq) - cost(ep - eq) - cost(eq - ep) + cost(-ep - eq)) / (4 * h * h);
        }
      }
      const double scale = std::max(1.0, N.cwiseAbs().maxCoeff());
      const double error = (H - N).cwiseAbs().maxCoeff() / scale;
      worst = std::max(worst, error);
      ASSERT_LT(error, 1e-5) << "sample " << sample << (wrt_i ? " pose i" : " pose j") << "\nexact\n" << H
                             << "\nnumeric\n" << N;
    }
  }
  ::testing::Test::RecordProperty("worst_relative_error", std::to_string(worst));
}

TEST(ChordalFactor, ExactHessianMatchesSecondDifferencesSE2) { check_chordal_hessian<core::SE2>(5); }
TEST(ChordalFactor, ExactHessianMatchesSecondDifferencesSE3) { check_chordal_hessian<core::SE3>(6); }

TEST(GeodesicFactor, ZeroAtTheMeasurement) {
  std::mt19937_64 rng(5);
  const PoseEdge<core::SE3> edge = random_edge<core::SE3>(rng);
  const core::SE3 Ti = random_pose<core::SE3>(rng, 3.0);
  EXPECT_LT(GeodesicFactor<core::SE3>::evaluate(Ti, Ti * edge.T_i_j, edge, nullptr, nullptr).norm(), 1e-12);
  EXPECT_LT(ChordalFactor<core::SE3>::evaluate(Ti, Ti * edge.T_i_j, edge, nullptr, nullptr).norm(), 1e-12);
}

TEST(ChordalFactor, SquaredNormIsSeSyncsTerm) {
  // kappa ||R_j - R_i R~||_F^2 + tau ||t_j - t_i - R_i t~||^2, written out independently.
  std::mt19937_64 rng(6);
  const PoseEdge<core::SE3> edge = random_edge<core::SE3>(rng);
  const core::SE3 Ti = random_pose<core::SE3>(rng, 1.0);
  const core::SE3 Tj = random_pose<core::SE3>(rng, 1.0);
  const Eigen::Matrix3d Ri = Ti.rotation_matrix();
  const double expected =
      edge.kappa * (Tj.rotation_matrix() - Ri * edge.T_i_j.rotation_matrix()).squaredNorm() +
      edge.tau * (Tj.translation() - Ti.translation() - Ri * edge.T_i_j.translation()).squaredNorm();
  EXPECT_NEAR(ChordalFactor<core::SE3>::evaluate(Ti, Tj, edge, nullptr, nullptr).squaredNorm(), expected, 1e-10 * expected);
}

}  // namespace
}  // namespace cairn::backend
