#include "cairn/backend/gnc.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <Eigen/Dense>

#include "cairn/backend/covariance.hpp"
#include "cairn/backend/factors.hpp"
#include "cairn/backend/initialization.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::backend {

double chi2_quantile_99(int dof) {
  // Chi-square 0.99 quantiles (standard tables, e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4).
  static constexpr double kTable[] = {6.635, 9.210, 11.345, 13.277, 15.086, 16.812,
                                      18.475, 20.090, 21.666, 23.209, 24.725, 26.217};
  CAIRN_ASSERT(dof >= 1 && dof <= 12, "chi2_quantile_99: dof must be in 1..12");
  return kTable[dof - 1];
}

namespace {

// Eq. (14) of Yang et al. 2020.
double tls_weight(double r2, double c2, double mu) {
  if (r2 <= mu / (mu + 1.0) * c2) return 1.0;
  if (r2 >= (mu + 1.0) / mu * c2) return 0.0;
  return std::sqrt(c2 / r2) * std::sqrt(mu * (mu + 1.0)) - mu;
}

// Covariance of an edge: the pseudo-inverse of its information (which may be singular after
// the reader's projection to positive semi-definite).
template <class Group>
Eigen::Matrix<double, Group::kDoF, Group::kDoF> covariance_of(const PoseEdge<Group>& edge) {
  constexpr int D = Group::kDoF;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, D, D>> eigen(edge.information);
  Eigen::Matrix<double, D, 1> inverse_values;
  const double floor = 1e-12 * std::max(eigen.eigenvalues().maxCoeff(), 1e-300);
  for (int k = 0; k < D; ++k) inverse_values[k] = eigen.eigenvalues()[k] > floor ? 1.0 / eigen.eigenvalues()[k] : 0.0;
  return eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose();
}

// An edge's measurement and covariance oriented from its lower pose index to its higher one:
// Z^-1 with Z exp(d) -> Z^-1 exp(-Ad(Z) d), so Sigma' = Ad(Z) Sigma Ad(Z)^T.
template <class Group>
struct Oriented {
  Group Z;
  Eigen::Matrix<double, Group::kDoF, Group::kDoF> sigma;
};

template <class Group>
Oriented<Group> oriented_forwards(const PoseEdge<Group>& edge) {
  const Eigen::Matrix<double, Group::kDoF, Group::kDoF> sigma = covariance_of(edge);
  if (edge.i <= edge.j) return {edge.T_i_j, sigma};
  const Eigen::Matrix<double, Group::kDoF, Group::kDoF> Ad = edge.T_i_j.Adj();
  return {edge.T_i_j.inverse(), Ad * sigma * Ad.transpose()};
}

// Median of chi-square with `dof` degrees of freedom, dof 1..12 (standard tables).
double chi2_median(int dof) {
  static constexpr double kTable[] = {0.455, 1.386, 2.366, 3.357, 4.351, 5.348,
                                      6.346, 7.344, 8.343, 9.342, 10.341, 11.340};
  return kTable[dof - 1];
}

// Variance factor of the stated information from short loop closures alone, before any
// optimisation: for a loop closure Z between poses a < b at most `window` apart along an
// unbroken odometry chain, the cycle e = log(Z^-1 Z_a,a+1 ... Z_b-1,b) has covariance
// Sigma_Z + Sigma_chain (the chain's by first-order propagation, Sigma_AB = Ad(B^-1) Sigma_A
// Ad(B^-1)^T + Sigma_B), so e^T (Sigma_Z + Sigma_chain)^-1 e is chi-square with kDoF degrees of
// freedom times the factor. Its median over these loops, over chi-square's median, is robust to
// the false loop closures among them (random ones rarely join poses this close and then fail by
// far). 0 when fewer than `minimum_loops` loop closures qualify.
template <class Group>
double short_loop_variance_factor(const PoseGraphProblem<Group>& problem, int window, int minimum_loops) {
  constexpr int D = Group::kDoF;
  using Matrix = Eigen::Matrix<double, D, D>;
  const std::size_t n = static_cast<std::size_t>(problem.size());
  // Odometry from index k to k + 1, oriented forwards, with its covariance.
  std::vector<char> has_odometry(n, 0);
  std::vector<Group> Z_k(n);
  std::vector<Matrix> sigma_k(n);
  for (const auto& edge : problem.edges) {
    if (edge.kind != EdgeKind::kOdometry || std::abs(edge.j - edge.i) != 1) continue;
    const auto k = static_cast<std::size_t>(std::min(edge.i, edge.j));
    const Oriented<Group> forwards = oriented_forwards(edge);
    Z_k[k] = forwards.Z;
    sigma_k[k] = forwards.sigma;
    has_odometry[k] = 1;
  }
  std::vector<double> d2;
  for (const auto& edge : problem.edges) {
    if (edge.kind != EdgeKind::kLoopClosure || std::abs(edge.j - edge.i) > window) continue;
    const int a = std::min(edge.i, edge.j);
    const int b = std::max(edge.i, edge.j);
    Group chain;
    Matrix sigma_chain = Matrix::Zero();
    bool unbroken = true;
    for (int k = a; k < b && unbroken; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      unbroken = has_odometry[kk] != 0;
      if (!unbroken) break;
      const Matrix Ad = Z_k[kk].inverse().Adj();
      sigma_chain = Ad * sigma_chain * Ad.transpose() + sigma_k[kk];
      chain = chain * Z_k[kk];
    }
    if (!unbroken) continue;
    const Oriented<Group> Z = oriented_forwards(edge);
    const typename Group::Tangent e = (Z.Z.inverse() * chain).log();
    const Eigen::LDLT<Matrix> ldlt(Z.sigma + sigma_chain);
    if (ldlt.info() != Eigen::Success) continue;
    const double value = e.dot(ldlt.solve(e));
    if (std::isfinite(value)) d2.push_back(value);
  }
  if (static_cast<int>(d2.size()) < minimum_loops) return 0.0;
  const auto middle = d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2);
  std::nth_element(d2.begin(), middle, d2.end());
  return *middle / chi2_median(D);
}

