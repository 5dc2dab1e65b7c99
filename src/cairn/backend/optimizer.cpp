#include "cairn/backend/optimizer.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <type_traits>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "cairn/backend/factors.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/threads.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::backend {

std::string_view to_string(Objective objective) {
  return objective == Objective::kGeodesic ? "geodesic" : "chordal";
}

OptimizerOptions::OptimizerOptions() {
  max_iterations = 100;
  function_tolerance = 1e-12;
  parameter_tolerance = 1e-10;
  initial_trust_region_radius = 1e16;
  max_trust_region_radius = std::numeric_limits<double>::infinity();
  min_damping_after_rejection = 1e-4;
  max_consecutive_invalid_steps = std::numeric_limits<int>::max();
}

bool OptimizerOptions::is_valid(std::string* error) const {
  std::string problems;
  TrustRegionOptions::is_valid(&problems);
  auto check = [&](bool ok, const char* what) {
    if (!ok) problems += std::string(problems.empty() ? "" : "; ") + what;
  };
  check(kernel_scale > 0.0, "kernel_scale must be > 0");
  check(threads >= 0, "threads must be >= 0");
  check(reuse_cg_tolerance > 0.0 && reuse_cg_tolerance < 1.0, "reuse_cg_tolerance must be in (0, 1)");
  check(reuse_max_cg_iterations >= 0, "reuse_max_cg_iterations must be >= 0");
  check(reuse_step_fraction > 0.0 && reuse_step_fraction <= 1.0, "reuse_step_fraction must be in (0, 1]");
  check(coupling_weight_floor >= 0.0, "coupling_weight_floor must be >= 0");
  if (error != nullptr) *error = problems;
  return problems.empty();
}

std::string OptimizerSummary::brief_report() const {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, "cost %.10g -> %.10g in %d iterations (%d accepted), %.3f s: %s (%s)",
                initial_cost, final_cost, iterations, successful_iterations, total_s,
                std::string(to_string(termination)).c_str(), message.c_str());
  return buffer;
}

namespace {

using core::Clock;
using core::seconds_since;


// OptimizerOptions::edge_weights[e], 1 when there are none.
double edge_weight(const OptimizerOptions& options, std::size_t e) {
  return options.edge_weights.empty() ? 1.0 : options.edge_weights[e];
}

template <class Group, class Factor>
class PoseGraphSystem {
  // Edges per task of the parallel evaluation.
  static constexpr std::size_t kGrain = 128;

 public:
  static constexpr int D = Group::kDoF;
  using BlockVector = Eigen::Matrix<double, D, 1>;

  PoseGraphSystem(PoseGraphProblem<Group>& problem, const OptimizerOptions& options, const std::vector<int>& variable,
         const std::vector<char>& in_pattern, BlockPattern& pattern)
      : problem_(problem),
        options_(options),
        arena_(core::arena_concurrency(options.threads)),
        variable_(variable),
        in_pattern_(in_pattern),
        free_poses_(pattern.matrix().size / D),
        pattern_(pattern) {
    blocks_.resize(problem.edges.size());
    gradient_ = Eigen::VectorXd::Zero(free_poses_ * D);
  }

  int free_poses() const { return free_poses_; }
  /// Chordal objective with exact_chordal_hessian: whether evaluate() adds the second-order term.
  bool second_order() const { return second_order_; }
  void set_second_order(bool on) { second_order_ = on; }
  BlockPattern& pattern() { return pattern_; }
  const Eigen::VectorXd& gradient() const { return gradient_; }

  double weight_of(std::size_t e) const { return edge_weight(options_, e); }

