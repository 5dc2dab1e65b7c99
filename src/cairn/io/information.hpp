#pragma once
/// \file
/// Checks and repairs of information matrices read from files.
///
/// Real benchmark files carry matrices that are not positive definite (5,021 edges of SE-Sync's
/// cubicle.g2o have indefinite 6x6 matrices from large translation-rotation couplings). A
/// negative, zero or non-finite diagonal entry is garbage and always an error; an indefinite
/// matrix with a positive diagonal is handled by InformationPolicy.

#include <Eigen/Core>
#include <string>
#include <string_view>

namespace cairn::io {

enum class InformationPolicy {
  /// Replace an indefinite matrix by the nearest symmetric positive semi-definite matrix in the
  /// Frobenius norm: negative eigenvalues set to zero (Higham, "Computing a nearest symmetric
  /// positive semidefinite matrix", Linear Algebra Appl. 103, 1988, Theorem 2.1). Default.
  kProject,
  /// Keep the matrix as written (the cost may be unbounded below along some directions).
  kKeep,
  /// Refuse the file (the CLI's --strict).
  kReject,
};

std::string_view to_string(InformationPolicy policy);

/// True when the symmetric matrix has a Cholesky factorisation with positive pivots.
bool is_positive_definite(const Eigen::MatrixXd& information);

enum class Definiteness {
  kPositiveDefinite,
  /// Positive semi-definite but singular: the smallest eigenvalue lies in
  /// [-kSemiDefiniteTolerance * largest, 0] (rounding of a projected matrix lands here).
  kSemiDefinite,
  /// An eigenvalue below -kSemiDefiniteTolerance * largest eigenvalue.
  kIndefinite,
};
/// Relative tolerance on the smallest eigenvalue that still counts as semi-definite.
inline constexpr double kSemiDefiniteTolerance = 1e-9;

Definiteness classify_information(const Eigen::MatrixXd& information);

/// Nearest symmetric positive semi-definite matrix (Higham 1988): symmetrise, eigen-decompose,
/// clamp negative eigenvalues to zero.
Eigen::MatrixXd nearest_positive_semidefinite(const Eigen::MatrixXd& information);

/// Empty when every diagonal entry is finite and > 0; otherwise a message such as
/// "information diagonal entry I(3,3) is -1: expected > 0" (1-based indices).
std::string check_information_diagonal(const Eigen::MatrixXd& information);

}  // namespace cairn::io
