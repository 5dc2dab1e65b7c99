#pragma once
/// \file
/// Sparse nonlinear least squares over a pose graph: Levenberg-Marquardt (default), Gauss-Newton
/// or Powell's dog-leg -- the iterations of cairn's one trust-region minimiser (trust_region.hpp)
/// -- on the normal equations assembled block by block (in parallel) and solved by CHOLMOD
/// (symbolic analysis once, numeric factorisation per iteration, or PCG on an earlier one).
/// Cost = sum over edges of rho(||r||^2), with r the whitened residual of the chosen objective
/// (no factor 1/2: with the geodesic objective this is g2o's chi2, with the chordal one
/// SE-Sync's f). Termination follows Ceres' Solver::Options (solver.h): function, gradient and
/// parameter tolerances, each with its formula below.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cairn/backend/factors.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/backend/robust_kernel.hpp"
#include "cairn/backend/trust_region.hpp"

namespace cairn::backend {

std::string_view to_string(Objective objective);

/// One iteration of the optimiser (the shared minimiser's record, trust_region.hpp).
using IterationSummary = TrustRegionIteration;

/// The minimiser's options (trust_region.hpp: algorithm, tolerances, radius, progress,
/// should_stop), with the pose graph's defaults and its own options. ||x|| of the parameter
/// tolerance is the norm of all translations; the gradient norm is max_i |(J^T r)_i|.
struct OptimizerOptions : TrustRegionOptions {
  /// Defaults that differ from the minimiser's (Ceres'):
  ///  * max_iterations 100, function_tolerance 1e-12, parameter_tolerance 1e-10: pose graphs are
  ///    solved to the optimum, not to Ceres' 1e-6 (the SE-Sync optima, docs/backend.md);
  ///  * initial_trust_region_radius 1e16: the first step is Gauss-Newton's (lambda = 1e-16), and
  ///    damping appears only after a rejected step, which raises lambda to at least
  ///    min_damping_after_rejection = 1e-4 (Ceres' initial damping, radius 1e4). Measured on the
  ///    SE-Sync graphs from a chordal start (docs/benchmarks.md), Ceres' radius 1e4 needs 5-16
  ///    iterations on 11 of 14 graphs where the undamped start needs 2-5: the damping holds back
  ///    the steps along the graphs' flat directions iteration after iteration. Dog-leg: the
  ///    initial radius;
  ///  * max_trust_region_radius infinite (lambda may fall below 1e-16) and no cap on failed
  ///    factorisations in a row (max_consecutive_invalid_steps): each raises lambda and the solve
  ///    goes on, as before the minimiser was shared.
  OptimizerOptions();

  Objective objective = Objective::kGeodesic;
  RobustKernel kernel = RobustKernel::kNone;
  /// Kernel scale c in whitened units (standard deviations); > 0.
  double kernel_scale = 1.0;
  /// LM only: once a factorisation exists, solve the next damped systems (H + lambda D) x = -g
  /// by conjugate gradients preconditioned with it (an inexact LM step, Wright & Holt 1985;
  /// Nocedal & Wright alg. 5.3) and factorise again only when PCG does not converge within
  /// `reuse_max_cg_iterations`. Near a minimum H changes little between iterations, so a few
  /// triangular solves replace a numeric factorisation, most of an iteration's time on large
  /// graphs. Only steps that reach the forcing term below are taken, so every step is the
  /// damped Gauss-Newton step to at most 1 %. Off: a factorisation every iteration (as Ceres).
  bool reuse_factorization = true;
  /// Largest forcing term of an inexact Newton step (Dembo, Eisenstat & Steihaug 1982): a PCG
  /// step is taken when ||(H + lambda D) x + g|| / ||g|| <= forcing, forcing = the max-norm
  /// gradient's reduction over the last accepted step clamped to [1e-8, reuse_cg_tolerance]
  /// (Eisenstat & Walker 1996, choice 1 in spirit). A rejected PCG step is retried from a fresh
  /// factorisation with the same damping. 0.01 measured best on the SE-Sync graphs (0.1 let
  /// loose steps be rejected on MIT and cost cubicle a factorisation; a forcing relative to the
  /// first iteration's gradient made PCG miss its budget near the minimum). In (0, 1).
  double reuse_cg_tolerance = 0.01;
  /// PCG iterations before giving up and factorising. One PCG iteration (two triangular solves
  /// with the factor, memory-bound, and a product with H) took 1/6 to 1/17 of a numeric
  /// factorisation's time on every SE-Sync graph (2026-11-24, docs/backend.md), so with 6 a
  /// failed attempt costs at most about one factorisation; successful ones took 1-7 iterations.
  /// 0 = derived from CHOLMOD's flop counts (a quarter of a factorisation's flops spent in
  /// triangular solves and products with H, 8 to 30 iterations): that count puts the ratio at
  /// 1.2-93, so on the large 3D graphs failed attempts ran 11-17 iterations, more than the
  /// factorisation they were to save; GNC uses it for its weighted solves, whose factors the
  /// outliers fill in (GncOptions::reuse_max_cg_iterations). A count, not a time, keeps runs
  /// repeatable. PCG also gives up early when its residual reduction so far projects past the
  /// budget. >= 0.
  int reuse_max_cg_iterations = 6;
  /// PCG is tried only once the last accepted step is at most this fraction of the largest
  /// accepted step of the solve: after a large step H has moved too far from the factorised
  /// one for it to precondition well. Measured from chordal starts on the 14 SE-Sync graphs
  /// (2026-11-24): the attempt right after the first step failed on 10 of them, costing a
  /// budget of PCG iterations on top of the factorisation (cubicle 22 ms, torus3D 22 ms); with
  /// 0.25 those attempts are skipped, while the later ones (steps 4-1000x smaller than the
  /// first) mostly converge in 1-5 iterations (0.1 also skipped a converging attempt on
  /// sphere_bignoise, whose second step is 0.16 of its first). 1 = try whenever a
  /// factorisation exists. In (0, 1].
  double reuse_step_fraction = 0.25;
  /// Threads for linearisation; 0 = all cores.
  int threads = 0;
  /// Chordal objective: the exact Hessian J^T J + S of the pulled-back cost
  /// (ChordalFactor::second_order) instead of Gauss-Newton's J^T J. Gauss-Newton converges only
  /// linearly on this objective, whose residuals do not vanish at the optimum (torus3D and the
  /// big-noise sphere stopped at 100 iterations); with the exact Hessian LM's steps are Newton
  /// steps near the optimum. S may be indefinite away from it, where the exact Hessian can stall
  /// LM: it is switched on once an accepted Gauss-Newton step lowers the cost by less than 0.1 %
  /// (optimizer.cpp, kSecondOrderSwitch). Levenberg-Marquardt only (Gauss-Newton and dog-leg need
  /// a positive semidefinite model); ignored for the geodesic objective. Measured on the 14 SE-Sync graphs
  /// (docs/backend.md): fewer iterations on every one (torus3D 100 -> 4, the big-noise sphere
  /// 100 -> 9, both now converged), never slower.
  bool exact_chordal_hessian = true;
  /// Optional per-edge weights multiplying rho (GNC's weights); empty = all 1.
  std::vector<double> edge_weights;
  /// Edges with 0 < weight < coupling_weight_floor enter the cost and the gradient exactly but
  /// not the Hessian: they stay out of the sparsity pattern, where edges between distant poses
  /// (GNC's not yet rejected false loop closures) would fill the factor in for a change of H of
  /// that weight's order. The weighted problem and its stationary points are unchanged; the
  /// steps become approximate Newton steps, which LM's ratio test keeps safe (test
  /// Optimizer.WeakEdgesKeptOutOfTheFactorLeaveTheMinimumWhereItIs). 0 = every weighted edge
  /// couples. GNC sets it during its graduation (GncOptions::negligible_weight). >= 0.
  double coupling_weight_floor = 0.0;

