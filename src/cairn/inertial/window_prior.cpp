#include "cairn/inertial/window_prior.hpp"

#include <cstddef>

namespace cairn::inertial {

StatePriorFactor::StatePriorFactor(const core::SE3& pose, const Vector3& velocity, const BiasValues& bias,
                                   const Vector3* gravity, const Eigen::MatrixXd& covariance)
    : pose_(pose),
      velocity_(velocity),
      bias_(bias),
      with_gravity_(gravity != nullptr),
      gravity_(gravity != nullptr ? *gravity : Vector3::Zero()) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (covariance + covariance.transpose()));
  const Eigen::VectorXd inverse_root = eigen.eigenvalues().cwiseMax(1e-18).cwiseSqrt().cwiseInverse();
  sqrt_information_ = inverse_root.asDiagonal() * eigen.eigenvectors().transpose();
}

bool StatePriorFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const int n = residual_size();
  Matrix6 Jr_inv;
  Eigen::VectorXd e(n);
  e.head<6>() = (pose_.inverse() * backend::se3_from_values(values[0])).log(Jr_inv);
  e.segment<3>(6) = Eigen::Map<const Vector3>(values[1]) - velocity_;
  e.segment<6>(9) = Eigen::Map<const BiasValues>(values[2]) - bias_;
  if (with_gravity_) e.tail<3>() = Eigen::Map<const Vector3>(values[3]) - gravity_;
  Eigen::Map<Eigen::VectorXd>(residual, n) = sqrt_information_ * e;
  if (jacobians == nullptr) return true;
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int sizes[4] = {6, 3, 6, 3};
  for (int v = 0, offset = 0; v < (with_gravity_ ? 4 : 3); offset += sizes[v], ++v) {
    if (jacobians[v] == nullptr) continue;
    if (v == 0) {
      Eigen::Map<RowMajor>(jacobians[v], n, 6) = sqrt_information_.leftCols(6) * Jr_inv;
    } else {
      Eigen::Map<RowMajor>(jacobians[v], n, sizes[v]) = sqrt_information_.middleCols(offset, sizes[v]);
    }
  }
  return true;
}

namespace {

using RowMajorX = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Adds factor f's w J^T J to H (offsets of the free variables' tangent blocks; -1 for constants).
void accumulate(const backend::LeastSquaresProblem& problem, int f, const std::vector<int>& offset, Eigen::MatrixXd& H) {
  const backend::Factor& factor = problem.factor(f);
  const std::vector<int>& vars = problem.factor_variables(f);
  const int m = factor.residual_size();
  std::vector<const double*> values;
  std::vector<RowMajorX> J;
  std::vector<double*> jacobians;
  for (int v : vars) {
    values.push_back(problem.values(v));
    J.emplace_back(m, problem.manifold(v).tangent_size());
  }
  for (auto& block : J) jacobians.push_back(block.data());
  Eigen::VectorXd r(m);
  if (!factor.evaluate(values.data(), r.data(), jacobians.data())) return;
  const backend::FactorLoss& loss = problem.factor_loss(f);
  const double w = backend::evaluate_kernel(loss.kernel, loss.scale, r.squaredNorm()).weight;
  for (std::size_t a = 0; a < vars.size(); ++a) {
    const int oa = offset[static_cast<std::size_t>(vars[a])];
    if (oa < 0) continue;
    for (std::size_t b = 0; b < vars.size(); ++b) {
      const int ob = offset[static_cast<std::size_t>(vars[b])];
      if (ob >= 0) H.block(oa, ob, J[a].cols(), J[b].cols()) += w * J[a].transpose() * J[b];
    }
  }
}

}  // namespace

Eigen::MatrixXd joint_marginal_covariance(const backend::LeastSquaresProblem& problem, const std::vector<int>& variables) {
  std::vector<int> offset(static_cast<std::size_t>(problem.num_variables()), -1);
  int size = 0;
  for (int v = 0; v < problem.num_variables(); ++v) {
    if (problem.is_constant(v)) continue;
    offset[static_cast<std::size_t>(v)] = size;
    size += problem.manifold(v).tangent_size();
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(size, size);
  for (int f = 0; f < problem.num_factors(); ++f) accumulate(problem, f, offset, H);
  int out_size = 0;
  for (int v : variables) out_size += problem.manifold(v).tangent_size();
  Eigen::MatrixXd selector = Eigen::MatrixXd::Zero(size, out_size);
  int column = 0;
  for (int v : variables) {
    const int n = problem.manifold(v).tangent_size();
    const int o = offset[static_cast<std::size_t>(v)];
    if (o >= 0) selector.block(o, column, n, n).setIdentity();
    column += n;
  }
  return selector.transpose() * H.ldlt().solve(selector);
}

}  // namespace cairn::inertial