struct DisjointSets {
  std::vector<std::size_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), std::size_t{0}); }
  std::size_t find(std::size_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void unite(std::size_t a, std::size_t b) { parent[find(a)] = find(b); }
};

// State shared by the stages: the problem, which edges are robust, the weighted inner solver
// with its workspace, and the counters of the summary.
template <class Group>
class Stages {
 public:
  Stages(PoseGraphProblem<Group>& problem, const GncOptions& options, GncSummary& summary)
      : problem_(problem), options_(options), summary_(summary), inner_(options.inner) {
    const std::size_t m = problem.edges.size();
    robust_.assign(m, 0);
    for (std::size_t e = 0; e < m; ++e) {
      robust_[e] = options.robust_odometry || problem.edges[e].kind == EdgeKind::kLoopClosure;
    }
    inner_.kernel = RobustKernel::kNone;
    inner_.reuse_max_cg_iterations = options.reuse_max_cg_iterations;
    inner_.reuse_step_fraction = options.reuse_step_fraction;
    inner_.edge_weights.assign(m, 1.0);
  }

  std::vector<double>& weights() { return inner_.edge_weights; }
  const std::vector<char>& robust() const { return robust_; }
  Objective objective() const { return inner_.objective; }

  double r2(std::size_t e) const {
    const auto& edge = problem_.edges[e];
    return squared_residual(problem_.T_world_pose[static_cast<std::size_t>(edge.i)],
                            problem_.T_world_pose[static_cast<std::size_t>(edge.j)], edge, inner_.objective);
  }

  OptimizerSummary solve(int max_iterations, double initial_radius) {
    inner_.max_iterations = max_iterations;
    inner_.initial_trust_region_radius = initial_radius;
    OptimizerSummary s = optimize(problem_, inner_, &workspace_);
    summary_.inner_iterations += s.iterations;
    summary_.factorizations += s.factorizations;
    summary_.analyses = workspace_.analyses;
    ++summary_.solves;
    return s;
  }