  /// False with every problem described in `error`, like Ceres' Solver::Options::IsValid.
  bool is_valid(std::string* error) const;
};

/// The minimiser's result (termination, message, costs, iterations, final_lambda, the log) and
/// the pose graph's sizes and times.
struct OptimizerSummary : TrustRegionResult {
  /// Numeric factorisations (the other steps came from PCG on an earlier factorisation).
  int factorizations = 0;
  int free_poses = 0;
  int edges = 0;
  std::size_t factor_nonzeros = 0;
  double linearize_s = 0.0;
  double factorize_s = 0.0;
  double solve_s = 0.0;
  double analyze_s = 0.0;
  double total_s = 0.0;

  bool is_solution_usable() const { return termination != TerminationType::kFailure; }
  /// One line: "LM: cost 1.2e+05 -> 52.348 in 12 iterations (0.031 s): converged (...)".
  std::string brief_report() const;
};

/// What a sequence of solves of one graph whose edge weights change (GNC's outer loop) can
/// share: the sparsity pattern with its symbolic analysis (fill-reducing ordering, CHOLMOD's
/// supernodes) and the last numeric factorisation, which preconditions the next solve's first
/// steps (PCG, as OptimizerOptions::reuse_factorization) instead of a factorisation of its own.
/// Edges whose weight is 0 are dropped from the pattern when the next solve re-analyses it,
/// which happens when more than `max_inactive_fraction` of the pattern's edges are inactive
/// (GNC's rejected false loop closures would otherwise keep their fill-in). Opaque; one per
/// graph; not thread-safe.
class OptimizerWorkspace {
 public:
  OptimizerWorkspace();
  ~OptimizerWorkspace();
  OptimizerWorkspace(const OptimizerWorkspace&) = delete;
  OptimizerWorkspace& operator=(const OptimizerWorkspace&) = delete;

  /// Share of the pattern's edges with weight 0 above which the next solve re-analyses. [0, 1].
  double max_inactive_fraction = 0.02;
  /// Symbolic analyses done so far (for tests and reports).
  int analyses = 0;

  /// Implementation state (defined in optimizer.cpp).
  struct State;
  std::unique_ptr<State> state;
};

/// Optimises problem.T_world_pose in place (fixed poses untouched).
template <class Group>
OptimizerSummary optimize(PoseGraphProblem<Group>& problem, const OptimizerOptions& options);

/// As above; `workspace` (may be null) carries the analysis and the last factorisation from the
/// previous solve of the same graph (same edges, same fixed poses; checked) into this one.
template <class Group>
OptimizerSummary optimize(PoseGraphProblem<Group>& problem, const OptimizerOptions& options,
                          OptimizerWorkspace* workspace);

/// Cost of the current poses under `options` (objective, kernel, edge weights).
template <class Group>
double evaluate_cost(const PoseGraphProblem<Group>& problem, const OptimizerOptions& options);

/// The index of the first edge whose cost under `options` is not finite at the current poses
/// (a pose or measurement so large that the residual overflows), or -1: names the culprit of a
/// non-finite evaluate_cost().
template <class Group>
long long first_nonfinite_edge(const PoseGraphProblem<Group>& problem, const OptimizerOptions& options);

}  // namespace cairn::backend
