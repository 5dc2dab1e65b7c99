#pragma once
/// \file
/// The dual certificate of SE-Sync's problem (Rosen, Carlone, Bandeira & Leonard, "SE-Sync: A
/// certifiably correct algorithm for synchronization over the special Euclidean group", IJRR
/// 2019, Sec. 4) at a rank-d point: does this set of poses minimise the chordal objective
///   f(R, t) = sum_e kappa_e ||R_j - R_i R~_ij||_F^2 + tau_e ||t_j - t_i - R_i t~_ij||^2
/// (ChordalFactor, the `--objective chordal` of `cairn optimize`) globally?
///
/// With the translations eliminated, f(R) = tr(Q R^T R) for R = [R_1 ... R_n] (d x dn) and the
/// connection-Laplacian-like Q of the paper's eq. (20). At R, let
///   Lambda = SymBlockDiag_d(Q R^T R)   (d x d blocks Sym((Q R^T)_i R_i), eq. 25),
///   S = Q - Lambda.
/// For any feasible rotations R' (R'_i^T R'_i = I), tr(R' Lambda R'^T) = tr(Lambda) = f(R), so
///   f(R') = tr(R' S R'^T) + f(R) >= f(R) + n d lambda_min(S):
/// S positive semidefinite proves R globally optimal (the paper's Theorem 7), and in every case
///   f(R) - f* <= n d max(0, -lambda_min(S))
/// bounds the suboptimality (weak duality for the block-diagonal multiplier Lambda).
///
/// How lambda_min(S) is bounded here: Q is dense (it holds the inverse of the translational
/// Laplacian), but it is the Schur complement of the sparse translation-explicit matrix M
/// (eq. 13-16, translations of all poses and rotations of all poses) once one translation is
/// fixed (the gauge; the columns of M's translation-rotation block sum to zero, so the anchored
/// Schur complement equals Q). Hence, by the Schur complement lemma,
///   S + eta I > 0   <=>   K(eta) = M_anchored - diag(0, Lambda) + diag(0, eta I) > 0,
/// and K(eta) is sparse: one CHOLMOD factorisation answers "lambda_min(S) > -eta?". That is the
/// test SE-Sync itself moved to in 2022 (fast_verification in SESync_utils.cpp: Cholesky of
/// S + eta I with CHOLMOD's quick return when not positive definite), here on the reduced S so
/// that eta bounds lambda_min(S) and the suboptimality bound above holds. Bisection over eta
/// brackets lambda_min(S).
///
/// The translations used are the optimal ones for the given rotations (solved here), so the
/// result depends on the rotations only, as SE-Sync's does.

#include <string>

#include "cairn/backend/problem.hpp"

namespace cairn::backend {

struct CertificateOptions {
  /// Certified when lambda_min(S) >= -eigenvalue_tolerance (absolute; SE-Sync's
  /// min_eig_num_tol: 1e-5 in the IJRR version, 1e-3 since 2022). > 0.
  double eigenvalue_tolerance = 1e-5;
  /// Certified: the shift is divided by 10 while S + eta I stays positive definite, down to
  /// eigenvalue_tolerance * 10^-refinement_decades, to tighten the bound. >= 0.
  int refinement_decades = 8;
  /// Not certified: geometric bisection steps bracketing lambda_min(S) (each halves the ratio
  /// of the bracket's ends in log scale). >= 0.
  int bisection_steps = 24;

  bool is_valid(std::string* error) const;
};

struct CertificateSummary {
  bool certified = false;
  int d = 0;                       ///< dimension of the rotations (2 or 3)
  int rank = 0;                    ///< rows of the point certified (d, or more in the staircase)
  int poses = 0;
  /// SE-Sync's f at the given rotations with their optimal translations.
  double f = 0.0;
  /// lambda_min(S) lies in [lambda_min_lower, lambda_min_upper]; the upper end is +infinity when
  /// no shift made K(eta) indefinite (certified with room to spare).
  double lambda_min_lower = 0.0;
  double lambda_min_upper = 0.0;
  /// f - f* <= suboptimality_bound = n d max(0, -lambda_min_lower); relative: divided by f.
  double suboptimality_bound = 0.0;
  double relative_suboptimality_bound = 0.0;
  int factorizations = 0;
  std::size_t factor_nonzeros = 0;
  double time_s = 0.0;
  std::string message;
};

/// The certificate at the rotations of `problem.T_world_pose` (translations are re-solved;
/// fixed poses are treated as the gauge only: with more than one fixed pose the message says
/// that the certificate speaks of the problem without them). Requires a connected graph (as
/// make_problem guarantees for a graph with one fixed pose) with SE-Sync weights on every edge.
template <class Group>
CertificateSummary certify_chordal(const PoseGraphProblem<Group>& problem, const CertificateOptions& options = {});

}  // namespace cairn::backend