  /// Cost sum_e w_e rho(||r_e||^2) at `poses`, and each edge's J^T J and J^T r blocks there
  /// for a later assemble(): a trial point is linearised as its cost is evaluated, so an
  /// accepted step (most of them, from LM's undamped start) does not evaluate its residuals a
  /// second time. A rejected step leaves blocks that are never assembled.
  /// The sum runs in edge order whatever the threads, so a solve gives the same bits with any
  /// thread count and from run to run (a parallel_reduce adds in the order its tasks finish: GNC
  /// on corrupted manhattan then ended in a worse local minimum in 2 of 10 runs, 2026-11-24).
  double evaluate(const std::vector<Group>& poses) {
    const tbb::blocked_range<std::size_t> all(0, problem_.edges.size(), kGrain);
    if (!all.is_divisible() || options_.threads == 1) {  // no task machinery
      double sum = 0.0;
      for (std::size_t e = 0; e < problem_.edges.size(); ++e) sum += linearize_edge(e, poses);
      return sum;
    }
    edge_cost_.resize(problem_.edges.size());
    arena_.execute([&] {
      tbb::parallel_for(all, [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t e = range.begin(); e != range.end(); ++e) edge_cost_[e] = linearize_edge(e, poses);
      });
    });
    double sum = 0.0;
    for (const double c : edge_cost_) sum += c;
    return sum;
  }

  /// Fills the pattern's values with J^T J and gradient_ with J^T r from the blocks of the last
  /// evaluate() (edges outside the pattern, below coupling_weight_floor, in the gradient only).
  void assemble() {
    pattern_.set_zero();
    gradient_.setZero();
    for (std::size_t e = 0; e < problem_.edges.size(); ++e) {
      if (weight_of(e) == 0.0) continue;
      const auto& edge = problem_.edges[e];
      const auto& b = blocks_[e];
      const int vi = variable_[static_cast<std::size_t>(edge.i)];
      const int vj = variable_[static_cast<std::size_t>(edge.j)];
      // Edges outside the pattern (coupling_weight_floor) add to the gradient only. Keeping
      // their diagonal blocks without the off-diagonal one was tried: that error of H is
      // indefinite, and LM then crept (intel with 300 weak false loop closures: not converged
      // in 100 iterations, against 83 without any of their blocks and 62 with all).
      if (vi >= 0) gradient_.template segment<D>(vi * D) += b.gi;
      if (vj >= 0) gradient_.template segment<D>(vj * D) += b.gj;
      if (!in_pattern_[e]) continue;
      if (vi >= 0) pattern_.add_diagonal_packed(vi, b.Hii.data());
      if (vj >= 0) pattern_.add_diagonal_packed(vj, b.Hjj.data());
      if (vi >= 0 && vj >= 0) {
        if (vi < vj) {
          pattern_.add_off_diagonal(vi, vj, b.Hij.data());
        } else {
          const Eigen::Matrix<double, D, D, Eigen::RowMajor> Hji = b.Hij.transpose();
          pattern_.add_off_diagonal(vj, vi, Hji.data());
        }
      }
    }
  }

  std::vector<Group> apply(const Eigen::VectorXd& step) const {
    std::vector<Group> poses = problem_.T_world_pose;
    for (int p = 0; p < problem_.size(); ++p) {
      const int v = variable_[static_cast<std::size_t>(p)];
      if (v < 0) continue;
      const typename Group::Tangent delta = step.template segment<D>(v * D);
      poses[static_cast<std::size_t>(p)] = poses[static_cast<std::size_t>(p)] * Group::exp(delta);
    }
    return poses;
  }

  double translation_norm() const {
    double sum = 0.0;
    for (const auto& T : problem_.T_world_pose) sum += T.translation().squaredNorm();
    return std::sqrt(sum);
  }

 private:
  struct EdgeBlocks {
    // The symmetric diagonal blocks as packed upper triangles (BlockPattern::add_diagonal_packed;
    // 2 x 15 doubles less per 3D edge, measured 2.1 MB on sphere_bignoise), the off-diagonal one
    // row-major so BlockPattern can read it as M[a * B + k].
    std::array<double, D*(D + 1) / 2> Hii, Hjj;
    Eigen::Matrix<double, D, D, Eigen::RowMajor> Hij;
    BlockVector gi, gj;
  };

