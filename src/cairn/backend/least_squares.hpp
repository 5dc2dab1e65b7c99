#pragma once
/// \file
/// cairn's general sparse nonlinear least-squares engine: variables of several manifolds,
/// factors with analytic Jacobians, robust kernels, constant variables, and Levenberg-Marquardt
/// on the normal equations with an optional Schur elimination of one variable group (points in
/// bundle adjustment, landmarks in SLAM). The shape is Ceres' Problem / Solver
/// (include/ceres/problem.h, solver.h) and GTSAM's NonlinearFactorGraph / Values:
///
///     LeastSquaresProblem problem;
///     const int camera = problem.add_variable(camera_parameters, euclidean_manifold(9));
///     const int point = problem.add_variable(point_xyz, euclidean_manifold(3), VariableGroup::kEliminate);
///     problem.add_factor(std::make_unique<BalReprojectionFactor>(u, v), {camera, point});
///     const LeastSquaresSummary summary = solve(problem, LeastSquaresOptions{});
///
/// Cost = 1/2 sum_f rho_f(||r_f||^2) (Ceres' convention; the pose-graph optimiser's cost has no
/// 1/2, see optimizer.hpp). Variables live in memory the caller owns (like Ceres' parameter
/// blocks) and are updated in place by x <- x [+] delta, delta in the tangent space of the
/// variable's manifold; factors give their Jacobians directly with respect to that delta.
///
/// Linear solvers (LeastSquaresOptions::linear_solver):
///  * kSparseNormalCholesky: J^T J over every free variable, CHOLMOD (block-AMD ordering).
///  * kSparseSchur: the variables of group kEliminate are eliminated first (Triggs et al. 2000,
///    "Bundle adjustment -- a modern synthesis", Sec. 6.1; Ceres' SPARSE_SCHUR): with H ordered
///    [reduced; eliminated] = [[A, W], [W^T, V]], V block-diagonal, the reduced system
///    S dx_r = -(g_r - W V^-1 g_e), S = A - W V^-1 W^T, is factorised by CHOLMOD and
///    dx_e = -V^-1 (g_e + W^T dx_r) follows block by block. Every factor may touch at most one
///    eliminated variable (Ceres' rule for its Schur solvers).
///  * kIterativeSchur: the same reduced system solved by conjugate gradients without forming S
///    (S x = A x - W (V^-1 (W^T x)), evaluated factor by factor), preconditioned by the block
///    diagonal of S (Ceres' ITERATIVE_SCHUR with SCHUR_JACOBI; Agarwal et al., "Bundle
///    adjustment in the large", ECCV 2010, Sec. 4). For large problems whose S would be dense.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/backend/robust_kernel.hpp"
#include "cairn/backend/trust_region.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"

namespace cairn::backend {

/// A smooth manifold for a variable: its stored (ambient) size, its tangent size, and the
/// retraction x [+] delta. Stateless; one instance per kind is shared by all variables.
class Manifold {
 public:
  virtual ~Manifold() = default;
  virtual int ambient_size() const = 0;
  virtual int tangent_size() const = 0;
  /// x_plus = x [+] delta (x and x_plus may alias).
  virtual void plus(const double* x, const double* delta, double* x_plus) const = 0;
  virtual std::string_view name() const = 0;
};

/// R^n with x [+] delta = x + delta (points, BAL cameras as Ceres' bundle_adjuster parameterises
/// them: angle-axis, translation, f, k1, k2 all additive; small intrinsics vectors).
const Manifold& euclidean_manifold(int n);
/// SE(3) stored as (qx, qy, qz, qw, tx, ty, tz), T_world_body, delta = (rho, phi) translation
/// first, T <- T exp(delta) (core/se3.hpp, docs/conventions.md).
const Manifold& se3_manifold();
/// SE(2) stored as (x, y, theta), delta = (rho_x, rho_y, phi), T <- T exp(delta).
const Manifold& se2_manifold();

/// A pose and the storage of se3_manifold() / se2_manifold(), both ways.
core::SE3 se3_from_values(const double* x);
void se3_to_values(const core::SE3& T, double* x);
core::SE2 se2_from_values(const double* x);
void se2_to_values(const core::SE2& T, double* x);

/// Which linear-solver group a variable belongs to.
enum class VariableGroup {
  kReduced,    ///< stays in the reduced (camera / pose) system
  kEliminate,  ///< eliminated first by the Schur solvers (points, landmarks)
};

/// A residual block: r = f(x_1, ..., x_k) of fixed size with analytic Jacobians (Ceres'
/// SizedCostFunction with the Jacobians already in the tangent spaces, as GTSAM's factors).
class Factor {
 public:
  virtual ~Factor() = default;
  virtual int residual_size() const = 0;
  /// Evaluates the residual (residual_size() values) at values[k] (each variable's ambient
  /// storage) and, when `jacobians` is not null, each non-null jacobians[k] as a row-major
  /// residual_size() x tangent_size(k) matrix (d r / d delta_k). Returns false when the
  /// residual is not defined at these values (the step is then rejected, as Ceres does).
  virtual bool evaluate(const double* const* values, double* residual, double* const* jacobians) const = 0;
};

/// The robust kernel of one factor (robust_kernel.hpp), scale in the residual's units.
struct FactorLoss {
  RobustKernel kernel = RobustKernel::kNone;
  double scale = 1.0;
};

class LeastSquaresProblem {
 public:
  LeastSquaresProblem();
  ~LeastSquaresProblem();
  LeastSquaresProblem(LeastSquaresProblem&&) noexcept;
  LeastSquaresProblem& operator=(LeastSquaresProblem&&) noexcept;