  /// True once options.inner.should_stop says stop (SIGINT in the CLI): the stages then end early.
  bool stopped() const { return options_.inner.should_stop && options_.inner.should_stop(); }

  /// Truncated least squares at the current poses: trusted edges r^2, robust ones min(r^2, c^2).
  double tls_cost(double c2) const {
    double sum = 0.0;
    for (std::size_t e = 0; e < problem_.edges.size(); ++e) sum += robust_[e] ? std::min(r2(e), c2) : r2(e);
    return sum;
  }

  /// The graduation of Yang et al. (2020) from the current poses; leaves binary weights.
  void graduate(double c2) {
    const std::size_t m = problem_.edges.size();
    std::fill(weights().begin(), weights().end(), 1.0);
    double max_r2 = 0.0;
    for (std::size_t e = 0; e < m; ++e) {
      if (robust_[e]) max_r2 = std::max(max_r2, r2(e));
    }
    if (max_r2 <= c2) {
      summary_.graduation_converged = true;  // every residual is already an inlier's
      return;
    }
    double mu = c2 / (2.0 * max_r2 - c2);
    double radius = options_.inner.initial_trust_region_radius;
    bool binary = false;
    // The graduation's weighted solves stop earlier (graduation_function_tolerance) and keep
    // faded loop closures out of the factor (negligible_weight); the later stages do neither.
    inner_.function_tolerance = std::max(options_.inner.function_tolerance, options_.graduation_function_tolerance);
    for (int outer = 1; outer <= options_.max_outer_iterations && !binary && !stopped(); ++outer) {
      ++summary_.outer_iterations;
      double non_binary = 0.0;
      for (std::size_t e = 0; e < m; ++e) {
        if (!robust_[e]) continue;
        const double w = tls_weight(r2(e), c2, mu);
        weights()[e] = w;
        non_binary += w * (1.0 - w);
      }
      inner_.coupling_weight_floor = options_.negligible_weight * tls_weight(c2, c2, mu);
      const OptimizerSummary s = solve(std::min(options_.inner.max_iterations, options_.iterations_per_outer), radius);
      // The next weighted solve starts with this one's damping: the weights change little
      // between outer iterations.
      if (options_.carry_damping && s.final_lambda > 0.0) radius = 1.0 / s.final_lambda;
      binary = non_binary < options_.binary_tolerance;
      if (!binary) mu *= options_.mu_factor;
    }
    inner_.function_tolerance = options_.inner.function_tolerance;
    inner_.coupling_weight_floor = options_.inner.coupling_weight_floor;
    summary_.final_mu = mu;
    summary_.graduation_converged = binary;
    for (std::size_t e = 0; e < m; ++e) {
      if (robust_[e]) weights()[e] = weights()[e] >= 0.5 ? 1.0 : 0.0;
    }
  }

  /// TLS at mu = infinity by majorisation-minimisation: accept the robust edges with r^2 <= c^2,
  /// solve least squares on them, repeat until the accepted set is stable. Each round minimises
  /// an upper bound of the TLS cost that touches it at the current poses, so the cost never
  /// rises. Returns the last solve.
  OptimizerSummary reclassify(double c2) {
    OptimizerSummary last = solve(options_.inner.max_iterations, options_.inner.initial_trust_region_radius);
    for (int round = 0; round < options_.max_reclassify_rounds && !stopped(); ++round) {
      int changed = 0;
      for (std::size_t e = 0; e < problem_.edges.size(); ++e) {
        if (!robust_[e]) continue;
        const double w = r2(e) <= c2 ? 1.0 : 0.0;
        changed += w != weights()[e];
        weights()[e] = w;
      }
      if (changed == 0) break;
      ++summary_.reclassify_rounds;
      last = solve(options_.inner.max_iterations, options_.inner.initial_trust_region_radius);
    }
    return last;
  }

