#include "cairn/backend/robust_kernel.hpp"

#include <cmath>

namespace cairn::backend {

std::string_view to_string(RobustKernel kernel) {
  switch (kernel) {
    case RobustKernel::kNone: return "none";
    case RobustKernel::kHuber: return "huber";
    case RobustKernel::kCauchy: return "cauchy";
    case RobustKernel::kGemanMcClure: return "geman-mcclure";
  }
  return "?";
}

KernelValue evaluate_kernel(RobustKernel kernel, double c, double s) {
  const double c2 = c * c;
  switch (kernel) {
    case RobustKernel::kNone: return {s, 1.0};
    case RobustKernel::kHuber: {
      if (s <= c2) return {s, 1.0};
      const double root = std::sqrt(s);
      return {2.0 * c * root - c2, c / root};
    }
    case RobustKernel::kCauchy: return {c2 * std::log1p(s / c2), 1.0 / (1.0 + s / c2)};
    case RobustKernel::kGemanMcClure: {
      const double denominator = c2 + s;
      return {c2 * s / denominator, c2 * c2 / (denominator * denominator)};
    }
  }
  return {s, 1.0};
}

}  // namespace cairn::backend