  // The upper triangle of J^T J, packed column by column (only the D (D + 1) / 2 distinct
  // column products; the full product computes the lower triangle again).
  template <class JacobianT>
  static void pack_upper_gram(const JacobianT& J, std::array<double, D*(D + 1) / 2>& packed) {
    std::size_t index = 0;
    for (int k = 0; k < D; ++k) {
      for (int a = 0; a <= k; ++a) packed[index++] = J.col(a).dot(J.col(k));
    }
  }

  // Fills blocks_[e] at `poses`; returns the edge's cost w rho(||r||^2).
  double linearize_edge(std::size_t e, const std::vector<Group>& poses) {
    const auto& edge = problem_.edges[e];
    typename Factor::Jacobian Ji;
    typename Factor::Jacobian Jj;
    typename Factor::Residual r = Factor::evaluate(poses[static_cast<std::size_t>(edge.i)],
                                                   poses[static_cast<std::size_t>(edge.j)], edge, &Ji, &Jj);
    const double w = weight_of(e);
    const KernelValue kernel = evaluate_kernel(options_.kernel, options_.kernel_scale, r.squaredNorm());
    // IRLS: scale by sqrt(w rho'(s)) (robust_kernel.hpp).
    const double scale = std::sqrt(w * kernel.weight);
    Eigen::Matrix<double, D, D> S_ii;
    Eigen::Matrix<double, D, D> S_jj;
    bool second_order = false;
    if constexpr (std::is_same_v<Factor, ChordalFactor<Group>>) {
      if (options_.exact_chordal_hessian && second_order_) {
        // The exact Hessian J^T J + S (ChordalFactor::second_order), weighted as J^T J is.
        Factor::second_order(poses[static_cast<std::size_t>(edge.i)], poses[static_cast<std::size_t>(edge.j)], edge, r,
                             &S_ii, &S_jj);
        S_ii *= scale * scale;
        S_jj *= scale * scale;
        second_order = true;
      }
    }
    if (scale != 1.0) {
      r *= scale;
      Ji *= scale;
      Jj *= scale;
    }
    auto& b = blocks_[e];
    pack_upper_gram(Ji, b.Hii);
    pack_upper_gram(Jj, b.Hjj);
    if (second_order) {
      std::size_t index = 0;
      for (int k = 0; k < D; ++k) {
        for (int a = 0; a <= k; ++a, ++index) {
          b.Hii[index] += S_ii(a, k);
          b.Hjj[index] += S_jj(a, k);
        }
      }
    }
    b.Hij.noalias() = Ji.transpose() * Jj;
    b.gi.noalias() = Ji.transpose() * r;
    b.gj.noalias() = Jj.transpose() * r;
    return w * kernel.rho;
  }

  PoseGraphProblem<Group>& problem_;
  const OptimizerOptions& options_;
  tbb::task_arena arena_;
  const std::vector<int>& variable_;
  const std::vector<char>& in_pattern_;  // per edge: its off-diagonal block is in pattern_
  int free_poses_ = 0;
  BlockPattern& pattern_;
  std::vector<EdgeBlocks> blocks_;
  std::vector<double> edge_cost_;  // per edge, summed in order by evaluate()
  Eigen::VectorXd gradient_;
  bool second_order_ = false;
};

// Chordal objective: Gauss-Newton's J^T J (positive semidefinite, robust far from a minimum)
// until an accepted step lowers the cost by less than this fraction, then the exact Hessian
// (quadratic convergence). From perturbed starts the exact Hessian from the first iteration
// stalled where Gauss-Newton did not (smallGrid3D, 1 of 30 starts with 3 rad rotation noise).
constexpr double kSecondOrderSwitch = 1e-3;

