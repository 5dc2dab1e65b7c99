#pragma once
/// \file
/// The one trust-region minimiser of cairn: Levenberg-Marquardt, Gauss-Newton and Powell's
/// dog-leg as a single loop, shared by every nonlinear least-squares solver in the tree (the
/// pose-graph optimiser, optimizer.hpp, and the general engine, least_squares.hpp). The shape is
/// Ceres' TrustRegionMinimizer (internal/ceres/trust_region_minimizer.cc) with its
/// TrustRegionStrategy: the loop owns the damping / radius, the acceptance test and the
/// termination rules; a TrustRegionModel owns the variables, the evaluation and the linear
/// algebra (the pose graph's block-sparse J^T J with factorisation reuse, the engine's Schur
/// complement or iterative Schur), so each problem keeps the data layout it is fast with.
///
/// Per iteration, with the model m(step) of the cost around the current point:
///  * LM (Levenberg 1944, Marquardt 1963): (H + lambda D) step = -g, D the model's scaling
///    (diag(J^T J) clamped, Ceres' LevenbergMarquardtStrategy); after an accepted step lambda is
///    multiplied by max(1/3, 1 - (2 rho - 1)^3) (Nielsen 1999; Madsen, Nielsen & Tingleff 2004,
///    eq. 3.16), after a rejected one by nu, nu doubling (Ceres' decrease_factor).
///  * Gauss-Newton: lambda = 0; a step that raises the cost ends the solve.
///  * Dog-leg (Powell 1970; Nocedal & Wright, Numerical Optimization, 2nd ed., sec. 4.1): the
///    Gauss-Newton step inside the radius, else the Cauchy point on the boundary, else the
///    dog-leg path's crossing of the boundary.
/// A step is accepted when rho = (actual decrease) / (model decrease) > 1e-3 (Ceres'
/// min_relative_decrease). Termination as Ceres' Solver::Options: function tolerance
/// |cost change| <= tol * cost (tested on every trial point, taken or not: Ceres'
/// FunctionToleranceReached), gradient tolerance on the model's max-norm gradient, parameter
/// tolerance ||step|| <= tol (||x|| + tol), an iteration cap, and consecutive invalid steps.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace cairn::backend {

enum class Algorithm { kLevenbergMarquardt, kGaussNewton, kDogleg };
std::string_view to_string(Algorithm algorithm);

enum class TerminationType {
  kConvergence,    ///< a tolerance was met
  kNoConvergence,  ///< max_iterations reached; the result is usable but may not be optimal
  kFailure,        ///< numerical failure (e.g. Gauss-Newton on an indefinite system)
  kInterrupted,    ///< should_stop said stop; usable, at the last accepted point
};
std::string_view to_string(TerminationType termination);

/// One iteration of the minimiser, as logged and handed to progress callbacks.
struct TrustRegionIteration {
  int iteration = 0;
  double cost = 0.0;               ///< after the step if it was taken, else unchanged
  double cost_change = 0.0;        ///< old cost - trial cost (the actual decrease tried)
  double gradient_max_norm = 0.0;  ///< the model's max-norm gradient at the start of the iteration
  double step_norm = 0.0;
  double relative_decrease = 0.0;  ///< actual / predicted decrease (rho); -1 when undefined
  /// LM: the damping lambda; dog-leg: the radius; Gauss-Newton: 0.
  double lambda = 0.0;
  /// LM: 1 / lambda (Ceres' mu); dog-leg: the radius; Gauss-Newton: infinity.
  double trust_region_radius = 0.0;
  bool step_accepted = false;
  bool reused_factorization = false;  ///< the step came from PCG on an earlier factorisation
  int cg_iterations = 0;              ///< conjugate-gradient iterations of this step
  /// Seconds, filled by the model where it measures them: residuals and Jacobians with their
  /// assembly, the numeric factorisation, the solves; and the whole iteration.
  double linearize_s = 0.0;
  double factorize_s = 0.0;
  double solve_s = 0.0;
  double iteration_s = 0.0;
};

