#pragma once
/// \file
/// Sparse nonlinear least squares over a pose graph: Levenberg-Marquardt (default), Gauss-Newton
/// or Powell's dog-leg, on the normal equations assembled block by block (in parallel) and
/// solved by CHOLMOD (symbolic analysis once, numeric factorisation per iteration).
/// Cost = sum over edges of rho(||r||^2), with r the whitened residual of the chosen objective
/// (no factor 1/2: with the geodesic objective this is g2o's chi2, with the chordal one
/// SE-Sync's f). Termination follows Ceres' Solver::Options (solver.h): function, gradient and
/// parameter tolerances, each with its formula below.

#include <functional>
#include <string>
#include <vector>

#include "cairn/backend/problem.hpp"
#include "cairn/backend/robust_kernel.hpp"

namespace cairn::backend {

enum class Algorithm { kLevenbergMarquardt, kGaussNewton, kDogleg };
enum class Objective {
  kGeodesic,  ///< r = S log(Z^-1 T_i^-1 T_j): the maximum-likelihood cost g2o, GTSAM, Ceres use
  kChordal,   ///< SE-Sync's f with isotropic weights kappa, tau (published certified optima)
};
std::string_view to_string(Algorithm algorithm);
std::string_view to_string(Objective objective);

struct IterationSummary {
  int iteration = 0;
  double cost = 0.0;               ///< after the step if accepted, else unchanged
  double cost_change = 0.0;        ///< old cost - new cost (the actual decrease tried)
  double gradient_max_norm = 0.0;  ///< max |J^T r| at the start of the iteration
  double step_norm = 0.0;
  double relative_decrease = 0.0;  ///< actual / predicted decrease (rho)
  double lambda = 0.0;             ///< LM damping (1/trust radius) or dog-leg radius
  bool step_accepted = false;
  bool reused_factorization = false;  ///< the step came from the previous factorisation
  double linearize_s = 0.0;
  double factorize_s = 0.0;
  double solve_s = 0.0;
  double iteration_s = 0.0;
};

struct OptimizerOptions {
  Algorithm algorithm = Algorithm::kLevenbergMarquardt;
  Objective objective = Objective::kGeodesic;
  RobustKernel kernel = RobustKernel::kNone;
  /// Kernel scale c in whitened units (standard deviations); > 0.
  double kernel_scale = 1.0;
  /// Iterations, accepted or not. >= 1.
  int max_iterations = 100;
  /// Stop when |old cost - new cost| / old cost < function_tolerance. >= 0.
  double function_tolerance = 1e-12;
  /// Stop when max_i |(J^T r)_i| < gradient_tolerance. >= 0.
  double gradient_tolerance = 1e-10;
  /// Stop when ||step|| < parameter_tolerance * (||x|| + parameter_tolerance), ||x|| the norm of
  /// all translations. >= 0.
  double parameter_tolerance = 1e-10;
  /// LM: initial damping lambda = 1 / radius, on Marquardt's scaling diag(J^T J) clamped to
  /// [1e-6, 1e32] (Ceres' defaults). Dog-leg: initial trust-region radius. > 0.
  double initial_trust_region_radius = 1e4;
  /// LM only: after a step whose actual decrease matched the model well (rho > 0.75), try the
  /// next step with the previous factorisation (a solve instead of a factorisation, which is
  /// most of an iteration's time on large graphs); the step is kept only if rho > 0.5 under the
  /// current linearisation, otherwise the iteration factorises as usual.
  bool reuse_factorization = false;
  /// Threads for linearisation; 0 = all cores.
  int threads = 0;
  /// Called after every iteration (the CLI prints progress); may be empty.
  std::function<void(const IterationSummary&)> progress;
  /// Optional per-edge weights multiplying rho (GNC's weights); empty = all 1.
  std::vector<double> edge_weights;

  /// False with every problem described in `error`, like Ceres' Solver::Options::IsValid.
  bool is_valid(std::string* error) const;
};

enum class TerminationType {
  kConvergence,    ///< a tolerance was met
  kNoConvergence,  ///< max_iterations reached; the result is usable but may not be optimal
  kFailure,        ///< numerical failure (e.g. Gauss-Newton on an indefinite system)
};
std::string_view to_string(TerminationType termination);

struct OptimizerSummary {
  TerminationType termination = TerminationType::kFailure;
  std::string message;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  int successful_iterations = 0;
  std::vector<IterationSummary> iteration_log;
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

/// Optimises problem.T_world_pose in place (fixed poses untouched).
template <class Group>
OptimizerSummary optimize(PoseGraphProblem<Group>& problem, const OptimizerOptions& options);

/// Cost of the current poses under `options` (objective, kernel, edge weights).
template <class Group>
double evaluate_cost(const PoseGraphProblem<Group>& problem, const OptimizerOptions& options);

}  // namespace cairn::backend