  /// Groups of rejected loop closures that agree with each other: two loop closures a = (i, j)
  /// and b = (k, l) with |i - k| and |j - l| at most `group_window` poses are consistent when
  /// the cycle T_jl^-1 Z_a^-1 T_ik Z_b (the short segments i->k and j->l from the current poses)
  /// is the identity within c^2 of its covariance Ad(T_jl^-1) Sigma_a Ad(T_jl^-1)^T + Sigma_b
  /// (the pairwise consistency of Mangelson et al., ICRA 2018, restricted to nearby pairs).
  /// Each group (connected components, at least two edges) is tried back in, largest first,
  /// and kept when the TLS cost falls and every edge of the group ends below c^2: a move of a
  /// local search on the TLS objective, which GNC's continuation can miss when a whole group of
  /// true loop closures closes a loop with much drift. Random false loop closures hardly ever
  /// form such groups. Returns the edges readmitted.
  std::size_t readmit_groups(double c2) {
    constexpr int D = Group::kDoF;
    using Matrix = Eigen::Matrix<double, D, D>;
    struct Candidate {
      std::size_t edge;
      int a, b;        // pose indices, a < b
      Group Z_a_b;     // measurement oriented a -> b
      Matrix sigma;    // its covariance
    };
    std::vector<Candidate> candidates;
    for (std::size_t e = 0; e < problem_.edges.size(); ++e) {
      if (!robust_[e] || weights()[e] != 0.0) continue;
      const auto& edge = problem_.edges[e];
      const Oriented<Group> forwards = oriented_forwards(edge);
      candidates.push_back(
          Candidate{e, std::min(edge.i, edge.j), std::max(edge.i, edge.j), forwards.Z, forwards.sigma});
    }
    if (candidates.size() < 2) return 0;
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) { return x.a < y.a; });
    DisjointSets sets(candidates.size());
    const auto& T = problem_.T_world_pose;
    const int window = options_.group_window;
    for (std::size_t x = 0; x < candidates.size(); ++x) {
      const Candidate& ca = candidates[x];
      for (std::size_t y = x + 1; y < candidates.size() && candidates[y].a - ca.a <= window; ++y) {
        const Candidate& cb = candidates[y];
        if (std::abs(cb.b - ca.b) > window) continue;
        const Group T_i_k = T[static_cast<std::size_t>(ca.a)].inverse() * T[static_cast<std::size_t>(cb.a)];
        const Group T_j_l = T[static_cast<std::size_t>(ca.b)].inverse() * T[static_cast<std::size_t>(cb.b)];
        const Group T_l_j = T_j_l.inverse();
        const typename Group::Tangent cycle = (T_l_j * ca.Z_a_b.inverse() * T_i_k * cb.Z_a_b).log();
        const Matrix Ad = T_l_j.Adj();
        const Matrix sigma = Ad * ca.sigma * Ad.transpose() + cb.sigma;
        const Eigen::LDLT<Matrix> ldlt(sigma);
        if (ldlt.info() != Eigen::Success) continue;
        const double d2 = cycle.dot(ldlt.solve(cycle));
        if (std::isfinite(d2) && d2 <= c2) sets.unite(x, y);
      }
    }
    std::vector<std::vector<std::size_t>> groups(candidates.size());
    for (std::size_t x = 0; x < candidates.size(); ++x) groups[sets.find(x)].push_back(candidates[x].edge);
    std::erase_if(groups, [](const auto& g) { return g.size() < 2; });
    std::sort(groups.begin(), groups.end(), [](const auto& x, const auto& y) { return x.size() > y.size(); });
    summary_.groups_tried += static_cast<int>(groups.size());
    std::size_t readmitted = 0;
    double cost = tls_cost(c2);  // at the current poses; poses change only with a kept group
    for (const auto& group : groups) {
      const std::vector<Group> poses_before = problem_.T_world_pose;
      for (const std::size_t e : group) weights()[e] = 1.0;
      solve(options_.inner.max_iterations, options_.inner.initial_trust_region_radius);
      bool fits = true;
      for (const std::size_t e : group) fits = fits && r2(e) <= c2;
      const double trial_cost = fits ? tls_cost(c2) : cost;
      if (fits && trial_cost < cost) {
        cost = trial_cost;
        readmitted += group.size();
        ++summary_.groups_readmitted;
      } else {
        for (const std::size_t e : group) weights()[e] = 0.0;
        problem_.T_world_pose = poses_before;
      }
    }
    return readmitted;
  }

  /// Restart from the chordal relaxation of the accepted edges (Carlone et al., ICRA 2015; see
  /// initialize_chordal), reclassify from there, and keep the result when the TLS cost falls.
  /// While false loop closures still weigh, the graduation can fold a stretch of the trajectory
  /// (a corner turned the wrong way); once they are rejected, the true loop closures to that
  /// stretch no longer fit and are rejected too, and the fold is a local minimum of least
  /// squares even with all of them back. Measured on city10000 with 10,688 false loop closures,
  /// seed 4: 72 true loop closures rejected, 0.27 m RMS; least squares over exactly the true
  /// edges from that result ended at chi2 2274 against the optimum's 512. The relaxation does not
  /// depend on the current poses, so it undoes such folds. Returns whether it was kept; skipped
  /// when the accepted edges leave a pose unconnected to a fixed one.
  bool restart_from_chordal(double c2, OptimizerSummary& last) {
    PoseGraphProblem<Group> accepted;
    accepted.ids = problem_.ids;
    accepted.T_world_pose = problem_.T_world_pose;
    accepted.fixed = problem_.fixed;
    accepted.has_initial_guess = problem_.has_initial_guess;
    for (std::size_t e = 0; e < problem_.edges.size(); ++e) {
      if (weights()[e] != 0.0) accepted.edges.push_back(problem_.edges[e]);
    }
    if (check_anchoring(accepted).unanchored > 0) return false;
    const double cost_before = tls_cost(c2);
    const std::vector<Group> poses_before = problem_.T_world_pose;
    const std::vector<double> weights_before = weights();
    const int rounds_before = summary_.reclassify_rounds;
    initialize_chordal(accepted);
    problem_.T_world_pose = accepted.T_world_pose;
    const OptimizerSummary s = reclassify(c2);
    if (tls_cost(c2) < cost_before * (1.0 - 1e-12)) {
      last = s;
      return true;
    }
    problem_.T_world_pose = poses_before;
    weights() = weights_before;
    summary_.reclassify_rounds = rounds_before;
    return false;
  }

  /// Rejected loop closures that the map predicts well enough: adding one measurement to a
  /// least-squares problem raises its minimum by the innovation's squared Mahalanobis norm
  /// d^2 = r^T (I + J H^-1 J^T)^-1 r (whitened residual r and Jacobian J at the current poses, H
  /// the accepted edges' J^T J; the Kalman update's identity, to first order), so accepting it
  /// lowers the TLS cost exactly when d^2 < c^2, while its bare residual r^2 overstates that
  /// cost by the map's own uncertainty. Short true loop closures are the typical case: left out,
  /// the odometry between their ends relaxes away from them. Readmits every such edge; the
  /// caller's reclassification then settles the set.
  /// With GncOptions::reject_by_leave_one_out, the mirror move too: leaving out an accepted
  /// edge lowers the minimum by d^2 = r^T (I - J H^-1 J^T)^-1 r (H with the edge; its
  /// leave-one-out innovation, Sherman-Morrison-Woodbury), so rejecting it lowers the TLS cost
  /// when d^2 > c^2. A false loop closure that GNC let bend the map around it fits that map
  /// (small r) but carries it alone (J H^-1 J^T near I), and is caught here.
  /// Returns the number of edges whose weight changed.
  /// `readmit_c2` (at most c2) is the bound for readmission, c2 the one for keeping an edge.
  std::size_t readmit_by_innovation(double c2, double readmit_c2) {
    return with_factor<Group>(inner_.objective, [&](auto factor) {
      return readmit_by_innovation_with<decltype(factor)>(c2, readmit_c2);
    });
  }

  template <class Factor>
  std::size_t readmit_by_innovation_with(double c2, double readmit_c2) {
    constexpr int D = Group::kDoF;
    constexpr int R = Factor::kResidualDim;
    std::vector<std::size_t> candidates;
    for (std::size_t e = 0; e < problem_.edges.size(); ++e) {
      if (robust_[e] && (weights()[e] == 0.0 || options_.reject_by_leave_one_out)) candidates.push_back(e);
    }
    if (candidates.empty()) return 0;
    std::vector<int> variable;
    SparseCholesky cholesky;
    if (!factorize_normal_equations(problem_, inner_.objective, weights(), variable, cholesky)) return 0;
    Eigen::Index n = 0;
    for (const int v : variable) n = std::max<Eigen::Index>(n, (v + 1) * D);
    if (n == 0) return 0;
    // J H^-1 J^T = Y^T Y with Y = L^-1 J^T (H = L L^T, stored order): J^T is non-zero only in
    // the rows of the edge's two poses, so each column of Y is a forward solve along their
    // elimination-tree paths alone (SparseCholesky::solve_lower_sparse). Full solves with the
    // columns of J^T, batched, took 59 of GNC's 77 s on corrupted city10000.
    std::vector<std::size_t> accepted;
    std::vector<std::size_t> removed;
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    std::vector<int> rows;
    std::vector<int> reach;
    Eigen::Matrix<double, Eigen::Dynamic, R> Y;
    for (const std::size_t e : candidates) {
      const auto& edge = problem_.edges[e];
      typename Factor::Jacobian Ji;
      typename Factor::Jacobian Jj;
      const typename Factor::Residual r = Factor::evaluate(problem_.T_world_pose[static_cast<std::size_t>(edge.i)],
                                                           problem_.T_world_pose[static_cast<std::size_t>(edge.j)],
                                                           edge, &Ji, &Jj);
      const int vi = variable[static_cast<std::size_t>(edge.i)];
      const int vj = variable[static_cast<std::size_t>(edge.j)];
      rows.clear();
      for (int d = 0; vi >= 0 && d < D; ++d) rows.push_back(vi * D + d);
      for (int d = 0; vj >= 0 && vj != vi && d < D; ++d) rows.push_back(vj * D + d);
      // J H^-1 J^T: H holds the edge when it is accepted, not when it is rejected.
      Eigen::Matrix<double, R, R> K = Eigen::Matrix<double, R, R>::Zero();
      if (!rows.empty()) {
        for (int k = 0; k < R; ++k) {
          for (const int row : rows) b[row] = 0.0;
          if (vi >= 0) b.template segment<D>(vi * D) += Ji.row(k).transpose();
          if (vj >= 0) b.template segment<D>(vj * D) += Jj.row(k).transpose();
          const double* y = cholesky.solve_lower_sparse(rows, b, reach);
          if (k == 0) Y.resize(static_cast<Eigen::Index>(reach.size()), R);
          CAIRN_ASSERT(static_cast<Eigen::Index>(reach.size()) == Y.rows(), "one reach for the edge's columns");
          for (std::size_t q = 0; q < reach.size(); ++q) Y(static_cast<Eigen::Index>(q), k) = y[reach[q]];
        }
        K = Y.transpose() * Y;
      }
      const bool in = weights()[e] != 0.0;
      Eigen::Matrix<double, R, R> S = Eigen::Matrix<double, R, R>::Identity();
      if (in) {
        S -= K;  // leaving the edge out
      } else {
        S += K;  // adding it
      }
      const Eigen::LDLT<Eigen::Matrix<double, R, R>> ldlt(S);
      // An accepted edge that no other path constrains has leverage 1 (S singular): it
      // cannot be judged by the others, and stays.
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() <= 1e-9) continue;
      const double d2 = r.dot(ldlt.solve(r));
      if (!std::isfinite(d2)) continue;
      if (!in && d2 <= readmit_c2) accepted.push_back(e);
      if (in && d2 > c2) removed.push_back(e);
    }
    for (const std::size_t e : accepted) weights()[e] = 1.0;
    for (const std::size_t e : removed) weights()[e] = 0.0;
    summary_.readmitted_by_innovation += static_cast<int>(accepted.size());
    summary_.rejected_by_leave_one_out += static_cast<int>(removed.size());
    return accepted.size() + removed.size();
  }

  /// Variance of unit weight (a posteriori variance factor, e.g. Foerstner & Wrobel,
  /// Photogrammetric Computer Vision, 2016, eq. 4.91): chi^2 of the accepted edges over their
  /// redundancy (accepted edges minus free poses, times the degrees of freedom). 1 when the
  /// stated information matrices match the errors; 0 when there is no redundancy.
  double variance_of_unit_weight() const {
    double chi2 = 0.0;
    std::size_t accepted = 0;
    for (std::size_t e = 0; e < problem_.edges.size(); ++e) {
      if (inner_.edge_weights[e] == 0.0) continue;
      chi2 += r2(e);
      ++accepted;
    }
    std::size_t free_poses = 0;
    for (const char f : problem_.fixed) free_poses += f == 0;
    if (accepted <= free_poses) return 0.0;
    return chi2 / static_cast<double>((accepted - free_poses) * static_cast<std::size_t>(Group::kDoF));
  }

 private:
  PoseGraphProblem<Group>& problem_;
  const GncOptions& options_;
  GncSummary& summary_;
  OptimizerOptions inner_;
  OptimizerWorkspace workspace_;
  std::vector<char> robust_;
};

}  // namespace