// Preconditioned conjugate gradients (Hestenes & Stiefel 1952; Nocedal & Wright, Numerical
// Optimization, 2nd ed., alg. 5.3) on (H + diag(damping)) x = b, H the upper-stored J^T J,
// preconditioned by a Cholesky factorisation of an earlier damped matrix. Converged when
// ||b - A x|| <= forcing ||b|| (an inexact Newton step, Dembo, Eisenstat & Steihaug 1982).
// Gives up after `max_iterations`, or earlier, from the third iteration on, when the mean
// residual reduction so far would need more than `max_iterations` in all.
struct PcgResult {
  Eigen::VectorXd x;
  Eigen::VectorXd residual;  // b - (H + diag(damping)) x, as CG updates it
  int iterations = 0;
  bool converged = false;
};

PcgResult preconditioned_cg(const UpperCsc& H, const Eigen::VectorXd& damping, const Eigen::VectorXd& b,
                            SparseCholesky& preconditioner, int max_iterations, double forcing) {
  PcgResult result;
  const Eigen::Index n = b.size();
  result.x = Eigen::VectorXd::Zero(n);
  const double b_norm = b.norm();
  if (b_norm == 0.0) {
    result.converged = true;
    return result;
  }
  Eigen::VectorXd r = b;
  Eigen::VectorXd z(n);
  Eigen::VectorXd p(n);
  Eigen::VectorXd Ap(n);
  double rz_previous = 0.0;
  for (int i = 1; i <= max_iterations; ++i) {
    preconditioner.solve_in_place(r, z);
    const double rz = r.dot(z);
    if (!std::isfinite(rz) || rz <= 0.0) break;  // preconditioner not positive definite here
    if (i == 1) {
      p = z;
    } else {
      p = z + (rz / rz_previous) * p;
    }
    rz_previous = rz;
    symmetric_multiply(H, p, Ap);
    Ap += damping.cwiseProduct(p);
    const double pAp = p.dot(Ap);
    if (!std::isfinite(pAp) || pAp <= 0.0) break;  // not positive definite along p
    const double alpha = rz / pAp;
    result.x += alpha * p;
    r -= alpha * Ap;
    result.iterations = i;
    const double relative = r.norm() / b_norm;
    if (relative <= forcing) {
      result.converged = true;
      result.residual = std::move(r);
      break;
    }
    if (i >= 3 && relative < 1.0) {
      const double rate = std::pow(relative, 1.0 / i);
      if (i + std::log(forcing / relative) / std::log(rate) > max_iterations) break;
    } else if (i >= 3) {
      break;  // no progress at all
    }
  }
  return result;
}

}  // namespace

struct OptimizerWorkspace::State {
  std::vector<int> variable;     // pose -> variable index (elimination order), -1 for fixed poses
  std::vector<char> fixed;       // the problem's fixed poses when `variable` was made
  std::vector<char> in_pattern;  // per edge: its blocks are in `pattern`
  std::size_t pattern_edges = 0;
  std::unique_ptr<BlockPattern> pattern;
  std::unique_ptr<SparseCholesky> cholesky;
};

OptimizerWorkspace::OptimizerWorkspace() = default;
OptimizerWorkspace::~OptimizerWorkspace() = default;

