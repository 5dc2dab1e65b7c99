#pragma once
/// \file
/// Residuals of a relative-pose edge and their analytic Jacobians, whitened by the edge's
/// weights. Poses are perturbed on the right: T <- T * exp(delta), delta translation first.
///
/// GeodesicFactor (the g2o/GTSAM/Ceres cost):
///   r = S log(Z^-1 T_i^-1 T_j),  S^T S = information
///   dr/d(delta_j) = S Jr^-1(e),  dr/d(delta_i) = -S Jr^-1(e) Adj(T_j^-1 T_i),  e = log(...)
/// (perturbing T_i gives E exp(-Adj(T_j^-1 T_i) delta_i); see docs/math/pose_graph.md).
///
/// ChordalFactor (SE-Sync's objective, Rosen et al. IJRR 2019, Problem 1, eq. 12):
///   r = ( sqrt(kappa) vec(R_j - R_i R~_ij) ,  sqrt(tau) (t_j - t_i - R_i t~_ij) )
/// so that sum ||r||^2 is exactly SE-Sync's f. With R <- R exp([phi]x), t <- t + R rho:
///   d vec(R_j)/d phi_j,k = vec(R_j G_k),  d vec(-R_i R~)/d phi_i,k = -vec(R_i G_k R~),
///   d(t_j - t_i - R_i t~)/d(rho_j, phi_j) = (R_j, 0),  .../d(rho_i, phi_i) = (-R_i, R_i [t~]x),
/// G_k the generators of so(d).

#include "cairn/backend/problem.hpp"

namespace cairn::backend {

/// The cost a solve minimises; each has its factor below (with_factor maps one to the other).
enum class Objective {
  kGeodesic,  ///< r = S log(Z^-1 T_i^-1 T_j): the maximum-likelihood cost g2o, GTSAM, Ceres use
  kChordal,   ///< SE-Sync's f with isotropic weights kappa, tau (published certified optima)
};

template <class Group>
struct GeodesicFactor {
  static constexpr int kDoF = Group::kDoF;
  static constexpr int kResidualDim = Group::kDoF;
  using Residual = Eigen::Matrix<double, kResidualDim, 1>;
  using Jacobian = Eigen::Matrix<double, kResidualDim, kDoF>;

  /// Whitened residual; Jacobians optional (nullptr to skip).
  static Residual evaluate(const Group& T_world_i, const Group& T_world_j, const PoseEdge<Group>& edge,
                           Jacobian* J_r_i, Jacobian* J_r_j);
};

template <class Group>
struct ChordalFactor {
  static constexpr int kDoF = Group::kDoF;
  static constexpr int d = Group::kDoF == 3 ? 2 : 3;
  static constexpr int kResidualDim = d * d + d;
  using Residual = Eigen::Matrix<double, kResidualDim, 1>;
  using Jacobian = Eigen::Matrix<double, kResidualDim, kDoF>;

  static Residual evaluate(const Group& T_world_i, const Group& T_world_j, const PoseEdge<Group>& edge,
                           Jacobian* J_r_i, Jacobian* J_r_j);

  using Hessian = Eigen::Matrix<double, kDoF, kDoF>;
  /// The second-order part of the Hessian of ||r||^2 / 2 under the perturbations T <- T exp(delta):
  /// S_ii = sum_k r_k d^2 r_k / d delta_i^2 and S_jj likewise (r is linear in each pose's R and t,
  /// so there is no i-j term). With T exp(delta) = (R exp(phi), t + R V(phi) rho), V = I + [phi]/2
  /// + O(phi^2):
  ///   d^2 R / d phi_a d phi_b = R Sym(G_a G_b),   d^2 t / d rho_a d phi_b = R G_b e_a / 2,
  /// the other second derivatives 0. J^T J + S is the exact Hessian of the pulled-back cost, whose
  /// Newton steps converge quadratically where Gauss-Newton's converge linearly (the chordal
  /// residuals do not vanish at the optimum). `r` is the residual evaluate() returned.
  static void second_order(const Group& T_world_i, const Group& T_world_j, const PoseEdge<Group>& edge,
                           const Residual& r, Hessian* S_ii, Hessian* S_jj);
};

/// Calls `f` with a value of the factor type of `objective` (GeodesicFactor<Group>{} or
/// ChordalFactor<Group>{}), so code templated on the factor is dispatched in one place.
template <class Group, class F>
decltype(auto) with_factor(Objective objective, F&& f) {
  if (objective == Objective::kChordal) return f(ChordalFactor<Group>{});
  return f(GeodesicFactor<Group>{});
}

/// ||r||^2 of `edge` at the given poses under `objective` (no Jacobians).
template <class Group>
double squared_residual(const Group& T_world_i, const Group& T_world_j, const PoseEdge<Group>& edge,
                        Objective objective) {
  return with_factor<Group>(objective, [&](auto factor) {
    return decltype(factor)::evaluate(T_world_i, T_world_j, edge, nullptr, nullptr).squaredNorm();
  });
}

/// Unwhitened geodesic error log(Z^-1 T_i^-1 T_j).
template <class Group>
typename Group::Tangent between_error(const Group& T_world_i, const Group& T_world_j, const Group& T_i_j);

}  // namespace cairn::backend
