#include "cairn/backend/staircase.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "cairn/backend/chordal_relaxation.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/backend/trust_region.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::backend {
namespace {

using core::Clock;
using core::seconds_since;

/// The polar factor U W^T of A (r x d, full column rank): the nearest matrix with orthonormal columns.
Eigen::MatrixXd polar(const Eigen::MatrixXd& A) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  return svd.matrixU() * svd.matrixV().transpose();
}

/// The rank-r problem on St(d, r)^n x R^(r n) (see staircase.hpp) as a trust-region model
/// (trust_region.hpp): f(Y) with its Riemannian gradient and exact Riemannian Hessian in
/// orthonormal bases of the tangent spaces, LM damping lambda I (the Hessian may be indefinite
/// away from a minimum; the damping makes the system positive definite). Y is r x n(d+1).
class RankSolver final : public TrustRegionModel {
 public:
  RankSolver(const ChordalRelaxation& relaxation, int r, Eigen::MatrixXd& Y)
      : x_(relaxation), n_(relaxation.n), d_(relaxation.d), r_(r), q_(r + d_ * (d_ - 1) / 2 + (r - d_) * d_), Y_(Y) {
    cholesky_.require_ll();
    build_pattern();
    f_ = x_.f(Y_);
    linearize();
  }

  /// Minimises f from Y (LM of the shared minimiser); returns the iterations taken.
  int solve(const StaircaseOptions& options) {
    TrustRegionOptions minimizer;
    minimizer.max_iterations = options.max_iterations;
    minimizer.gradient_tolerance = options.gradient_tolerance;  // relative: gradient_max_norm()
    minimizer.function_tolerance = 1e-15;
    minimizer.parameter_tolerance = 0.0;
    // Damping starts at 1e-6 of the Hessian's largest diagonal entry and has no floor.
    double scale = 0.0;
    for (int column = 0; column < H_.size; ++column) scale = std::max(scale, std::abs(H_.value[H_.column_start[column + 1] - 1]));
    minimizer.initial_trust_region_radius = scale > 0.0 ? 1.0 / (1e-6 * scale) : 1e16;
    minimizer.max_trust_region_radius = std::numeric_limits<double>::infinity();
    minimizer.max_consecutive_invalid_steps = 60;
    minimizer.should_stop = options.polish.should_stop;
    return minimize(*this, minimizer).iterations;
  }

  bool start(double* cost, std::string* /*error*/) override {
    *cost = f_;
    return true;
  }
  /// max |grad| / max(1, f): the staircase's relative gradient tolerance.
  double gradient_max_norm() override { return g_.size() == 0 ? 0.0 : g_.cwiseAbs().maxCoeff() / std::max(1.0, f_); }
  double values_norm() override { return Y_.norm(); }
  const Eigen::VectorXd& gradient() override { return g_; }
  double curvature(const Eigen::VectorXd& v) override { return v.dot(symmetric_multiply(H_, v)); }
  double model_decrease(const Eigen::VectorXd& step) override { return -(g_.dot(step) + 0.5 * curvature(step)); }

  StepQuality compute_step(double lambda, Eigen::VectorXd& step, double* predicted, TrustRegionIteration& /*it*/) override {
    UpperCsc& csc = damped_;
    if (csc.size != H_.size) csc = H_;
    csc.value = H_.value;
    // Each column's diagonal entry is its last (rows sorted, upper triangle).
    for (int column = 0; column < csc.size; ++column) csc.value[csc.column_start[column + 1] - 1] += lambda;
    if (!analyzed_) {
      cholesky_.analyze(csc);
      analyzed_ = true;
    }
    // Not positive definite: the Hessian is indefinite here and needs more damping.
    if (cholesky_.factorize(csc) != FactorizationStatus::kSuccess) return StepQuality::kFailed;
    step = cholesky_.solve(Eigen::VectorXd(-g_));
    if (!step.allFinite()) return StepQuality::kFailed;
    *predicted = model_decrease(step);
    return StepQuality::kExact;
  }

  bool evaluate_trial(const Eigen::VectorXd& step, double* cost, TrustRegionIteration& /*it*/) override {
    trial_ = retract(Y_, step);
    *cost = x_.f(trial_);
    return std::isfinite(*cost);
  }

  void accept_trial(double /*old_cost*/, double new_cost, bool final, TrustRegionIteration& /*it*/) override {
    Y_ = std::move(trial_);
    f_ = new_cost;
    if (!final) linearize();
  }

  void reject_trial(StepQuality /*quality*/) override {}

 private:
  int variable(int p) const { return p < x_.anchor ? p : p - 1; }

