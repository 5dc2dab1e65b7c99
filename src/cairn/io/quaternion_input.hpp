#pragma once
/// \file
/// Quaternions as files hold them: any four finite numbers. SO3's constructor asserts on a
/// non-finite or zero squared norm, so components whose squares overflow (1e200) or vanish
/// (1e-170) are scaled by the largest one first. Shared by the trajectory and graph readers.

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace cairn::io {

/// Scales `q` so that SO3 can normalise it, and returns its norm before scaling (infinite when
/// that overflows, 0 for the zero quaternion). An ordinary quaternion is left bit for bit as it
/// was, which keeps normalisation exact.
inline double make_normalisable(Eigen::Quaterniond& q) {
  const double largest = q.coeffs().cwiseAbs().maxCoeff();
  if (largest == 0.0) return 0.0;
  const double squared_norm = q.squaredNorm();
  if (std::isfinite(squared_norm) && squared_norm >= std::numeric_limits<double>::min()) return std::sqrt(squared_norm);
  q.coeffs() /= largest;
  return largest * q.norm();  // may overflow to inf
}

}  // namespace cairn::io
