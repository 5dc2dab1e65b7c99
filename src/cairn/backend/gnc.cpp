#include "cairn/backend/gnc.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "cairn/backend/factors.hpp"
#include "cairn/core/assert.hpp"

namespace cairn::backend {

double chi2_quantile_99(int dof) {
  // Chi-square 0.99 quantiles (standard tables, e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4).
  static constexpr double kTable[] = {6.635, 9.210, 11.345, 13.277, 15.086, 16.812,
                                      18.475, 20.090, 21.666, 23.209, 24.725, 26.217};
  CAIRN_ASSERT(dof >= 1 && dof <= 12, "chi2_quantile_99: dof must be in 1..12");
  return kTable[dof - 1];
}

namespace {

double squared_residual(const auto& problem, const auto& edge, Objective objective) {
  using Group = std::decay_t<decltype(problem.T_world_pose[0])>;
  const auto& Ti = problem.T_world_pose[static_cast<std::size_t>(edge.i)];
  const auto& Tj = problem.T_world_pose[static_cast<std::size_t>(edge.j)];
  if (objective == Objective::kChordal) return ChordalFactor<Group>::evaluate(Ti, Tj, edge, nullptr, nullptr).squaredNorm();
  return GeodesicFactor<Group>::evaluate(Ti, Tj, edge, nullptr, nullptr).squaredNorm();
}

// Eq. (14) of Yang et al. 2020.
double tls_weight(double r2, double c2, double mu) {
  if (r2 <= mu / (mu + 1.0) * c2) return 1.0;
  if (r2 >= (mu + 1.0) / mu * c2) return 0.0;
  return std::sqrt(c2 / r2) * std::sqrt(mu * (mu + 1.0)) - mu;
}

}  // namespace

template <class Group>
GncSummary optimize_gnc(PoseGraphProblem<Group>& problem, const GncOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CAIRN_ASSERT(options.mu_factor > 1.0 && options.max_outer_iterations >= 1 && options.binary_tolerance > 0.0 &&
                   options.iterations_per_outer >= 1,
               "invalid GncOptions");
  GncSummary summary;
  const std::size_t m = problem.edges.size();
  const double c2 = options.inlier_threshold_chi2 > 0.0 ? options.inlier_threshold_chi2 : chi2_quantile_99(Group::kDoF);
  summary.threshold_chi2 = c2;
  std::vector<char> robust(m, 0);
  for (std::size_t e = 0; e < m; ++e) {
    robust[e] = options.robust_odometry || problem.edges[e].kind == EdgeKind::kLoopClosure;
  }

  OptimizerOptions inner = options.inner;
  inner.kernel = RobustKernel::kNone;
  inner.edge_weights.assign(m, 1.0);

  // Non-robust solution, then mu_0 from its largest robust residual (Remark 5).
  OptimizerSummary solve;
  if (options.start_from_least_squares) {
    solve = optimize(problem, inner);
    summary.inner_iterations += solve.iterations;
  }
  double max_r2 = 0.0;
  for (std::size_t e = 0; e < m; ++e) {
    if (robust[e]) max_r2 = std::max(max_r2, squared_residual(problem, problem.edges[e], inner.objective));
  }
  if (max_r2 <= c2) {
    summary.weights = inner.edge_weights;
    summary.final_solve = solve;
    summary.message = "every residual is below the inlier threshold: nothing to reject";
    summary.total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
  }
  double mu = c2 / (2.0 * max_r2 - c2);
  const int final_iterations = inner.max_iterations;
  inner.max_iterations = std::min(inner.max_iterations, options.iterations_per_outer);
  summary.message = "maximum number of outer iterations reached";
  for (int outer = 1; outer <= options.max_outer_iterations; ++outer) {
    summary.outer_iterations = outer;
    double non_binary = 0.0;
    for (std::size_t e = 0; e < m; ++e) {
      if (!robust[e]) continue;
      const double w = tls_weight(squared_residual(problem, problem.edges[e], inner.objective), c2, mu);
      inner.edge_weights[e] = w;
      non_binary += w * (1.0 - w);
    }
    solve = optimize(problem, inner);
    summary.inner_iterations += solve.iterations;
    if (non_binary < options.binary_tolerance) {
      summary.message = "weights converged to 0 or 1";
      break;
    }
    mu *= options.mu_factor;
  }
  summary.final_mu = mu;
  // Binary decision, then least squares on the accepted edges.
  for (std::size_t e = 0; e < m; ++e) {
    if (!robust[e]) continue;
    inner.edge_weights[e] = inner.edge_weights[e] >= 0.5 ? 1.0 : 0.0;
    if (inner.edge_weights[e] == 0.0) summary.rejected_edges.push_back(e);
  }
  inner.max_iterations = final_iterations;
  summary.final_solve = optimize(problem, inner);
  summary.inner_iterations += summary.final_solve.iterations;
  summary.weights = inner.edge_weights;
  summary.total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

template GncSummary optimize_gnc(Problem2D&, const GncOptions&);
template GncSummary optimize_gnc(Problem3D&, const GncOptions&);

}  // namespace cairn::backend