  /// Bases, Euclidean gradient, Riemannian gradient and Hessian at Y.
  void linearize() {
    build_bases(Y_);
    const Eigen::MatrixXd G = 2.0 * (x_.M * Y_.transpose()).transpose();  // Euclidean gradient, r x N
    g_ = riemannian_gradient(G);
    fill_hessian(Y_, G);
  }

  /// The Hessian's pattern, fixed by M: the upper triangle of the pose-pair blocks that M couples
  /// (and every diagonal block), with each pair's (d + 1) x (d + 1) block of M gathered once, so
  /// that fill_hessian() writes values in place instead of a map lookup and a dynamic product per
  /// nonzero of M, triplets and two sparse copies per iteration (20 % of a 3D staircase's time;
  /// perf on torus3D, 2026-11-25).
  void build_pattern() {
    const int D = d_ + 1;
    std::vector<std::map<int, std::size_t>> column(static_cast<std::size_t>(n_));
    const auto m_block = [&](int a, int b) {
      auto [it, inserted] = column[static_cast<std::size_t>(b)].try_emplace(a, coupling_m_.size());
      if (inserted) coupling_m_.resize(coupling_m_.size() + static_cast<std::size_t>(D * D), 0.0);
      return it->second;
    };
    for (int p = 0; p < n_; ++p) {
      if (p != x_.anchor) m_block(p, p);
    }
    for (int c = 0; c < x_.M.outerSize(); ++c) {
      const auto [pc, lc] = local(c);
      if (pc == x_.anchor) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(x_.M, c); it; ++it) {
        const auto [pr, lr] = local(static_cast<int>(it.row()));
        if (pr == x_.anchor || pr > pc) continue;
        coupling_m_[m_block(pr, pc) + static_cast<std::size_t>(lr * D + lc)] += it.value();
      }
    }
    const int size = (n_ - 1) * q_;
    H_.size = size;
    H_.column_start.assign(static_cast<std::size_t>(size) + 1, 0);
    coupling_start_.assign(static_cast<std::size_t>(n_) + 1, 0);
    coupling_.clear();
    for (int b = 0; b < n_; ++b) {
      coupling_start_[static_cast<std::size_t>(b)] = static_cast<int>(coupling_.size());
      if (b == x_.anchor) continue;
      int prefix = 0;
      for (const auto& [a, m] : column[static_cast<std::size_t>(b)]) {  // sorted by a; a == b last
        coupling_.push_back({a, m, prefix});
        prefix += q_;
      }
      const int above = prefix - q_;  // rows of the blocks above the diagonal block
      for (int j = 0; j < q_; ++j) {
        const int col = variable(b) * q_ + j;
        H_.column_start[static_cast<std::size_t>(col) + 1] = H_.column_start[static_cast<std::size_t>(col)] + above + j + 1;
      }
    }
    coupling_start_[static_cast<std::size_t>(n_)] = static_cast<int>(coupling_.size());
    H_.row.resize(static_cast<std::size_t>(H_.column_start.back()));
    H_.value.assign(H_.row.size(), 0.0);
    for (int b = 0; b < n_; ++b) {
      if (b == x_.anchor) continue;
      for (int j = 0; j < q_; ++j) {
        int k = H_.column_start[static_cast<std::size_t>(variable(b) * q_ + j)];
        for (int e = coupling_start_[static_cast<std::size_t>(b)]; e < coupling_start_[static_cast<std::size_t>(b) + 1]; ++e) {
          const int a = coupling_[static_cast<std::size_t>(e)].a;
          const int rows = a == b ? j + 1 : q_;
          for (int i = 0; i < rows; ++i) H_.row[static_cast<std::size_t>(k++)] = variable(a) * q_ + i;
        }
      }
    }
  }

  /// Orthonormal bases of each pose's tangent space as (r (1 + d)) x q matrices acting on
  /// vec([t_p | Y_p]) (column-major).
  void build_bases(const Eigen::MatrixXd& Y) {
    bases_.assign(static_cast<std::size_t>(n_), Eigen::MatrixXd());
    for (int p = 0; p < n_; ++p) {
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(r_ * (1 + d_), q_);
      B.topLeftCorner(r_, r_).setIdentity();
      const Eigen::MatrixXd Yp = Y.block(0, n_ + p * d_, r_, d_);
      int column = r_;
      auto put = [&](const Eigen::MatrixXd& V) {
        B.col(column++).tail(r_ * d_) = Eigen::Map<const Eigen::VectorXd>(V.data(), r_ * d_);
      };
      for (int k = 0; k < d_; ++k) {
        for (int l = k + 1; l < d_; ++l) {
          Eigen::MatrixXd Omega = Eigen::MatrixXd::Zero(d_, d_);
          Omega(k, l) = -std::sqrt(0.5);
          Omega(l, k) = std::sqrt(0.5);
          put(Yp * Omega);
        }
      }
      if (r_ > d_) {
        const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Yp);
        const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(r_, r_);
        const Eigen::MatrixXd perp = Q.rightCols(r_ - d_);
        for (int m = 0; m < r_ - d_; ++m) {
          for (int c = 0; c < d_; ++c) {
            Eigen::MatrixXd V = Eigen::MatrixXd::Zero(r_, d_);
            V.col(c) = perp.col(m);
            put(V);
          }
        }
      }
      bases_[static_cast<std::size_t>(p)] = std::move(B);
    }
  }

  /// Column `column` of Y as (pose, local column: 0 = translation, 1 + c = column c of Y_p).
  std::pair<int, int> local(int column) const {
    if (column < n_) return {column, 0};
    return {(column - n_) / d_, 1 + (column - n_) % d_};
  }

  Eigen::VectorXd riemannian_gradient(const Eigen::MatrixXd& G) const {
    Eigen::VectorXd g = Eigen::VectorXd::Zero((n_ - 1) * q_);
    for (int p = 0; p < n_; ++p) {
      if (p == x_.anchor) continue;
      Eigen::MatrixXd Z(r_, 1 + d_);
      Z.col(0) = G.col(p);
      Z.rightCols(d_) = G.block(0, n_ + p * d_, r_, d_);
      g.segment(variable(p) * q_, q_) =
          bases_[static_cast<std::size_t>(p)].transpose() * Eigen::Map<const Eigen::VectorXd>(Z.data(), Z.size());
    }
    return g;
  }

  /// The exact Riemannian Hessian at Y into H_'s values: per coupled pair (a, b), a <= b,
  /// 2 B_a^T (M_ab (x) I_r) B_b, the Euclidean Hessian 2 M (x) I_r projected by the bases; on the
  /// diagonal blocks minus the Stiefel curvature (S_p (x) I_r) on vec(V_p),
  /// S_p = Sym(Y_p^T grad_p).
  void fill_hessian(const Eigen::MatrixXd& Y, const Eigen::MatrixXd& G) {
    const int D = d_ + 1;
    Eigen::MatrixXd T(D * r_, q_), block(q_, q_), kron = Eigen::MatrixXd::Zero(r_ * d_, r_ * d_);
    for (int b = 0; b < n_; ++b) {
      if (b == x_.anchor) continue;
      const Eigen::MatrixXd& Bb = bases_[static_cast<std::size_t>(b)];
      for (int e = coupling_start_[static_cast<std::size_t>(b)]; e < coupling_start_[static_cast<std::size_t>(b) + 1]; ++e) {
        const CouplingBlock& coupling = coupling_[static_cast<std::size_t>(e)];
        const double* m = coupling_m_.data() + coupling.m;
        for (int lr = 0; lr < D; ++lr) {
          auto rows = T.middleRows(lr * r_, r_);
          rows.setZero();
          for (int lc = 0; lc < D; ++lc) {
            if (m[lr * D + lc] != 0.0) rows.noalias() += m[lr * D + lc] * Bb.middleRows(lc * r_, r_);
          }
        }
        block.noalias() = 2.0 * bases_[static_cast<std::size_t>(coupling.a)].transpose() * T;
        if (coupling.a == b) {
          const Eigen::MatrixXd Yp = Y.block(0, n_ + b * d_, r_, d_);
          const Eigen::MatrixXd Gp = G.block(0, n_ + b * d_, r_, d_);
          const Eigen::MatrixXd P = Yp.transpose() * Gp;
          const Eigen::MatrixXd S = 0.5 * (P + P.transpose());
          const auto BR = Bb.bottomRows(r_ * d_);
          for (int i = 0; i < d_; ++i) {
            for (int k = 0; k < d_; ++k) kron.block(i * r_, k * r_, r_, r_) = S(i, k) * Eigen::MatrixXd::Identity(r_, r_);
          }
          block.noalias() -= BR.transpose() * kron * BR;
        }
        for (int j = 0; j < q_; ++j) {
          double* out = H_.value.data() + H_.column_start[static_cast<std::size_t>(variable(b) * q_ + j)] + coupling.prefix;
          const int rows = coupling.a == b ? j + 1 : q_;
          for (int i = 0; i < rows; ++i) out[i] = block(i, j);
        }
      }
    }
  }

  Eigen::MatrixXd retract(const Eigen::MatrixXd& Y, const Eigen::VectorXd& step) const {
    Eigen::MatrixXd out = Y;
    for (int p = 0; p < n_; ++p) {
      if (p == x_.anchor) continue;
      const Eigen::VectorXd v = bases_[static_cast<std::size_t>(p)] * step.segment(variable(p) * q_, q_);
      out.col(p) += v.head(r_);
      const Eigen::Map<const Eigen::MatrixXd> V(v.data() + r_, r_, d_);
      out.block(0, n_ + p * d_, r_, d_) = polar(Y.block(0, n_ + p * d_, r_, d_) + V);
    }
    return out;
  }

  const ChordalRelaxation& x_;
  int n_, d_, r_, q_;
  Eigen::MatrixXd& Y_;
  double f_ = 0.0;
  Eigen::VectorXd g_;
  struct CouplingBlock {
    int a;          ///< row pose, <= the column pose
    std::size_t m;  ///< its (d + 1) x (d + 1) block of M in coupling_m_, row-major
    int prefix;     ///< rows of its column's blocks above it
  };
  std::vector<int> coupling_start_;  ///< per column pose b: its blocks in coupling_ (by row pose)
  std::vector<CouplingBlock> coupling_;
  std::vector<double> coupling_m_;
  UpperCsc H_;       ///< the Riemannian Hessian's upper triangle
  UpperCsc damped_;  ///< H_ + lambda I for the factorisation
  Eigen::MatrixXd trial_;
  SparseCholesky cholesky_;
  bool analyzed_ = false;
  std::vector<Eigen::MatrixXd> bases_;
};

