#include "cairn/backend/certificate.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <limits>

#include "cairn/backend/sparse_cholesky.hpp"

namespace cairn::backend {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

/// Adds w v v^T for a sparse vector v given as (index, value) pairs.
template <std::size_t N>
void add_outer(Triplets& triplets, double w, const std::array<std::pair<int, double>, N>& v) {
  for (const auto& [p, a] : v) {
    for (const auto& [q, b] : v) triplets.emplace_back(p, q, w * a * b);
  }
}

}  // namespace

bool CertificateOptions::is_valid(std::string* error) const {
  std::string why;
  if (!(eigenvalue_tolerance > 0.0) || !std::isfinite(eigenvalue_tolerance)) why += "eigenvalue_tolerance must be > 0; ";
  if (refinement_decades < 0) why += "refinement_decades must be >= 0; ";
  if (bisection_steps < 0) why += "bisection_steps must be >= 0; ";
  if (error != nullptr) *error = why;
  return why.empty();
}

template <class Group>
CertificateSummary certify_chordal(const PoseGraphProblem<Group>& problem, const CertificateOptions& options) {
  constexpr int d = kRotationDim<Group>;
  using MatrixD = Eigen::Matrix<double, d, d>;
  using VectorD = Eigen::Matrix<double, d, 1>;
  const auto start = std::chrono::steady_clock::now();
  CertificateSummary summary;
  summary.d = d;
  const int n = problem.size();
  summary.poses = n;
  std::string invalid;
  if (!options.is_valid(&invalid)) {
    summary.message = "invalid options: " + invalid;
    return summary;
  }
  if (n < 2) {
    summary.certified = true;
    summary.lambda_min_upper = std::numeric_limits<double>::infinity();
    summary.message = "fewer than two poses: trivially optimal";
    return summary;
  }

  // The translation-explicit data matrix M of SE-Sync (eq. 13-16), in a row formulation: row k
  // of X = [t_1 .. t_n | R_1 .. R_n] (d x n(d+1)) is x, and f = sum_k x^T M x. Index of t_p is
  // p, of column m of R_p is n + p d + m. Per edge, with residual rows written as a^T x:
  //   translation row k:  t_j[k] - t_i[k] - sum_m R_i[k, m] t~[m]   (weight tau)
  //   rotation row k, column c:  R_j[k, c] - sum_m R_i[k, m] R~[m, c]   (weight kappa)
  const int full = n * (d + 1);
  Triplets triplets;
  triplets.reserve(problem.edges.size() * static_cast<std::size_t>((2 + d) * (2 + d) + d * (1 + d) * (1 + d)));
  for (const auto& edge : problem.edges) {
    const MatrixD R_ij = rotation_matrix_of(edge.T_i_j);
    const VectorD t_ij = edge.T_i_j.translation();
    std::array<std::pair<int, double>, 2 + d> a;
    a[0] = {edge.j, 1.0};
    a[1] = {edge.i, -1.0};
    for (int m = 0; m < d; ++m) a[static_cast<std::size_t>(2 + m)] = {n + edge.i * d + m, -t_ij(m)};
    add_outer(triplets, edge.tau, a);
    for (int c = 0; c < d; ++c) {
      std::array<std::pair<int, double>, 1 + d> b;
      b[0] = {n + edge.j * d + c, 1.0};
      for (int m = 0; m < d; ++m) b[static_cast<std::size_t>(1 + m)] = {n + edge.i * d + m, -R_ij(m, c)};
      add_outer(triplets, edge.kappa, b);
    }
  }
  Eigen::SparseMatrix<double> M(full, full);
  M.setFromTriplets(triplets.begin(), triplets.end());

  // Gauge: the translation of one pose (the first fixed one) is held; its row and column go.
  int anchor = 0;
  int fixed_count = 0;
  for (int p = 0; p < n; ++p) {
    if (problem.fixed[static_cast<std::size_t>(p)]) {
      if (fixed_count == 0) anchor = p;
      ++fixed_count;
    }
  }
  auto reduced = [&](int index) { return index < n ? (index == anchor ? -1 : index - (index > anchor)) : index - 1; };

  // Optimal translations for the given rotations: M_tt,red t_red = -(M_tR R^T)_red.
  Eigen::MatrixXd R(d, n * d);
  for (int p = 0; p < n; ++p) R.block<d, d>(0, p * d) = rotation_matrix_of(problem.T_world_pose[static_cast<std::size_t>(p)]);
  Triplets tt;
  for (int c = 0; c < n; ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(M, c); it; ++it) {
      if (it.row() < n && c != anchor && it.row() != anchor) tt.emplace_back(reduced(static_cast<int>(it.row())), reduced(c), it.value());
    }
  }
  Eigen::SparseMatrix<double> Mtt(n - 1, n - 1);
  Mtt.setFromTriplets(tt.begin(), tt.end());
  const Eigen::SparseMatrix<double> MtR = M.block(0, n, n, n * d);
  const Eigen::MatrixXd B = MtR * R.transpose();  // n x d
  Eigen::MatrixXd B_reduced(n - 1, d);
  for (int p = 0; p < n; ++p) {
    if (p != anchor) B_reduced.row(reduced(p)) = B.row(p);
  }
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> translations(Mtt);
  if (translations.info() != Eigen::Success) {
    summary.message = "the translational Laplacian is singular: is the graph connected?";
    return summary;
  }
  const Eigen::MatrixXd t_reduced = translations.solve(-B_reduced);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(d, full);
  for (int p = 0; p < n; ++p) {
    if (p != anchor) X.col(p) = t_reduced.row(reduced(p)).transpose();
  }
  X.rightCols(n * d) = R;
  const Eigen::MatrixXd G = M * X.transpose();  // full x d; its rotation rows are Q R^T
  summary.f = X.transpose().cwiseProduct(G).sum();

  // Lambda_i = Sym((Q R^T)_i R_i), and K(eta) = M_anchored - diag(0, Lambda) + diag(0, eta I).
  Triplets k;
  k.reserve(M.nonZeros() + static_cast<std::size_t>(n * d * (d + 1)));
  for (int c = 0; c < full; ++c) {
    const int rc = reduced(c);
    if (rc < 0) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(M, c); it; ++it) {
      const int rr = reduced(static_cast<int>(it.row()));
      if (rr >= 0 && rr <= rc) k.emplace_back(rr, rc, it.value());
    }
  }
  for (int p = 0; p < n; ++p) {
    const MatrixD P = G.block<d, d>(n + p * d, 0) * R.block<d, d>(0, p * d);
    const MatrixD Lambda = 0.5 * (P + P.transpose());
    for (int c = 0; c < d; ++c) {
      for (int r = 0; r <= c; ++r) k.emplace_back(n - 1 + p * d + r, n - 1 + p * d + c, -Lambda(r, c));
    }
  }
  const int N = full - 1;
  Eigen::SparseMatrix<double> K(N, N);  // upper triangle, diagonal present everywhere
  K.setFromTriplets(k.begin(), k.end());
  K.makeCompressed();
  UpperCsc A;
  A.size = N;
  A.column_start.assign(K.outerIndexPtr(), K.outerIndexPtr() + N + 1);
  A.row.assign(K.innerIndexPtr(), K.innerIndexPtr() + K.nonZeros());
  A.value.assign(K.valuePtr(), K.valuePtr() + K.nonZeros());
  const std::vector<double> base = A.value;
  std::vector<int> rotation_diagonal;  // the last entry of each rotation column is its diagonal
  for (int c = n - 1; c < N; ++c) rotation_diagonal.push_back(A.column_start[static_cast<std::size_t>(c) + 1] - 1);

  SparseCholesky cholesky;
  cholesky.require_ll();  // a simplicial LDL^T would factorise an indefinite K without a word
  cholesky.analyze(A);
  summary.factor_nonzeros = cholesky.factor_nonzeros();
  bool failed = false;
  // True when S + eta I is positive definite.
  auto positive = [&](double eta) {
    A.value = base;
    for (const int at : rotation_diagonal) A.value[static_cast<std::size_t>(at)] += eta;
    ++summary.factorizations;
    const FactorizationStatus status = cholesky.factorize(A);
    if (status == FactorizationStatus::kFailure) failed = true;
    return status == FactorizationStatus::kSuccess;
  };

  // Cholesky succeeds on K + E with ||E|| of order eps ||K|| (backward stability), so shifts
  // below that resolution prove nothing: the refinement stops there.
  double largest_diagonal = 0.0;
  for (int c = 0; c < N; ++c) {
    largest_diagonal = std::max(largest_diagonal, std::abs(base[static_cast<std::size_t>(A.column_start[static_cast<std::size_t>(c) + 1] - 1)]));
  }
  const double resolution = 100.0 * std::numeric_limits<double>::epsilon() * largest_diagonal;
  const double tolerance = options.eigenvalue_tolerance;
  double eta_hi = tolerance;  // S + eta_hi I > 0: lambda_min(S) > -eta_hi
  double eta_lo = std::numeric_limits<double>::quiet_NaN();  // S + eta_lo I not > 0
  if (positive(tolerance)) {
    summary.certified = true;
    for (int decade = 0; decade < options.refinement_decades; ++decade) {
      const double eta = eta_hi / 10.0;
      if (eta < resolution) break;
      if (!positive(eta)) {
        eta_lo = eta;
        break;
      }
      eta_hi = eta;
    }
  } else if (!failed) {
    eta_lo = tolerance;
    // Grow the shift until S + eta I is positive definite; |lambda_min(S)| is at most ||S||,
    // far below the cap.
    for (eta_hi = 4.0 * tolerance; !positive(eta_hi) && !failed && eta_hi < 1e300; eta_hi *= 4.0) eta_lo = eta_hi;
    for (int step = 0; step < options.bisection_steps && !failed; ++step) {
      const double mid = std::sqrt(eta_lo * eta_hi);
      if (positive(mid)) {
        eta_hi = mid;
      } else {
        eta_lo = mid;
      }
    }
  }
  if (failed) {
    summary.certified = false;
    summary.message = "CHOLMOD failed to factorise the certificate matrix (out of memory?)";
    summary.lambda_min_lower = -std::numeric_limits<double>::infinity();
    summary.lambda_min_upper = std::numeric_limits<double>::infinity();
    summary.suboptimality_bound = std::numeric_limits<double>::infinity();
    summary.relative_suboptimality_bound = std::numeric_limits<double>::infinity();
  } else {
    summary.lambda_min_lower = -eta_hi;
    summary.lambda_min_upper = std::isnan(eta_lo) ? std::numeric_limits<double>::infinity() : -eta_lo;
    summary.suboptimality_bound = static_cast<double>(n) * d * eta_hi;
    summary.relative_suboptimality_bound = summary.f > 0.0 ? summary.suboptimality_bound / summary.f : 0.0;
    char text[256];
    std::snprintf(text, sizeof text, "%s: lambda_min(S) in [%.3g, %.3g]; f - f* <= %.3g (%.2g relative)",
                  summary.certified ? "certified globally optimal" : "not certified",
                  summary.lambda_min_lower, summary.lambda_min_upper, summary.suboptimality_bound,
                  summary.relative_suboptimality_bound);
    summary.message = text;
    if (fixed_count > 1) {
      summary.message += "; the graph fixes " + std::to_string(fixed_count) +
                         " poses: the certificate speaks of the problem with one (the gauge)";
    }
  }
  summary.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

template CertificateSummary certify_chordal(const Problem2D&, const CertificateOptions&);
template CertificateSummary certify_chordal(const Problem3D&, const CertificateOptions&);

}  // namespace cairn::backend