template <class Group>
GncSummary optimize_gnc(PoseGraphProblem<Group>& problem, const GncOptions& options) {
  const auto start = core::Clock::now();
  CAIRN_ASSERT(options.mu_factor > 1.0 && options.max_outer_iterations >= 1 && options.binary_tolerance > 0.0 &&
                   options.iterations_per_outer >= 1 && options.max_reclassify_rounds >= 0 &&
                   options.group_window >= 0 && options.scaled_threshold_multiplier > 0.0 &&
                   options.short_loop_window >= 1 && options.regraduation_ratio > 1.0 &&
                   options.final_threshold_factor >= 1.0 && options.readmission_factor > 0.0 &&
                   options.readmission_factor <= 1.0,
               "invalid GncOptions");
  GncSummary summary;
  Stages<Group> stages(problem, options, summary);
  const double quantile = chi2_quantile_99(Group::kDoF);
  const bool adaptive = options.inlier_threshold_chi2 <= 0.0 && options.estimate_noise_scale;
  // Noise variance factors are clamped: noise-free (simulated) measurements must not collapse
  // the threshold to 0.
  auto scaled_threshold = [&](double factor) {
    return options.scaled_threshold_multiplier * quantile * std::clamp(factor, 1e-3, 1e3);
  };
  double c2 = options.inlier_threshold_chi2 > 0.0 ? options.inlier_threshold_chi2 : quantile;
  if (adaptive) {
    summary.short_loop_variance_factor =
        short_loop_variance_factor(problem, options.short_loop_window, options.minimum_short_loops);
    // Only to tighten: where false loop closures make up much of the short ones (a small graph
    // whose loops are all short) the median is theirs and far above 1.
    if (summary.short_loop_variance_factor > 0.0) {
      c2 = scaled_threshold(std::min(summary.short_loop_variance_factor, 1.0));
    }
  }
  summary.initial_threshold_chi2 = c2;
  const std::vector<Group> initial_poses = problem.T_world_pose;

  using core::Clock;
  // Adds the time since `from` to `seconds` and returns now.
  auto lap = [](double& seconds, Clock::time_point from) {
    const Clock::time_point now = Clock::now();
    seconds += std::chrono::duration<double>(now - from).count();
    return now;
  };
  Clock::time_point t = Clock::now();
  // Each stage may be cut short by options.inner.should_stop; the rest are then skipped and the
  // result is the current poses with the current (binary) classification, marked interrupted.
  [&] {
    if (options.start_from_least_squares) stages.solve(options.inner.max_iterations, options.inner.initial_trust_region_radius);
    stages.graduate(c2);
    t = lap(summary.graduation_s, t);
    if (stages.stopped()) return;
    if (adaptive) {
      // The stated information matrices may be off by a common factor (intel's overstate its
      // errors some 50 times in variance): estimate it again on the accepted edges and measure
      // the threshold in it.
      summary.final_solve = stages.reclassify(c2);
      t = lap(summary.reclassify_s, t);
      summary.noise_variance_factor = stages.variance_of_unit_weight();
      if (summary.noise_variance_factor > 0.0) {
        const double scaled = scaled_threshold(summary.noise_variance_factor);
        if (scaled < c2 / options.regraduation_ratio) {
          // Much tighter: the first graduation may have bent the map around false loop closures
          // that its loose threshold let in, so graduate again from the initial guess.
          problem.T_world_pose = initial_poses;
          summary.regraduated = true;
          t = Clock::now();
          stages.graduate(scaled);
          t = lap(summary.graduation_s, t);
        }
        c2 = scaled;
      }
    }
    summary.graduation_threshold_chi2 = c2;
    // The stages after the graduation decide on a map that is right by now, so they can afford a
    // looser threshold for the heavy tails of real errors (intel's true loop closures reach 38x
    // their median r^2 at the optimum; chi-square's 0.999 quantile is 7x its median). The price:
    // a false loop closure that bends a weakly held part of the map can lower the TLS cost at this
    // threshold; GncOptions::readmission_factor keeps such edges from being readmitted.
    if (stages.stopped()) return;
    if (adaptive) c2 *= options.final_threshold_factor;
    summary.threshold_chi2 = c2;
    t = Clock::now();
    summary.final_solve = stages.reclassify(c2);
    t = lap(summary.reclassify_s, t);
    if (stages.stopped()) return;
    // A rejected loop closure needs a smaller innovation to come back than an accepted one needs
    // to stay (GncOptions::readmission_factor; with a fixed threshold, the threshold itself).
    const double readmit_c2 = adaptive ? options.readmission_factor * c2 : c2;
    if (options.restart_from_chordal) summary.restarted = stages.restart_from_chordal(c2, summary.final_solve);
    t = lap(summary.restart_s, t);
    if (stages.stopped()) return;
    if (options.group_window > 0 && stages.readmit_groups(c2) > 0) summary.final_solve = stages.reclassify(c2);
    t = lap(summary.groups_s, t);
    for (int round = 0; options.readmit_by_innovation && round < options.max_reclassify_rounds && !stages.stopped();
         ++round) {
      // Each readmitted edge alone lowers the TLS cost; several that contradict each other need
      // not, and the reclassification may then reject them again: keep a round only if the cost
      // fell, else undo it and stop (no cycling).
      const double cost_before = stages.tls_cost(c2);
      const std::vector<Group> poses_before = problem.T_world_pose;
      const std::vector<double> weights_before = stages.weights();
      const OptimizerSummary solve_before = summary.final_solve;
      const int readmitted_before = summary.readmitted_by_innovation;
      if (stages.readmit_by_innovation(c2, readmit_c2) == 0) break;
      summary.final_solve = stages.reclassify(c2);
      if (!(stages.tls_cost(c2) < cost_before * (1.0 - 1e-12))) {
        problem.T_world_pose = poses_before;
        stages.weights() = weights_before;
        summary.final_solve = solve_before;
        summary.readmitted_by_innovation = readmitted_before;
        break;
      }
    }
    t = lap(summary.innovation_s, t);
  }();
  summary.interrupted = stages.stopped();
  if (summary.threshold_chi2 == 0.0) summary.threshold_chi2 = c2;
  summary.tls_cost = stages.tls_cost(c2);

  summary.weights = stages.weights();
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    if (stages.robust()[e] && summary.weights[e] == 0.0) summary.rejected_edges.push_back(e);
  }
  summary.message = summary.interrupted          ? "interrupted (the classification so far)"
                    : summary.graduation_converged ? "weights converged to 0 or 1"
                                                   : "maximum number of outer iterations reached before the weights were binary";
  summary.total_s = core::seconds_since(start);
  return summary;
}

template GncSummary optimize_gnc(Problem2D&, const GncOptions&);
template GncSummary optimize_gnc(Problem3D&, const GncOptions&);

}  // namespace cairn::backend
