#pragma once
/// \file
/// SE-Sync's problem in matrix form, shared by the certificate (certificate.hpp) and the
/// Riemannian staircase (staircase.hpp). Rosen et al., IJRR 2019, eq. 13-16: with
/// Y = [t_1 .. t_n | Y_1 .. Y_n] (r x n(d+1); t_i in R^r, Y_i in St(d, r), r >= d; r = d and
/// Y_i = R_i is the pose graph itself), the chordal objective is f(Y) = tr(Y M Y^T) for the sparse
/// translation-explicit data matrix M. Column of t_p: p; of column m of Y_p: n + p d + m.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

#include "cairn/backend/certificate.hpp"
#include "cairn/backend/problem.hpp"

namespace cairn::backend {

struct ChordalRelaxation {
  int n = 0;
  int d = 0;
  /// The pose whose translation is held at 0 (the gauge): the first fixed pose.
  int anchor = 0;
  int fixed_count = 0;
  /// Full symmetric storage, n(d+1) square.
  Eigen::SparseMatrix<double> M;

  int columns() const { return n * (d + 1); }
  /// Index with the anchor's translation removed (-1 for it): the anchored system's numbering.
  int reduced(int column) const {
    return column < n ? (column == anchor ? -1 : column - (column > anchor)) : column - 1;
  }
  /// Y with the translations minimising f for the rotation blocks R (r x dn), anchor's at 0.
  /// False when the translational Laplacian is singular (a disconnected graph).
  bool with_optimal_translations(const Eigen::MatrixXd& R, Eigen::MatrixXd* Y) const;
  /// f(Y) = tr(Y M Y^T).
  double f(const Eigen::MatrixXd& Y) const;

  struct TranslationSolver;
  std::shared_ptr<TranslationSolver> translations;  // factorisation of the anchored M_tt
};

template <class Group>
ChordalRelaxation make_chordal_relaxation(const PoseGraphProblem<Group>& problem);

/// The rotation blocks [R_1 .. R_n] (d x dn) of the problem's poses.
template <class Group>
Eigen::MatrixXd rotation_blocks(const PoseGraphProblem<Group>& problem);

/// The certificate at rotation blocks R (r x dn, columns of each block orthonormal), as
/// certificate.hpp describes for r = d (the same for any r: Lambda_i = Sym((Q Y^T)_i Y_i)).
/// With `escape` non-null and the point not certified: the direction of negative curvature
/// (Rosen et al., Sec. 4.2.2, eq. 32): the eigenvector v of lambda_min(S) (rotation part, unit
/// norm) with its translation part -M_tt^-1 M_tR v, as a row of n(d+1) entries.
CertificateSummary certify_relaxation(const ChordalRelaxation& relaxation, const Eigen::MatrixXd& R,
                                      const CertificateOptions& options, Eigen::RowVectorXd* escape = nullptr);

}  // namespace cairn::backend
