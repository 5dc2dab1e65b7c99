#include "cairn/backend/certificate.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "cairn/backend/chordal_relaxation.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/timer.hpp"

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

struct ChordalRelaxation::TranslationSolver {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  bool ok = false;
};

template <class Group>
ChordalRelaxation make_chordal_relaxation(const PoseGraphProblem<Group>& problem) {
  constexpr int d = kRotationDim<Group>;
  using MatrixD = Eigen::Matrix<double, d, d>;
  using VectorD = Eigen::Matrix<double, d, 1>;
  ChordalRelaxation relaxation;
  const int n = problem.size();
  relaxation.n = n;
  relaxation.d = d;
  // Per edge, with residual rows written as a^T y for a row y of Y:
  //   translation row k:  t_j[k] - t_i[k] - sum_m Y_i[k, m] t~[m]   (weight tau)
  //   rotation row k, column c:  Y_j[k, c] - sum_m Y_i[k, m] R~[m, c]   (weight kappa)
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
  relaxation.M.resize(full, full);
  relaxation.M.setFromTriplets(triplets.begin(), triplets.end());
  for (int p = 0; p < n; ++p) {
    if (problem.fixed[static_cast<std::size_t>(p)]) {
      if (relaxation.fixed_count == 0) relaxation.anchor = p;
      ++relaxation.fixed_count;
    }
  }
  // The anchored translational Laplacian M_tt, factorised once.
  Triplets tt;
  for (int c = 0; c < n; ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(relaxation.M, c); it; ++it) {
      const int r = static_cast<int>(it.row());
      if (r < n && c != relaxation.anchor && r != relaxation.anchor) {
        tt.emplace_back(relaxation.reduced(r), relaxation.reduced(c), it.value());
      }
    }
  }
  Eigen::SparseMatrix<double> Mtt(std::max(n - 1, 0), std::max(n - 1, 0));
  Mtt.setFromTriplets(tt.begin(), tt.end());
  relaxation.translations = std::make_shared<ChordalRelaxation::TranslationSolver>();
  relaxation.translations->ldlt.compute(Mtt);
  relaxation.translations->ok = relaxation.translations->ldlt.info() == Eigen::Success;
  return relaxation;
}

template <class Group>
Eigen::MatrixXd rotation_blocks(const PoseGraphProblem<Group>& problem) {
  constexpr int d = kRotationDim<Group>;
  Eigen::MatrixXd R(d, problem.size() * d);
  for (int p = 0; p < problem.size(); ++p) {
    R.block<d, d>(0, p * d) = rotation_matrix_of(problem.T_world_pose[static_cast<std::size_t>(p)]);
  }
  return R;
}

bool ChordalRelaxation::with_optimal_translations(const Eigen::MatrixXd& R, Eigen::MatrixXd* Y) const {
  if (!translations || !translations->ok) return false;
  const int r = static_cast<int>(R.rows());
  // M_tt,red t_red = -(M_tR R^T)_red, one right-hand side per row of Y.
  const Eigen::SparseMatrix<double> MtR = M.block(0, n, n, n * d);
  const Eigen::MatrixXd B = MtR * R.transpose();  // n x r
  Eigen::MatrixXd B_reduced(n - 1, r);
  for (int p = 0; p < n; ++p) {
    if (p != anchor) B_reduced.row(reduced(p)) = B.row(p);
  }
  const Eigen::MatrixXd t_reduced = translations->ldlt.solve(-B_reduced);
  Y->setZero(r, columns());
  for (int p = 0; p < n; ++p) {
    if (p != anchor) Y->col(p) = t_reduced.row(reduced(p)).transpose();
  }
  Y->rightCols(n * d) = R;
  return true;
}

double ChordalRelaxation::f(const Eigen::MatrixXd& Y) const {
  const Eigen::MatrixXd G = M * Y.transpose();
  return Y.transpose().cwiseProduct(G).sum();
}

