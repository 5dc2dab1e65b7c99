#include "cairn/backend/yaw_translation.hpp"

#include <stdexcept>

#include "cairn/core/se3.hpp"

namespace cairn::backend {

YawTranslationManifold::YawTranslationManifold(const Eigen::Vector3d& up_world) {
  if (!(up_world.allFinite() && up_world.norm() > 0.0)) throw std::invalid_argument("YawTranslationManifold: the up direction must be finite and non-zero");
  up_ = up_world.normalized();
}

void YawTranslationManifold::plus(const double* x, const double* delta, double* x_plus) const {
  const core::SE3 T = se3_from_values(x);
  const core::SO3 turn = core::SO3::exp(up_ * delta[3]);
  se3_to_values(core::SE3(turn * T.so3(), T.translation() + Eigen::Vector3d(delta[0], delta[1], delta[2])), x_plus);
}

Eigen::Matrix<double, 6, 4> YawTranslationManifold::se3_tangent_jacobian(const double* x) const {
  const Eigen::Matrix3d R_T = se3_from_values(x).so3().inverse().matrix();
  Eigen::Matrix<double, 6, 4> J = Eigen::Matrix<double, 6, 4>::Zero();
  J.topLeftCorner<3, 3>() = R_T;
  J.block<3, 1>(3, 3) = R_T * up_;
  return J;
}

YawTranslationAdapter::YawTranslationAdapter(std::unique_ptr<Factor> inner, std::vector<const YawTranslationManifold*> manifolds)
    : inner_(std::move(inner)), manifolds_(std::move(manifolds)) {}

bool YawTranslationAdapter::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  if (jacobians == nullptr) return inner_->evaluate(values, residual, nullptr);
  const int m = inner_->residual_size();
  const std::size_t n = manifolds_.size();
  // SE(3) Jacobians (m x 6, row-major) for the adapted variables, the caller's arrays for the rest.
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>> se3(n);
  std::vector<double*> inner_jacobians(n, nullptr);
  for (std::size_t b = 0; b < n; ++b) {
    if (jacobians[b] == nullptr) continue;
    if (manifolds_[b] == nullptr) {
      inner_jacobians[b] = jacobians[b];
    } else {
      se3[b].resize(m, 6);
      inner_jacobians[b] = se3[b].data();
    }
  }
  if (!inner_->evaluate(values, residual, inner_jacobians.data())) return false;
  for (std::size_t b = 0; b < n; ++b) {
    if (jacobians[b] == nullptr || manifolds_[b] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>(jacobians[b], m, 4) = se3[b] * manifolds_[b]->se3_tangent_jacobian(values[b]);
  }
  return true;
}

}  // namespace cairn::backend
