#pragma once
/// \file
/// Marginal covariances of chosen poses at the current estimate: blocks of (J^T J)^-1 of the
/// geodesic objective, in the tangent space of the right perturbation T exp(delta), translation
/// first. Computed from one sparse Cholesky factorisation and one solve per requested pose with
/// its kDoF unit right-hand sides, never a dense inverse (as GTSAM's Marginals and Ceres'
/// Covariance with SPARSE_QR/SuiteSparse do, with a column solve instead of a recursion).
/// Fixed poses have zero covariance (they define the gauge).

#include <optional>
#include <vector>

#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/backend/sparse_cholesky.hpp"

namespace cairn::backend {

template <class Group>
struct MarginalCovariances {
  using Matrix = Eigen::Matrix<double, Group::kDoF, Group::kDoF>;
  std::vector<int> poses;        ///< requested pose indices
  std::vector<Matrix> covariance;  ///< same order
};

/// Factorises J^T J (whitened Jacobians of `objective`, each edge's block scaled by its weight;
/// edges of weight 0 left out; `weights` empty = all 1) over the free poses, numbered in
/// `variable` (pose index -> block, numbered in a fill-reducing elimination order; -1 for fixed
/// poses). False when not positive definite.
template <class Group>
bool factorize_normal_equations(const PoseGraphProblem<Group>& problem, Objective objective,
                                const std::vector<double>& weights, std::vector<int>& variable,
                                SparseCholesky& cholesky);

/// nullopt when J^T J is not positive definite (a pose not constrained by the edges).
template <class Group>
std::optional<MarginalCovariances<Group>> marginal_covariances(const PoseGraphProblem<Group>& problem,
                                                                 const std::vector<int>& poses);

}  // namespace cairn::backend