namespace {

// Brings `state` to a pattern (and symbolic analysis) that holds every edge that couples its
// poses (weight non-zero and at least coupling_weight_floor): kept if it already does and few of
// its edges are inactive, else rebuilt without the others (random false loop closures couple
// distant poses and fill the factor in).
// Returns true when it analysed anew.
template <class Group>
bool prepare_pattern(PoseGraphProblem<Group>& problem, const OptimizerOptions& options,
                     double max_inactive_fraction, OptimizerWorkspace::State& state) {
  const std::size_t m = problem.edges.size();
  // Edges whose off-diagonal blocks belong in the pattern (OptimizerOptions::coupling_weight_floor).
  auto couples = [&](std::size_t e) {
    const double w = edge_weight(options, e);
    return w != 0.0 && w >= options.coupling_weight_floor;
  };
  std::vector<int> variable(static_cast<std::size_t>(problem.size()), -1);
  int free_poses = 0;
  for (int p = 0; p < problem.size(); ++p) {
    if (!problem.fixed[static_cast<std::size_t>(p)]) variable[static_cast<std::size_t>(p)] = free_poses++;
  }
  if (state.pattern && state.fixed == problem.fixed && state.in_pattern.size() == m) {
    bool covered = true;
    std::size_t inactive = 0;
    for (std::size_t e = 0; e < m && covered; ++e) {
      const bool active = couples(e);
      if (active && !state.in_pattern[e]) covered = false;
      if (!active && state.in_pattern[e]) ++inactive;
    }
    if (covered && static_cast<double>(inactive) <= max_inactive_fraction * static_cast<double>(state.pattern_edges)) {
      return false;
    }
  }
  state.in_pattern.assign(m, 0);
  state.pattern_edges = 0;
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t e = 0; e < m; ++e) {
    if (!couples(e)) continue;
    state.in_pattern[e] = 1;
    ++state.pattern_edges;
    const int a = variable[static_cast<std::size_t>(problem.edges[e].i)];
    const int b = variable[static_cast<std::size_t>(problem.edges[e].j)];
    if (a >= 0 && b >= 0) pairs.emplace_back(a, b);
  }
  // Variables numbered in elimination order, so CHOLMOD factorises the matrix as stored.
  const std::vector<int>& label = block_amd_labels(free_poses, pairs, problem.elimination_order);
  apply_block_labels(label, variable, pairs);
  state.variable = std::move(variable);
  state.fixed = problem.fixed;
  state.pattern = std::make_unique<BlockPattern>(free_poses, Group::kDoF, pairs);
  state.cholesky = std::make_unique<SparseCholesky>();
  if (free_poses > 0) state.cholesky->analyze_in_stored_order(state.pattern->matrix());
  return true;
}

// The pose graph as the trust-region minimiser sees it (trust_region.hpp): the current poses
// with their assembled J^T J and J^T r, the trial poses, and the linear algebra of a step:
// CHOLMOD on the damped J^T J, or PCG preconditioned with an earlier factorisation
// (OptimizerOptions::reuse_factorization).
template <class Group, class Factor>
class PoseGraphModel final : public TrustRegionModel {
 public:
  PoseGraphModel(PoseGraphProblem<Group>& problem, const OptimizerOptions& options, PoseGraphSystem<Group, Factor>& system,
                 SparseCholesky& cholesky, OptimizerSummary& summary)
      : problem_(problem), options_(options), system_(system), cholesky_(cholesky), summary_(summary) {
    reuse_ = options.algorithm == Algorithm::kLevenbergMarquardt && options.reuse_factorization;
    // PCG budget before refactorising (OptimizerOptions::reuse_max_cg_iterations); 0: a quarter
    // of a factorisation's flops spent in iterations of two triangular solves (4 flops per
    // factor non-zero) and one product with H (4 per stored entry).
    cg_budget_ = options.reuse_max_cg_iterations;
    if (cg_budget_ == 0) {
      const double per_iteration = 4.0 * static_cast<double>(cholesky.factor_nonzeros()) +
                                   4.0 * static_cast<double>(system.pattern().matrix().value.size());
      cg_budget_ = static_cast<int>(std::clamp(0.25 * cholesky.factor_flops() / per_iteration, 8.0, 30.0));
    }
  }

  bool start(double* cost, std::string* /*error*/) override {
    const auto t0 = Clock::now();
    *cost = system_.evaluate(problem_.T_world_pose);
    linearize();
    summary_.linearize_s += seconds_since(t0);
    previous_gradient_max_norm_ = gradient_max_norm_;
    return true;
  }

  double gradient_max_norm() override { return gradient_max_norm_; }
  double values_norm() override { return system_.translation_norm(); }
  const Eigen::VectorXd& gradient() override { return system_.gradient(); }

  double curvature(const Eigen::VectorXd& v) override { return v.dot(symmetric_multiply(system_.pattern().matrix(), v)); }