  /// Adds a variable stored at `values` (manifold.ambient_size() doubles, owned by the caller,
  /// alive and not moved while the problem is). Returns its index.
  int add_variable(double* values, const Manifold& manifold, VariableGroup group = VariableGroup::kReduced);
  /// Holds a variable constant (its factors still count; no step is taken on it).
  void set_constant(int variable, bool constant = true);
  bool is_constant(int variable) const;
  /// Adds a factor on `variables` (in the order the factor's evaluate() expects them).
  int add_factor(std::unique_ptr<Factor> factor, std::vector<int> variables, FactorLoss loss = {});

  int num_variables() const;
  int num_factors() const;
  int num_residuals() const;
  const Manifold& manifold(int variable) const;
  VariableGroup group(int variable) const;
  double* values(int variable) const;
  const Factor& factor(int index) const;
  const std::vector<int>& factor_variables(int index) const;
  const FactorLoss& factor_loss(int index) const;

  struct Impl;
  Impl& impl() { return *impl_; }
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

enum class LinearSolverType { kSparseNormalCholesky, kSparseSchur, kIterativeSchur };
std::string_view to_string(LinearSolverType type);

/// The minimiser's options (trust_region.hpp: algorithm, Ceres' tolerances and defaults --
/// 50 iterations, function 1e-6, gradient 1e-10, parameter 1e-8, radius 1e4 up to 1e16 --,
/// progress, should_stop) and the engine's. The gradient tolerance is Ceres' max_i
/// |x_i - (x [+] -g)_i| (for the Euclidean variables of BA, max |g_i|; solver.h); LM solves
/// (J^T J + D / mu) dx = -J^T r, mu the trust-region radius, D the diagonal of J^T J clamped to
/// [min_diagonal, max_diagonal] (Ceres' LevenbergMarquardtStrategy).
struct LeastSquaresOptions : TrustRegionOptions {
  LinearSolverType linear_solver = LinearSolverType::kSparseSchur;
  /// The clamp of D above. 0 < min_diagonal <= max_diagonal.
  double min_diagonal = 1e-6;
  double max_diagonal = 1e32;
  /// kIterativeSchur: conjugate gradients stop when i (Q_i - Q_{i-1}) / Q_i < cg_tolerance, Q
  /// the quadratic model (Nash & Sofer 1990; Ceres' rule with q_tolerance = eta, default 0.1),
  /// after at least min_cg_iterations and at most max_cg_iterations. cg_tolerance in (0, 1).
  double cg_tolerance = 0.1;
  int max_cg_iterations = 500;
  int min_cg_iterations = 1;
  /// kSparseSchur and kSparseNormalCholesky: solve the system by PCG preconditioned with the
  /// previous iteration's factorisation, and factorise only when that does not reach
  /// ||S x - b|| <= reuse_cg_tolerance ||b|| within reuse_max_cg_iterations (the pose-graph
  /// optimiser's reuse_factorization). Tried only when a factorisation costs at least 50 PCG
  /// iterations' flops (CHOLMOD's count), i.e. on large dense-ish reduced systems
  /// (problem-318-41628: 2,862 unknowns, factor 3.7 M non-zeros); on small ones every step is the
  /// exact LM step, as Ceres'. The steps become inexact Newton
  /// steps (Dembo, Eisenstat & Steihaug 1982), which LM's ratio test keeps safe.
  bool reuse_factorization = true;
  double reuse_cg_tolerance = 0.01;
  int reuse_max_cg_iterations = 6;
  /// Evaluate the Jacobians together with the cost of each trial point (into a second buffer,
  /// swapped in when the step is accepted) instead of evaluating the residuals again with
  /// Jacobians after acceptance, as Ceres does. One evaluation per accepted step instead of two,
  /// at the price of Jacobians computed for rejected steps and a second Jacobian buffer in memory.
  /// The iterates are the same either way.
  bool jacobians_with_trial_cost = true;
  /// Threads for evaluation and the Schur complement, and for CHOLMOD's BLAS during the solve
  /// (restored afterwards, set_blas_threads); 0 = all cores.
  int threads = 0;
  bool is_valid(std::string* error) const;
};

/// One iteration (the shared minimiser's record, trust_region.hpp).
using LeastSquaresIteration = TrustRegionIteration;
using LeastSquaresTermination = TerminationType;

/// The minimiser's result (termination, message, costs, iterations, the log) and the engine's
/// sizes, counts and per-phase times.
struct LeastSquaresSummary : TrustRegionResult {
  Algorithm algorithm = Algorithm::kLevenbergMarquardt;
  LinearSolverType linear_solver = LinearSolverType::kSparseSchur;
  int cg_iterations = 0;  ///< total, kIterativeSchur and factorisation reuse
  int factorizations = 0;  ///< numeric factorisations (kSparseSchur, kSparseNormalCholesky)
  int reused_factorizations = 0;  ///< steps solved by PCG on an earlier factorisation
  int threads = 1;
  int variables = 0;
  int eliminated_variables = 0;
  int factors = 0;
  int residuals = 0;
  int reduced_size = 0;  ///< scalar unknowns of the system CHOLMOD or CG solves
  std::size_t factor_nonzeros = 0;
  /// Per phase, seconds (as Ceres' Summary): residual evaluation with Jacobians, trial-point
  /// costs, forming the (reduced) normal equations, factorisation / CG, back-substitution.
  double jacobian_s = 0.0;
  double residual_s = 0.0;
  double linear_system_s = 0.0;
  double linear_solve_s = 0.0;
  double analyze_s = 0.0;
  double total_s = 0.0;

