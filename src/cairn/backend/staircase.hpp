#pragma once
/// \file
/// The Riemannian staircase (Rosen et al., IJRR 2019, Sec. 4.2 and Algorithm 1; Boumal, "A
/// Riemannian low-rank method for optimization over semidefinite matrices with block-diagonal
/// constraints", 2015): when the certificate at a rank-d point fails, SE-Sync's relaxation is
/// solved at ranks r = d+1, d+2, ... (Y_i in the Stiefel manifold St(d, r), translations in R^r)
/// until a point certifies; each rank starts from the previous one lifted by a zero row and moved
/// along the direction of negative curvature the failed certificate found (eq. 32). The certified
/// rank-r point is rounded to SO(d)^n (the SVD rounding of Algorithm 2), polished at rank d by the
/// pose-graph optimiser on the chordal objective, and certified again: when the relaxation is
/// exact (every SE-Sync benchmark), that point is the global optimum.
///
/// The solver at each rank is Levenberg-Marquardt with the exact Riemannian Hessian in an
/// orthonormal basis of each pose's tangent space (translation; Y_i Omega with Omega skew; Y_perp K),
/// Hess f[V] = Proj(2 V M) - V_i Sym(Y_i^T grad_i) (the embedded metric; Absil, Mahony &
/// Sepulchre 2008, Sec. 5.5), factorised by CHOLMOD, retraction by the polar factor; the anchor
/// pose is held (it fixes the O(r) gauge for r = d + 1).

#include <string>
#include <vector>

#include "cairn/backend/certificate.hpp"
#include "cairn/backend/optimizer.hpp"

namespace cairn::backend {

struct StaircaseOptions {
  /// false: only the certificate at rank d, nothing climbed or changed (for a solve of another
  /// objective, whose poses the chordal staircase must not replace).
  bool climb = true;
  /// Highest rank tried is d + max_rank_increase (SE-Sync: r_max = 10). >= 1.
  int max_rank_increase = 5;
  /// Levenberg-Marquardt iterations per rank. >= 1.
  int max_iterations = 300;
  /// Converged at a rank when max |grad| <= gradient_tolerance * max(1, f). > 0.
  double gradient_tolerance = 1e-10;
  CertificateOptions certificate;
  /// The rank-d polish after rounding (its objective is set to chordal). Its should_stop also
  /// stops the climb (between iterations); the poses are then left as they were.
  OptimizerOptions polish;
};

struct StaircaseLevel {
  int rank = 0;
  int iterations = 0;
  double f = 0.0;
  CertificateSummary certificate;
};

struct StaircaseSummary {
  /// The problem's poses at the end are certified globally optimal.
  bool certified = false;
  /// Every rank visited, the first the given (rank-d) point.
  std::vector<StaircaseLevel> levels;
  /// The certificate of the returned rank-d poses.
  CertificateSummary certificate;
  double f_initial = 0.0;
  double f_final = 0.0;
  double time_s = 0.0;
  /// polish.should_stop ended it; the poses were not changed.
  bool interrupted = false;
  std::string message;
};

/// Certifies the rank-d poses of `problem`; when that fails, climbs the staircase and replaces
/// the poses by the rounded, polished result if it is better (its f lower). Fixed poses other
/// than the first (the anchor) are not supported: the summary says so and nothing changes.
template <class Group>
StaircaseSummary riemannian_staircase(PoseGraphProblem<Group>& problem, const StaircaseOptions& options = {});

}  // namespace cairn::backend
