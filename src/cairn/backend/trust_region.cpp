#include "cairn/backend/trust_region.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::backend {

std::string_view to_string(Algorithm algorithm) {
  switch (algorithm) {
    case Algorithm::kLevenbergMarquardt: return "lm";
    case Algorithm::kGaussNewton: return "gn";
    case Algorithm::kDogleg: return "dogleg";
  }
  return "?";
}

std::string_view to_string(TerminationType termination) {
  switch (termination) {
    case TerminationType::kConvergence: return "convergence";
    case TerminationType::kNoConvergence: return "no_convergence";
    case TerminationType::kFailure: return "failure";
    case TerminationType::kInterrupted: return "interrupted";
  }
  return "?";
}

bool TrustRegionOptions::is_valid(std::string* error) const {
  std::ostringstream problems;
  if (max_iterations < 1) problems << "max_iterations must be >= 1; ";
  if (!(function_tolerance >= 0.0)) problems << "function_tolerance must be >= 0; ";
  if (!(gradient_tolerance >= 0.0)) problems << "gradient_tolerance must be >= 0; ";
  if (!(parameter_tolerance >= 0.0)) problems << "parameter_tolerance must be >= 0; ";
  if (!(initial_trust_region_radius > 0.0)) problems << "initial_trust_region_radius must be > 0; ";
  if (!(max_trust_region_radius >= initial_trust_region_radius)) {
    problems << "max_trust_region_radius must be >= initial_trust_region_radius; ";
  }
  if (!(min_damping_after_rejection >= 0.0)) problems << "min_damping_after_rejection must be >= 0; ";
  if (max_consecutive_invalid_steps < 1) problems << "max_consecutive_invalid_steps must be >= 1; ";
  const std::string text = problems.str();
  if (text.empty()) return true;
  if (error != nullptr) *error = text.substr(0, text.size() - 2);
  return false;
}

namespace {

using core::Clock;
using core::seconds_since;

// Ceres' min_relative_decrease: a step is taken when rho exceeds it.
constexpr double kMinRelativeDecrease = 1e-3;
// LM gives up when lambda exceeds this (Ceres' min_trust_region_radius 1e-32); dog-leg when its
// radius falls below its inverse.
constexpr double kMaxLambda = 1e32;

// Powell's dog-leg step in a trust region of `radius` from the Gauss-Newton step and the
// gradient (Nocedal & Wright, alg. 4.1 with the path's boundary crossing, eq. 4.16).
Eigen::VectorXd dogleg_step(TrustRegionModel& model, const Eigen::VectorXd& gauss_newton, double radius) {
  if (gauss_newton.norm() <= radius) return gauss_newton;
  const Eigen::VectorXd& g = model.gradient();
  const double alpha = g.squaredNorm() / model.curvature(g);
  const Eigen::VectorXd cauchy = -alpha * g;
  if (cauchy.norm() >= radius) return -(radius / g.norm()) * g;
  const Eigen::VectorXd d = gauss_newton - cauchy;
  const double a = d.squaredNorm();
  const double b = 2.0 * cauchy.dot(d);
  const double c = cauchy.squaredNorm() - radius * radius;
  const double beta = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  return cauchy + beta * d;
}

}  // namespace

