#include "cairn/backend/relative_pose_factor.hpp"

#include "cairn/backend/factors.hpp"

namespace cairn::backend {

bool RelativePoseFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  using Factor3 = GeodesicFactor<core::SE3>;
  Factor3::Jacobian J_i, J_j;
  const bool want = jacobians != nullptr;
  const Factor3::Residual r =
      Factor3::evaluate(se3_from_values(values[0]), se3_from_values(values[1]), edge_, want ? &J_i : nullptr, want ? &J_j : nullptr);
  if (!r.allFinite()) return false;
  Eigen::Map<Eigen::Matrix<double, 6, 1>>{residual} = r;
  using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  if (want && jacobians[0] != nullptr) Eigen::Map<RowMajor6>{jacobians[0]} = J_i;
  if (want && jacobians[1] != nullptr) Eigen::Map<RowMajor6>{jacobians[1]} = J_j;
  return true;
}

}  // namespace cairn::backend