CertificateSummary certify_relaxation(const ChordalRelaxation& relaxation, const Eigen::MatrixXd& R,
                                      const CertificateOptions& options, Eigen::RowVectorXd* escape) {
  const auto start = core::Clock::now();
  if (escape != nullptr) escape->resize(0);  // set below only when a direction was found
  CertificateSummary summary;
  const int n = relaxation.n;
  const int d = relaxation.d;
  const int r = static_cast<int>(R.rows());
  summary.d = d;
  summary.rank = r;
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
  Eigen::MatrixXd Y;
  if (!relaxation.with_optimal_translations(R, &Y)) {
    summary.message = "the translational Laplacian is singular: is the graph connected?";
    return summary;
  }
  const Eigen::SparseMatrix<double>& M = relaxation.M;
  const Eigen::MatrixXd G = M * Y.transpose();  // n(d+1) x r; its rotation rows are Q Y^T
  summary.f = Y.transpose().cwiseProduct(G).sum();

  // Lambda_i = Sym((Q Y^T)_i Y_i), and K(eta) = M_anchored - diag(0, Lambda) + diag(0, eta I).
  const int full = relaxation.columns();
  Triplets k;
  k.reserve(static_cast<std::size_t>(M.nonZeros()) + static_cast<std::size_t>(n * d * (d + 1)));
  for (int c = 0; c < full; ++c) {
    const int rc = relaxation.reduced(c);
    if (rc < 0) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(M, c); it; ++it) {
      const int rr = relaxation.reduced(static_cast<int>(it.row()));
      if (rr >= 0 && rr <= rc) k.emplace_back(rr, rc, it.value());
    }
  }
  for (int p = 0; p < n; ++p) {
    const Eigen::MatrixXd P = G.block(n + p * d, 0, d, r) * R.block(0, p * d, r, d);
    const Eigen::MatrixXd Lambda = 0.5 * (P + P.transpose());
    for (int c = 0; c < d; ++c) {
      for (int q = 0; q <= c; ++q) k.emplace_back(n - 1 + p * d + q, n - 1 + p * d + c, -Lambda(q, c));
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
    bool found = false;
    for (eta_hi = 4.0 * tolerance; !failed && eta_hi < 1e300; eta_hi *= 4.0) {
      if (positive(eta_hi)) {
        found = true;
        break;
      }
      eta_lo = eta_hi;
    }
    if (!found) failed = true;  // no shift made K positive definite (non-finite entries?)
    for (int step = 0; step < options.bisection_steps && !failed; ++step) {
      const double mid = std::sqrt(eta_lo * eta_hi);
      if (positive(mid)) {
        eta_hi = mid;
      } else {
        eta_lo = mid;
      }
    }
  }
  if (escape != nullptr && !summary.certified && !failed && positive(eta_hi)) {
    // Inverse iteration with S + eta_hi I, positive definite with its smallest eigenvalue
    // lambda_min + eta_hi close to 0, through K(eta_hi): K [z_t; z_R] = [0; x] gives
    // z_R = (S + eta_hi I)^-1 x and z_t = -M_tt^-1 M_tR z_R, the translations that go with it.
    std::mt19937 rng(1);
    std::normal_distribution<double> normal(0.0, 1.0);
    Eigen::VectorXd x(n * d);
    for (int i = 0; i < x.size(); ++i) x(i) = normal(rng);
    x.normalize();
    Eigen::VectorXd z;
    for (int iteration = 0; iteration < 100; ++iteration) {
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(N);
      rhs.tail(n * d) = x;
      z = cholesky.solve(rhs);
      const double norm = z.tail(n * d).norm();
      z /= norm;
      const double change = (z.tail(n * d) - x).norm();
      x = z.tail(n * d);
      if (change < 1e-10) break;
    }
    escape->setZero(full);
    for (int p = 0; p < n; ++p) {
      if (p != relaxation.anchor) (*escape)(p) = z(relaxation.reduced(p));
    }
    escape->tail(n * d) = x.transpose();
  }
  if (failed) {
    summary.certified = false;
    summary.message = "the certificate matrix could not be factorised at any shift (CHOLMOD failed, or non-finite data)";
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
    if (relaxation.fixed_count > 1) {
      summary.message += "; the graph fixes " + std::to_string(relaxation.fixed_count) +
                         " poses: the certificate speaks of the problem with one (the gauge)";
    }
  }
  summary.time_s = core::seconds_since(start);
  return summary;
}

template <class Group>
CertificateSummary certify_chordal(const PoseGraphProblem<Group>& problem, const CertificateOptions& options) {
  const auto start = core::Clock::now();
  const ChordalRelaxation relaxation = make_chordal_relaxation(problem);
  CertificateSummary summary = certify_relaxation(relaxation, rotation_blocks(problem), options);
  summary.time_s = core::seconds_since(start);
  return summary;
}

template ChordalRelaxation make_chordal_relaxation(const Problem2D&);
template ChordalRelaxation make_chordal_relaxation(const Problem3D&);
template Eigen::MatrixXd rotation_blocks(const Problem2D&);
template Eigen::MatrixXd rotation_blocks(const Problem3D&);
template CertificateSummary certify_chordal(const Problem2D&, const CertificateOptions&);
template CertificateSummary certify_chordal(const Problem3D&, const CertificateOptions&);

}  // namespace cairn::backend