  bool is_solution_usable() const { return termination != LeastSquaresTermination::kFailure; }
  std::string brief_report() const;
};

/// Minimises 1/2 sum rho(||r||^2) over the free variables, updating them in place.
LeastSquaresSummary solve(LeastSquaresProblem& problem, const LeastSquaresOptions& options);

/// Marginal covariances of a least-squares problem at its current values (Laplace approximation).
/// Named apart from the pose graph's MarginalCovariances<Group> (covariance.hpp): both headers
/// once declared `backend::MarginalCovariances`, and a program including both did not compile.
struct VariableCovariances {
  bool ok = false;
  std::string message;  ///< why not, when !ok
  /// Per requested variable, in its tangent space (tangent_size x tangent_size); zero for a
  /// constant variable.
  std::vector<Eigen::MatrixXd> blocks;
};

/// The diagonal blocks of (J^T J)^-1 for `variables` at the current values, J whitened and
/// robust-reweighted as in the solve (Ceres' Covariance with its default algorithm does the same:
/// the inverse of the Gauss-Newton Hessian). J^T J over every free variable, factorised by
/// CHOLMOD; the columns are solved for the requested blocks only. Not ok when J^T J is singular
/// (a gauge freedom: hold a variable constant).
VariableCovariances marginal_covariances(LeastSquaresProblem& problem, const std::vector<int>& variables,
                                         int threads = 1);

/// S with S^T S = information, S = Lambda^1/2 V^T from information = V Lambda V^T (eigenvalues
/// below zero, rounding on a semi-definite matrix, count as zero): whitens a residual e into
/// S e, so that 1/2 ||S e||^2 = 1/2 e^T information e. For factors built from a covariance.
template <int N>
Eigen::Matrix<double, N, N> square_root_information(const Eigen::Matrix<double, N, N>& information) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(information);
  const Eigen::Matrix<double, N, 1> root = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return root.asDiagonal() * eigen.eigenvectors().transpose();
}

/// Cost 1/2 sum rho(||r||^2) at the current values; NaN when a factor cannot be evaluated.
double evaluate_cost(const LeastSquaresProblem& problem);

/// Whether the Schur solvers' kernels for two-residual factors (bundle adjustment) run with AVX:
/// true on a CPU with AVX unless the environment variable CAIRN_NO_AVX is set when the process
/// starts, which selects the scalar kernels (the same arithmetic, for testing them on any CPU).
bool schur_kernels_use_avx();

}  // namespace cairn::backend