/// Y moved along the direction of negative curvature `escape` (a new last row, Y's others kept):
/// the largest step of 1, 1/2, 1/4, ... times sqrt(n) that lowers f.
bool escape_saddle(const ChordalRelaxation& x, const Eigen::RowVectorXd& escape, Eigen::MatrixXd& Y) {
  const int r = static_cast<int>(Y.rows()) + 1;
  Eigen::MatrixXd lifted = Eigen::MatrixXd::Zero(r, Y.cols());
  lifted.topRows(r - 1) = Y;
  const double f0 = x.f(lifted);
  for (double alpha = std::sqrt(static_cast<double>(x.n)); alpha > 1e-8; alpha *= 0.5) {
    Eigen::MatrixXd trial = lifted;
    trial.row(r - 1) = alpha * escape;
    for (int p = 0; p < x.n; ++p) trial.block(0, x.n + p * x.d, r, x.d) = polar(trial.block(0, x.n + p * x.d, r, x.d));
    if (x.f(trial) < f0 - 1e-12 * std::max(1.0, std::abs(f0))) {
      Y = trial;
      return true;
    }
  }
  return false;
}

/// Algorithm 2 of Rosen et al.: the d leading right singular directions of the rotation part
/// (Sigma_d V_d^T), the sign giving most blocks det > 0; each block is projected to SO(d) by
/// pose_from.
Eigen::MatrixXd leading_directions(const Eigen::MatrixXd& Yrot, int d) {
  const int n = static_cast<int>(Yrot.cols()) / d;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Yrot, Eigen::ComputeThinU | Eigen::ComputeThinV);
  Eigen::MatrixXd R = svd.matrixU().leftCols(d).transpose() * Yrot;
  int positive = 0;
  for (int p = 0; p < n; ++p) positive += R.block(0, p * d, d, d).determinant() > 0.0;
  if (positive < n - positive) R.row(d - 1) *= -1.0;
  return R;
}

}  // namespace