struct TrustRegionOptions {
  Algorithm algorithm = Algorithm::kLevenbergMarquardt;
  /// Iterations, accepted or not (Ceres' max_num_iterations). >= 1.
  int max_iterations = 50;
  /// Stop when |old cost - trial cost| <= function_tolerance * old cost. >= 0.
  double function_tolerance = 1e-6;
  /// Stop when the model's max-norm gradient is <= gradient_tolerance. >= 0.
  double gradient_tolerance = 1e-10;
  /// Stop when ||step|| <= parameter_tolerance * (||x|| + parameter_tolerance), ||x|| as the
  /// model measures it. >= 0.
  double parameter_tolerance = 1e-8;
  /// LM: lambda starts at 1 / initial_trust_region_radius (Ceres' mu). Dog-leg: the initial
  /// radius. > 0.
  double initial_trust_region_radius = 1e4;
  /// LM: lambda never drops below 1 / max_trust_region_radius (Ceres' 1e16). Infinity: no
  /// floor. >= initial_trust_region_radius.
  double max_trust_region_radius = 1e16;
  /// LM: a rejected or invalid step raises lambda to at least this (0: no floor). The pose-graph
  /// optimiser starts undamped (lambda 1e-16) and uses Ceres' initial damping 1e-4 here, so one
  /// overshoot is damped at once instead of after a dozen doublings (optimizer.hpp).
  double min_damping_after_rejection = 0.0;
  /// The solve fails after this many steps in a row the model could not compute (Ceres'
  /// max_num_consecutive_invalid_steps, 5). LM only: Gauss-Newton and dog-leg fail at the first.
  int max_consecutive_invalid_steps = 5;
  /// Called after every iteration; may be empty.
  std::function<void(const TrustRegionIteration&)> progress;
  /// Polled before every iteration; true stops with kInterrupted at the last accepted point.
  std::function<bool()> should_stop;

  bool is_valid(std::string* error) const;
};

/// How the model computed a step.
enum class StepQuality {
  kExact,    ///< the solution of the (damped) linear system, to working precision
  kInexact,  ///< an approximate solution (PCG on an earlier factorisation): a rejection may be
             ///< the solver's fault, so LM retries with the same lambda
  kFailed,   ///< no step (the system is not positive definite, or the solution not finite)
};

/// What the minimiser needs from a problem. The model holds the current point and its
/// linearisation, and at most one trial point. Costs are in the problem's own units (the
/// pose-graph optimiser's sum rho, the engine's 1/2 sum rho).
class TrustRegionModel {
 public:
  virtual ~TrustRegionModel() = default;
  /// Evaluates and linearises at the starting point. False when that is impossible (the reason
  /// in *error).
  virtual bool start(double* cost, std::string* error) = 0;
  /// Max-norm of the gradient at the current point, in the model's own definition.
  virtual double gradient_max_norm() = 0;
  /// ||x|| for the parameter tolerance.
  virtual double values_norm() = 0;
  /// The LM step (lambda > 0) or the Gauss-Newton step (lambda == 0): (H + lambda D) step = -g.
  /// Sets *predicted to the decrease of the model's cost along the step.
  virtual StepQuality compute_step(double lambda, Eigen::VectorXd& step, double* predicted,
                                   TrustRegionIteration& iteration) = 0;
  /// Dog-leg only: the gradient g at the current point, in the step's layout.
  virtual const Eigen::VectorXd& gradient() = 0;
  /// Dog-leg only: v^T H v, H the model's undamped Hessian approximation.
  virtual double curvature(const Eigen::VectorXd& v) = 0;
  /// Dog-leg only: the model cost decrease along `step` (from gradient() and curvature()).
  virtual double model_decrease(const Eigen::VectorXd& step) = 0;
  /// The cost at the trial point x [+] step; false when it cannot be evaluated (non-finite).
  virtual bool evaluate_trial(const Eigen::VectorXd& step, double* cost, TrustRegionIteration& iteration) = 0;
  /// The trial point becomes the current point. `final` is true when the solve ends with it
  /// (no linearisation needed there).
  virtual void accept_trial(double old_cost, double new_cost, bool final, TrustRegionIteration& iteration) = 0;
  /// The trial point is dropped; the current point stays as it was.
  virtual void reject_trial(StepQuality quality) = 0;
};

struct TrustRegionResult {
  TerminationType termination = TerminationType::kFailure;
  std::string message;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  int successful_iterations = 0;
  /// LM's lambda when the solve ended (dog-leg: 1 / radius), to start a related solve where
  /// this one stopped (GNC's outer loop).
  double final_lambda = 0.0;
  std::vector<TrustRegionIteration> iteration_log;
};

/// Minimises the model's cost from its current point. Options must be valid (checked).
TrustRegionResult minimize(TrustRegionModel& model, const TrustRegionOptions& options);

}  // namespace cairn::backend