  // Cost ||r||^2 (no 1/2): ||r||^2 - ||r + J s||^2 = -2 g^T s - s^T H s.
  double model_decrease(const Eigen::VectorXd& step) override { return -2.0 * gradient().dot(step) - curvature(step); }

  StepQuality compute_step(double lambda, Eigen::VectorXd& step, double* predicted, TrustRegionIteration& it) override {
    const Eigen::VectorXd& g = system_.gradient();
    auto& A = system_.pattern().matrix();
    // LM's damping lambda D, D = diag(J^T J) clamped as Ceres does; used by PCG and added to
    // the diagonal before a factorisation. Empty for Gauss-Newton (lambda = 0).
    damping_.resize(lambda > 0.0 ? A.size : 0);
    for (Eigen::Index k = 0; k < damping_.size(); ++k) {
      damping_[k] = lambda * std::clamp(diagonal_[static_cast<std::size_t>(k)], 1e-6, 1e32);
    }
    if (reuse_ && lambda > 0.0 && cholesky_.has_factor() && !force_factorization_ &&
        last_step_ <= options_.reuse_step_fraction * largest_step_) {
      // Inexact LM step: PCG on the current damped system, the last factorisation as
      // preconditioner. Forcing term (Eisenstat & Walker 1996, choice 1 in spirit): the
      // gradient's reduction over the last iteration, at most reuse_cg_tolerance, at least 1e-8.
      // Loose while the gradient falls slowly, tight when it falls fast, so the superlinear
      // convergence of the exact steps is kept near the minimum.
      const auto t0 = Clock::now();
      const double forcing =
          std::clamp(gradient_max_norm_ / previous_gradient_max_norm_, 1e-8, options_.reuse_cg_tolerance);
      PcgResult pcg = preconditioned_cg(A, damping_, -g, cholesky_, cg_budget_, forcing);
      it.solve_s += seconds_since(t0);
      it.cg_iterations = pcg.iterations;
      if (pcg.converged && pcg.x.allFinite()) {
        step = std::move(pcg.x);
        it.reused_factorization = true;
        // With PCG's residual rho = -g - (H + lambda D) step: step^T H step = -g^T step -
        // step^T rho - lambda step^T D step, so the decrease of ||r + J step||^2 is
        // -g^T step + step^T rho + lambda step^T D step (no product with H).
        *predicted = -g.dot(step) + step.dot(pcg.residual) + step.dot(damping_.cwiseProduct(step));
        return StepQuality::kInexact;
      }
    }
    for (Eigen::Index k = 0; k < damping_.size(); ++k) {
      A.value[static_cast<std::size_t>(system_.pattern().diagonal_index(static_cast<int>(k)))] += damping_[k];
    }
    force_factorization_ = false;
    const auto t1 = Clock::now();
    const FactorizationStatus status = cholesky_.factorize(A);
    ++summary_.factorizations;
    it.factorize_s += seconds_since(t1);
    for (Eigen::Index k = 0; k < damping_.size(); ++k) {  // back to the undamped J^T J
      const int index = system_.pattern().diagonal_index(static_cast<int>(k));
      A.value[static_cast<std::size_t>(index)] = diagonal_[static_cast<std::size_t>(k)];
    }
    if (status != FactorizationStatus::kSuccess) return StepQuality::kFailed;
    const auto t2 = Clock::now();
    step = cholesky_.solve(Eigen::VectorXd(-g));
    it.solve_s += seconds_since(t2);
    if (!step.allFinite()) return StepQuality::kFailed;
    // (H + lambda D) step = -g  =>  step^T H step = -g^T step - lambda step^T D step, so the
    // decrease of ||r + J step||^2 is -g^T step + lambda step^T D step.
    *predicted = -g.dot(step) + (damping_.size() > 0 ? step.dot(damping_.cwiseProduct(step)) : 0.0);
    return StepQuality::kExact;
  }

