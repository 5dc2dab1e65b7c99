#include "cairn/filter/nees.hpp"

#include <Eigen/Cholesky>

#include "cairn/core/so2.hpp"

namespace cairn::filter {

std::optional<double> nees(const Eigen::VectorXd& error, const Eigen::MatrixXd& covariance) {
  const Eigen::LLT<Eigen::MatrixXd> llt(covariance);
  if (llt.info() != Eigen::Success) return std::nullopt;
  return error.dot(llt.solve(error));
}

std::optional<double> pose_nees(const PoseVector& estimate, const PoseVector& truth, const Matrix3& covariance) {
  Eigen::VectorXd error = estimate - truth;
  error(2) = core::wrap_angle(error(2));
  return nees(error, covariance);
}

}  // namespace cairn::filter
