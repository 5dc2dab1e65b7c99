#include "cairn/backend/covariance.hpp"

#include "cairn/backend/factors.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"

namespace cairn::backend {

template <class Group>
std::optional<MarginalCovariances<Group>> marginal_covariances(const PoseGraphProblem<Group>& problem,
                                                                 const std::vector<int>& poses) {
  constexpr int D = Group::kDoF;
  using RowMajor = Eigen::Matrix<double, D, D, Eigen::RowMajor>;
  std::vector<int> variable(static_cast<std::size_t>(problem.size()), -1);
  int n = 0;
  for (int p = 0; p < problem.size(); ++p) {
    if (!problem.fixed[static_cast<std::size_t>(p)]) variable[static_cast<std::size_t>(p)] = n++;
  }
  std::vector<std::pair<int, int>> pairs;
  for (const auto& e : problem.edges) {
    const int a = variable[static_cast<std::size_t>(e.i)];
    const int b = variable[static_cast<std::size_t>(e.j)];
    if (a >= 0 && b >= 0) pairs.emplace_back(a, b);
  }
  BlockPattern pattern(n, D, pairs);
  for (const auto& e : problem.edges) {
    typename GeodesicFactor<Group>::Jacobian Ji;
    typename GeodesicFactor<Group>::Jacobian Jj;
    GeodesicFactor<Group>::evaluate(problem.T_world_pose[static_cast<std::size_t>(e.i)],
                                    problem.T_world_pose[static_cast<std::size_t>(e.j)], e, &Ji, &Jj);
    const int a = variable[static_cast<std::size_t>(e.i)];
    const int b = variable[static_cast<std::size_t>(e.j)];
    if (a >= 0) {
      const RowMajor H = Ji.transpose() * Ji;
      pattern.add_diagonal(a, H.data());
    }
    if (b >= 0) {
      const RowMajor H = Jj.transpose() * Jj;
      pattern.add_diagonal(b, H.data());
    }
    if (a >= 0 && b >= 0) {
      const RowMajor H = a < b ? RowMajor(Ji.transpose() * Jj) : RowMajor(Jj.transpose() * Ji);
      pattern.add_off_diagonal(std::min(a, b), std::max(a, b), H.data());
    }
  }
  MarginalCovariances<Group> result;
  result.poses = poses;
  SparseCholesky cholesky;
  if (n > 0) {
    cholesky.analyze(pattern.matrix());
    if (cholesky.factorize(pattern.matrix()) != FactorizationStatus::kSuccess) return std::nullopt;
  }
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

template std::optional<MarginalCovariances<core::SE2>> marginal_covariances(const Problem2D&, const std::vector<int>&);
template std::optional<MarginalCovariances<core::SE3>> marginal_covariances(const Problem3D&, const std::vector<int>&);

}  // namespace cairn::backend