TrustRegionResult minimize(TrustRegionModel& model, const TrustRegionOptions& options) {
  std::string invalid;
  CAIRN_ASSERT(options.is_valid(&invalid), invalid.c_str());
  TrustRegionResult result;
  const bool lm = options.algorithm == Algorithm::kLevenbergMarquardt;
  const bool dogleg = options.algorithm == Algorithm::kDogleg;
  const bool gauss_newton = options.algorithm == Algorithm::kGaussNewton;
  auto finish = [&](TerminationType termination, std::string message) -> TrustRegionResult& {
    result.termination = termination;
    result.message = std::move(message);
    return result;
  };

  double cost = 0.0;
  std::string error;
  if (!model.start(&cost, &error)) return finish(TerminationType::kFailure, error);
  result.initial_cost = cost;
  result.final_cost = cost;
  if (!std::isfinite(cost)) {
    return finish(TerminationType::kFailure, "the cost at the start is not finite (NaN or infinite residuals)");
  }

  const double min_lambda = 1.0 / options.max_trust_region_radius;  // 0 when the radius is unbounded
  double lambda = lm ? std::max(1.0 / options.initial_trust_region_radius, min_lambda) : 0.0;
  double nu = 2.0;  // Ceres' decrease_factor
  double radius = options.initial_trust_region_radius;
  int consecutive_invalid = 0;
  Eigen::VectorXd step;
  Eigen::VectorXd gauss_newton_step;  // dog-leg: cached while the point does not change
  bool gauss_newton_valid = false;
  double gradient_norm = model.gradient_max_norm();
  if (gradient_norm <= options.gradient_tolerance) {
    return finish(TerminationType::kConvergence, "gradient tolerance reached at the initial values (max gradient " +
                                                     std::to_string(gradient_norm) + ")");
  }
  result.final_lambda = dogleg ? 1.0 / radius : lambda;

  // A rejected or failed LM step: more damping.
  auto raise_damping = [&] {
    lambda = std::max(lambda * nu, options.min_damping_after_rejection);
    nu *= 2.0;
  };

  while (true) {
    if (options.should_stop && options.should_stop()) {
      return finish(TerminationType::kInterrupted,
                    "interrupted before iteration " + std::to_string(result.iterations + 1) +
                        "; values of the last accepted step");
    }
    if (result.iterations >= options.max_iterations) {
      return finish(TerminationType::kNoConvergence, "maximum number of iterations reached");
    }
    const auto iteration_start = Clock::now();
    TrustRegionIteration it;
    it.iteration = ++result.iterations;
    it.gradient_max_norm = gradient_norm;
    it.cost = cost;
    // The damping or radius this iteration's step is computed with.
    it.lambda = lm ? lambda : (dogleg ? radius : 0.0);
    it.trust_region_radius = lm ? 1.0 / lambda : (dogleg ? radius : std::numeric_limits<double>::infinity());
    auto record = [&] {
      it.iteration_s = seconds_since(iteration_start);
      result.final_cost = cost;
      result.final_lambda = dogleg ? 1.0 / radius : lambda;
      result.iteration_log.push_back(it);
      if (options.progress) options.progress(it);
    };

    // The step.
    double predicted = 0.0;
    StepQuality quality = StepQuality::kExact;
    if (dogleg) {
      if (!gauss_newton_valid) {
        double unused = 0.0;
        quality = model.compute_step(0.0, gauss_newton_step, &unused, it);
        gauss_newton_valid = quality != StepQuality::kFailed;
      }
      if (gauss_newton_valid) {
        step = dogleg_step(model, gauss_newton_step, radius);
        predicted = model.model_decrease(step);
      }
    } else {
      quality = model.compute_step(lambda, step, &predicted, it);
    }
    if (quality == StepQuality::kFailed) {
      if (!lm) {
        record();
        return finish(TerminationType::kFailure,
                      "the normal equations are not positive definite (is every variable constrained?)");
      }
      raise_damping();
      record();
      if (++consecutive_invalid >= options.max_consecutive_invalid_steps) {
        return finish(TerminationType::kFailure,
                      "the linear solver failed " + std::to_string(consecutive_invalid) +
                          " times in a row (the damped system is not positive definite or its solution not finite)");
      }
      continue;
    }
    consecutive_invalid = 0;
    it.step_norm = step.norm();
    if (it.step_norm <= options.parameter_tolerance * (model.values_norm() + options.parameter_tolerance)) {
      record();
      return finish(TerminationType::kConvergence, "parameter tolerance reached (step norm " + std::to_string(it.step_norm) + ")");
    }

    // The trial point.
    double new_cost = std::numeric_limits<double>::infinity();
    if (!model.evaluate_trial(step, &new_cost, it) || !std::isfinite(new_cost)) {
      new_cost = std::numeric_limits<double>::infinity();
    }
    const bool finite = std::isfinite(new_cost);
    it.cost_change = finite ? cost - new_cost : -std::numeric_limits<double>::infinity();
    it.relative_decrease = finite && predicted > 0.0 ? it.cost_change / predicted : -1.0;
    if (finite && std::abs(it.cost_change) <= options.function_tolerance * cost) {
      // Ceres' FunctionToleranceReached: tested on every trial point, taken or not, so steps at
      // the floating-point floor of the cost end the solve instead of raising the damping again
      // and again. The trial point is kept when it is no worse.
      if (it.cost_change >= 0.0) {
        model.accept_trial(cost, new_cost, /*final=*/true, it);
        cost = new_cost;
        it.step_accepted = true;
        ++result.successful_iterations;
      } else {
        model.reject_trial(quality);
      }
      it.cost = cost;
      record();
      char message[160];
      std::snprintf(message, sizeof(message), "function tolerance reached: |cost change| / cost = %.3e <= %.1e",
                    std::abs(it.cost_change) / std::max(cost, 1e-300), options.function_tolerance);
      return finish(TerminationType::kConvergence, message);
    }
    const bool accept = finite && (gauss_newton ? new_cost <= cost : it.relative_decrease > kMinRelativeDecrease);
    if (accept) {
      model.accept_trial(cost, new_cost, /*final=*/false, it);
      cost = new_cost;
      it.cost = cost;
      it.step_accepted = true;
      ++result.successful_iterations;
      gauss_newton_valid = false;
      if (lm) {
        const double t = 2.0 * it.relative_decrease - 1.0;
        lambda = std::max(min_lambda, lambda * std::max(1.0 / 3.0, 1.0 - t * t * t));
        nu = 2.0;
      } else if (dogleg) {
        if (it.relative_decrease > 0.75) radius = std::max(radius, 3.0 * it.step_norm);
        if (it.relative_decrease < 0.25) radius = 0.25 * std::min(radius, it.step_norm);
      }
      gradient_norm = model.gradient_max_norm();
      record();
      if (gradient_norm <= options.gradient_tolerance) {
        return finish(TerminationType::kConvergence,
                      "gradient tolerance reached (max gradient " + std::to_string(gradient_norm) + ")");
      }
      continue;
    }
    model.reject_trial(quality);
    if (gauss_newton) {
      record();
      return finish(TerminationType::kConvergence, "Gauss-Newton step did not decrease the cost");
    }
    if (lm && quality == StepQuality::kInexact) {
      // An inexact step failed: the fault may be the linear solver's, not the model's. Keep
      // lambda; the model computes the next step exactly.
      record();
      continue;
    }
    if (lm) {
      raise_damping();
    } else {
      radius = 0.25 * std::min(radius, it.step_norm);
    }
    record();
    if (lm && lambda > kMaxLambda) {
      return finish(TerminationType::kConvergence, "no further decrease possible (damping above 1e32)");
    }
    if (dogleg && radius < 1.0 / kMaxLambda) {
      return finish(TerminationType::kConvergence, "no further decrease possible (trust region below 1e-32)");
    }
  }
}

}  // namespace cairn::backend