  bool evaluate_trial(const Eigen::VectorXd& step, double* cost, TrustRegionIteration& it) override {
    candidate_ = system_.apply(step);
    const auto t0 = Clock::now();
    *cost = system_.evaluate(candidate_);
    it.linearize_s += seconds_since(t0);
    return std::isfinite(*cost);
  }

  void accept_trial(double old_cost, double new_cost, bool final, TrustRegionIteration& it) override {
    problem_.T_world_pose = std::move(candidate_);
    previous_gradient_max_norm_ = gradient_max_norm_;
    last_step_ = it.step_norm;
    largest_step_ = std::max(largest_step_, it.step_norm);
    if (final) return;
    const auto t0 = Clock::now();
    // Chordal objective, LM only (Gauss-Newton and dog-leg need a positive semidefinite model):
    // the exact Hessian once Gauss-Newton's steps make little progress (kSecondOrderSwitch).
    if (options_.algorithm == Algorithm::kLevenbergMarquardt && options_.exact_chordal_hessian &&
        options_.objective == Objective::kChordal && !system_.second_order() &&
        old_cost - new_cost < kSecondOrderSwitch * old_cost) {
      system_.set_second_order(true);
      system_.evaluate(problem_.T_world_pose);  // the blocks again, now with the second-order term
    }
    linearize();
    it.linearize_s += seconds_since(t0);
  }

  void reject_trial(StepQuality quality) override {
    // A rejected PCG step is retried from a fresh factorisation with the same damping.
    if (quality == StepQuality::kInexact) force_factorization_ = true;
    candidate_.clear();
  }

 private:
  // J^T J and J^T r from the blocks of the last evaluate() at the current poses.
  void linearize() {
    system_.assemble();
    const auto& A = system_.pattern().matrix();
    diagonal_.resize(static_cast<std::size_t>(A.size));
    for (int k = 0; k < A.size; ++k) {
      diagonal_[static_cast<std::size_t>(k)] = A.value[static_cast<std::size_t>(system_.pattern().diagonal_index(k))];
    }
    gradient_max_norm_ = system_.gradient().size() > 0 ? system_.gradient().cwiseAbs().maxCoeff() : 0.0;
  }

  PoseGraphProblem<Group>& problem_;
  const OptimizerOptions& options_;
  PoseGraphSystem<Group, Factor>& system_;
  SparseCholesky& cholesky_;
  OptimizerSummary& summary_;
  bool reuse_ = false;
  int cg_budget_ = 0;
  bool force_factorization_ = false;         // after a rejected inexact step
  double last_step_ = 0.0;                   // norm of the last accepted step
  double largest_step_ = 0.0;                // largest accepted step norm so far
  double gradient_max_norm_ = 0.0;           // at the current poses
  double previous_gradient_max_norm_ = 1.0;  // at the accepted point before the current one
  std::vector<double> diagonal_;             // undamped diag(J^T J)
  Eigen::VectorXd damping_;
  std::vector<Group> candidate_;
};

