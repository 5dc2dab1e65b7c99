#pragma once
/// \file
/// Normalised estimation error squared, e^T Sigma^-1 e with e = estimate - truth (Bar-Shalom,
/// Li & Kirubarajan 2001, Sec. 5.4). For a consistent estimator it is chi^2
/// with dim(e) degrees of freedom; see chi_square.hpp for the bands of its Monte-Carlo mean.

#include <optional>

#include <Eigen/Core>

#include "cairn/filter/range_bearing.hpp"

namespace cairn::filter {

/// NEES of a vector estimate; nullopt when sigma is not positive definite.
std::optional<double> nees(const Eigen::VectorXd& error, const Eigen::MatrixXd& covariance);

/// NEES of a pose (x, y, theta) with the angle error wrapped into (-pi, pi].
std::optional<double> pose_nees(const PoseVector& estimate, const PoseVector& truth, const Matrix3& covariance);

}  // namespace cairn::filter
