#include "cairn/backend/covariance.hpp"

#include "cairn/backend/factors.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"

namespace cairn::backend {

namespace {

template <class Group, class Factor>
bool factorize_with(const PoseGraphProblem<Group>& problem, const std::vector<double>& weights,
                    std::vector<int>& variable, SparseCholesky& cholesky) {
  constexpr int D = Group::kDoF;
  using RowMajor = Eigen::Matrix<double, D, D, Eigen::RowMajor>;
  CAIRN_ASSERT(weights.empty() || weights.size() == problem.edges.size(), "one weight per edge");
  variable.assign(static_cast<std::size_t>(problem.size()), -1);
  int n = 0;
  for (int p = 0; p < problem.size(); ++p) {
    if (!problem.fixed[static_cast<std::size_t>(p)]) variable[static_cast<std::size_t>(p)] = n++;
  }
  auto weight_of = [&](std::size_t e) { return weights.empty() ? 1.0 : weights[e]; };
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t k = 0; k < problem.edges.size(); ++k) {
    const auto& e = problem.edges[k];
    const int a = variable[static_cast<std::size_t>(e.i)];
    const int b = variable[static_cast<std::size_t>(e.j)];
    if (a >= 0 && b >= 0 && weight_of(k) != 0.0) pairs.emplace_back(a, b);
  }
  // Variables numbered in elimination order (block AMD), so CHOLMOD factorises as stored.
  const std::vector<int> label = block_amd_labels(n, pairs);
  apply_block_labels(label, variable, pairs);
  BlockPattern pattern(n, D, pairs);
  for (std::size_t k = 0; k < problem.edges.size(); ++k) {
    const auto& e = problem.edges[k];
    const double w = weight_of(k);
    if (w == 0.0) continue;
    typename Factor::Jacobian Ji;
    typename Factor::Jacobian Jj;
    Factor::evaluate(problem.T_world_pose[static_cast<std::size_t>(e.i)], problem.T_world_pose[static_cast<std::size_t>(e.j)],
                     e, &Ji, &Jj);
    const int a = variable[static_cast<std::size_t>(e.i)];
    const int b = variable[static_cast<std::size_t>(e.j)];
    if (a >= 0) {
      const RowMajor H = w * Ji.transpose() * Ji;
      pattern.add_diagonal(a, H.data());
    }
    if (b >= 0) {
      const RowMajor H = w * Jj.transpose() * Jj;
      pattern.add_diagonal(b, H.data());
    }
    if (a >= 0 && b >= 0) {
      const RowMajor H = a < b ? RowMajor(w * Ji.transpose() * Jj) : RowMajor(w * Jj.transpose() * Ji);
      pattern.add_off_diagonal(std::min(a, b), std::max(a, b), H.data());
    }
  }
  if (n == 0) return true;
  cholesky.analyze_in_stored_order(pattern.matrix());
  return cholesky.factorize(pattern.matrix()) == FactorizationStatus::kSuccess;
}

}  // namespace

template <class Group>
bool factorize_normal_equations(const PoseGraphProblem<Group>& problem, Objective objective,
                                const std::vector<double>& weights, std::vector<int>& variable,
                                SparseCholesky& cholesky) {
  return with_factor<Group>(objective, [&](auto factor) {
    return factorize_with<Group, decltype(factor)>(problem, weights, variable, cholesky);
  });
}

template <class Group>
std::optional<MarginalCovariances<Group>> marginal_covariances(const PoseGraphProblem<Group>& problem,
                                                                 const std::vector<int>& poses) {
  constexpr int D = Group::kDoF;
  std::vector<int> variable;
  SparseCholesky cholesky;
  if (!factorize_normal_equations(problem, Objective::kGeodesic, {}, variable, cholesky)) return std::nullopt;
  MarginalCovariances<Group> result;
  result.poses = poses;
  for (const int p : poses) {
    CAIRN_ASSERT(p >= 0 && p < problem.size(), "pose index out of range");
    const int v = variable[static_cast<std::size_t>(p)];
    if (v < 0) {
      result.covariance.push_back(MarginalCovariances<Group>::Matrix::Zero());
      continue;
    }
    std::vector<int> columns;
    for (int k = 0; k < D; ++k) columns.push_back(v * D + k);
    const Eigen::MatrixXd X = cholesky.inverse_columns(columns);
    typename MarginalCovariances<Group>::Matrix block = X.block(v * D, 0, D, D);
    result.covariance.push_back(0.5 * (block + block.transpose()));
  }
  return result;
}

template bool factorize_normal_equations(const Problem2D&, Objective, const std::vector<double>&, std::vector<int>&,
                                         SparseCholesky&);
template bool factorize_normal_equations(const Problem3D&, Objective, const std::vector<double>&, std::vector<int>&,
                                         SparseCholesky&);
template std::optional<MarginalCovariances<core::SE2>> marginal_covariances(const Problem2D&, const std::vector<int>&);
template std::optional<MarginalCovariances<core::SE3>> marginal_covariances(const Problem3D&, const std::vector<int>&);

}  // namespace cairn::backend