template <class Group, class Factor>
OptimizerSummary run(PoseGraphProblem<Group>& problem, const OptimizerOptions& options, OptimizerWorkspace* workspace) {
  const auto start = Clock::now();
  OptimizerSummary summary;
  std::string invalid;
  CAIRN_ASSERT(options.is_valid(&invalid), invalid.c_str());
  CAIRN_ASSERT(options.edge_weights.empty() || options.edge_weights.size() == problem.edges.size(),
               "edge_weights must be empty or hold one weight per edge");
  OptimizerWorkspace::State local_state;
  OptimizerWorkspace::State* state = &local_state;
  if (workspace != nullptr) {
    CAIRN_ASSERT(workspace->max_inactive_fraction >= 0.0 && workspace->max_inactive_fraction <= 1.0,
                 "OptimizerWorkspace::max_inactive_fraction must be in [0, 1]");
    if (!workspace->state) workspace->state = std::make_unique<OptimizerWorkspace::State>();
    state = workspace->state.get();
  }
  const auto analyze_start = Clock::now();
  if (prepare_pattern(problem, options, workspace != nullptr ? workspace->max_inactive_fraction : 0.0, *state)) {
    summary.analyze_s = seconds_since(analyze_start);
    if (workspace != nullptr) ++workspace->analyses;
  }
  SparseCholesky& cholesky = *state->cholesky;
  PoseGraphSystem<Group, Factor> system(problem, options, state->variable, state->in_pattern, *state->pattern);
  summary.free_poses = system.free_poses();
  summary.edges = static_cast<int>(problem.edges.size());
  if (system.free_poses() == 0) {
    summary.initial_cost = summary.final_cost = system.evaluate(problem.T_world_pose);
    summary.termination = TerminationType::kConvergence;
    summary.message = "no free poses";
    summary.total_s = seconds_since(start);
    return summary;
  }

  PoseGraphModel<Group, Factor> model(problem, options, system, cholesky, summary);
  static_cast<TrustRegionResult&>(summary) = minimize(model, options);
  summary.factor_nonzeros = cholesky.factor_nonzeros();
  for (const auto& it : summary.iteration_log) {
    summary.linearize_s += it.linearize_s;
    summary.factorize_s += it.factorize_s;
    summary.solve_s += it.solve_s;
  }
  summary.total_s = seconds_since(start);
  return summary;
}

}  // namespace

template <class Group>
OptimizerSummary optimize(PoseGraphProblem<Group>& problem, const OptimizerOptions& options,
                          OptimizerWorkspace* workspace) {
  // An explicit thread count holds for CHOLMOD's BLAS too (0 leaves the BLAS as it is).
  const ScopedBlasThreads blas(options.threads);
  return with_factor<Group>(options.objective,
                            [&](auto factor) { return run<Group, decltype(factor)>(problem, options, workspace); });
}

template <class Group>
OptimizerSummary optimize(PoseGraphProblem<Group>& problem, const OptimizerOptions& options) {
  return optimize(problem, options, nullptr);
}

namespace {

// One edge's term of evaluate_cost: its weight times the kernel of its squared residual.
template <class Group>
double edge_cost(const PoseGraphProblem<Group>& problem, const OptimizerOptions& options, std::size_t e) {
  const auto& edge = problem.edges[e];
  const double s = squared_residual(problem.T_world_pose[static_cast<std::size_t>(edge.i)],
                                    problem.T_world_pose[static_cast<std::size_t>(edge.j)], edge, options.objective);
  return edge_weight(options, e) * evaluate_kernel(options.kernel, options.kernel_scale, s).rho;
}

}  // namespace

template <class Group>
double evaluate_cost(const PoseGraphProblem<Group>& problem, const OptimizerOptions& options) {
  double sum = 0.0;
  for (std::size_t e = 0; e < problem.edges.size(); ++e) sum += edge_cost(problem, options, e);
  return sum;
}

template <class Group>
long long first_nonfinite_edge(const PoseGraphProblem<Group>& problem, const OptimizerOptions& options) {
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    if (!std::isfinite(edge_cost(problem, options, e))) return static_cast<long long>(e);
  }
  return -1;
}

template OptimizerSummary optimize(Problem2D&, const OptimizerOptions&);
template OptimizerSummary optimize(Problem3D&, const OptimizerOptions&);
template OptimizerSummary optimize(Problem2D&, const OptimizerOptions&, OptimizerWorkspace*);
template OptimizerSummary optimize(Problem3D&, const OptimizerOptions&, OptimizerWorkspace*);
template double evaluate_cost(const Problem2D&, const OptimizerOptions&);
template double evaluate_cost(const Problem3D&, const OptimizerOptions&);
template long long first_nonfinite_edge(const Problem2D&, const OptimizerOptions&);
template long long first_nonfinite_edge(const Problem3D&, const OptimizerOptions&);

}  // namespace cairn::backend
