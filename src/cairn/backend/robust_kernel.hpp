#pragma once
/// \file
/// Robust kernels rho(s) of a squared whitened residual s = ||r||^2, applied by iteratively
/// reweighted least squares: each linearisation scales r and J by sqrt(rho'(s)) (Ceres'
/// LossFunction without the second-order correction; Triggs et al. 2000, sec. 4.3), and the
/// cost the optimiser reports and tests is sum rho(s). With rho(s) = s this is least squares.

#include <string_view>

namespace cairn::backend {

enum class RobustKernel {
  kNone,         ///< rho = s
  kHuber,        ///< rho = s for s <= c^2, 2 c sqrt(s) - c^2 beyond
  kCauchy,       ///< rho = c^2 log(1 + s / c^2)
  kGemanMcClure, ///< rho = c^2 s / (c^2 + s)
};

std::string_view to_string(RobustKernel kernel);

/// rho(s) and rho'(s) for kernel scale `c` (in whitened units, i.e. standard deviations).
struct KernelValue {
  double rho = 0.0;
  double weight = 1.0;  ///< rho'(s)
};
KernelValue evaluate_kernel(RobustKernel kernel, double c, double s);

}  // namespace cairn::backend