template <class Group>
StaircaseSummary riemannian_staircase(PoseGraphProblem<Group>& problem, const StaircaseOptions& options) {
  // The polish's thread count holds for the rank solves' factorisations too (0: as it is).
  // Unlimited, OpenBLAS's idle threads spin in sched_yield between calls: torus3D from a 3 rad
  // perturbation with --threads 1, 89 s of CPU (30 s of it system time) instead of 60 s.
  const ScopedBlasThreads blas(options.polish.threads);
  constexpr int d = kRotationDim<Group>;
  const auto start = Clock::now();
  StaircaseSummary summary;
  const ChordalRelaxation x = make_chordal_relaxation(problem);
  const Eigen::MatrixXd R0 = rotation_blocks(problem);
  Eigen::RowVectorXd escape;
  StaircaseLevel first;
  first.rank = d;
  first.certificate = certify_relaxation(x, R0, options.certificate, &escape);
  first.f = first.certificate.f;
  summary.levels.push_back(first);
  summary.certificate = first.certificate;
  summary.f_initial = summary.f_final = first.f;
  auto finish = [&](const std::string& message) {
    summary.message = message;
    summary.time_s = seconds_since(start);
    return summary;
  };
  if (first.certificate.certified) {
    summary.certified = true;
    return finish("certified at rank " + std::to_string(d));
  }
  if (!options.climb) return finish("not certified at rank " + std::to_string(d) + " (the staircase was not asked for)");
  if (x.fixed_count > 1) return finish("not certified; the staircase needs a graph with one fixed pose (the gauge)");
  if (escape.size() == 0) return finish("not certified; " + first.certificate.message);

  Eigen::MatrixXd Y;
  x.with_optimal_translations(R0, &Y);
  bool relaxation_certified = false;
  auto stopped = [&] { return options.polish.should_stop && options.polish.should_stop(); };
  for (int r = d + 1; r <= d + options.max_rank_increase; ++r) {
    if (stopped()) {
      summary.interrupted = true;
      return finish("interrupted at rank " + std::to_string(r - 1) + ": the poses are as they were");
    }
    if (escape.size() == 0) return finish("no direction of negative curvature at rank " + std::to_string(r - 1));
    if (!escape_saddle(x, escape, Y)) return finish("no descent along the direction of negative curvature at rank " + std::to_string(r - 1));
    StaircaseLevel level;
    level.rank = r;
    RankSolver solver(x, r, Y);
    level.iterations = solver.solve(options);
    level.certificate = certify_relaxation(x, Y.rightCols(x.n * d), options.certificate, &escape);
    level.f = level.certificate.f;
    summary.levels.push_back(level);
    if (level.certificate.certified) {
      relaxation_certified = true;
      break;
    }
  }
  if (!relaxation_certified) return finish("no rank up to " + std::to_string(d + options.max_rank_increase) + " certified");

  // Round, place in the frame of the fixed pose, polish at rank d, certify.
  using MatrixD = Eigen::Matrix<double, d, d>;
  using VectorD = Eigen::Matrix<double, d, 1>;
  Eigen::MatrixXd R = leading_directions(Y.rightCols(x.n * d), d);
  std::vector<Group> rounded(static_cast<std::size_t>(x.n));
  for (int p = 0; p < x.n; ++p) {
    rounded[static_cast<std::size_t>(p)] = pose_from<Group>(MatrixD(R.block(0, p * d, d, d)), VectorD::Zero());
    R.block(0, p * d, d, d) = rotation_matrix_of(rounded[static_cast<std::size_t>(p)]);
  }
  Eigen::MatrixXd Yd;
  x.with_optimal_translations(R, &Yd);
  PoseGraphProblem<Group> candidate = problem;
  for (int p = 0; p < x.n; ++p) {
    rounded[static_cast<std::size_t>(p)] = pose_from<Group>(MatrixD(R.block(0, p * d, d, d)), VectorD(Yd.col(p)));
  }
  const Group T_world_anchor = problem.T_world_pose[static_cast<std::size_t>(x.anchor)];
  const Group T_fix = T_world_anchor * rounded[static_cast<std::size_t>(x.anchor)].inverse();
  for (int p = 0; p < x.n; ++p) candidate.T_world_pose[static_cast<std::size_t>(p)] = T_fix * rounded[static_cast<std::size_t>(p)];
  OptimizerOptions polish = options.polish;
  polish.objective = Objective::kChordal;
  polish.kernel = RobustKernel::kNone;
  polish.edge_weights.clear();
  optimize(candidate, polish);
  if (stopped()) {
    summary.interrupted = true;
    return finish("interrupted while polishing the rounded point: the poses are as they were");
  }
  // The candidate has the problem's edges and fixed poses: the same relaxation.
  const CertificateSummary final_certificate = certify_relaxation(x, rotation_blocks(candidate), options.certificate);
  if (final_certificate.f < first.f) {
    problem.T_world_pose = candidate.T_world_pose;
    summary.certificate = final_certificate;
    summary.f_final = final_certificate.f;
  }
  summary.certified = summary.certificate.certified;
  return finish(summary.certified ? "certified after the staircase (relaxation certified at rank " +
                                        std::to_string(summary.levels.back().rank) + ", rounded and polished)"
                                  : "the relaxation is certified at rank " + std::to_string(summary.levels.back().rank) +
                                        " but its rounded point is not: the relaxation may not be exact here");
}

template StaircaseSummary riemannian_staircase(Problem2D&, const StaircaseOptions&);
template StaircaseSummary riemannian_staircase(Problem3D&, const StaircaseOptions&);

}  // namespace cairn::backend
