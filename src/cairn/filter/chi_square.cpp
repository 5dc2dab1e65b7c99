#include "cairn/filter/chi_square.hpp"

#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::filter {
namespace {

// Regularised lower incomplete gamma P(a, x) (Numerical Recipes 3rd ed. Sec. 6.2.1:
// series for x < a + 1, Lentz continued fraction for Q = 1 - P otherwise).
double gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefix = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 10000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return sum * std::exp(log_prefix);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < 10000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}

}  // namespace

double chi_square_cdf(double x, double dof) {
  CAIRN_ASSERT(dof > 0.0, "chi_square_cdf: dof must be positive");
  return gamma_p(0.5 * dof, 0.5 * x);
}

double chi_square_quantile(double probability, double dof) {
  CAIRN_ASSERT(probability > 0.0 && probability < 1.0, "chi_square_quantile: probability must be in (0, 1)");
  CAIRN_ASSERT(dof > 0.0, "chi_square_quantile: dof must be positive");
  double low = 0.0;
  double high = dof + 10.0 * std::sqrt(2.0 * dof) + 10.0;
  while (chi_square_cdf(high, dof) < probability) high *= 2.0;
  for (int i = 0; i < 200 && high - low > 1e-12 * high; ++i) {
    const double mid = 0.5 * (low + high);
    if (chi_square_cdf(mid, dof) < probability) {
      low = mid;
    } else {
      high = mid;
    }
  }
  return 0.5 * (low + high);
}

ChiSquareBand mean_chi_square_band(double dof, int runs, double probability) {
  CAIRN_ASSERT(runs > 0, "mean_chi_square_band: runs must be positive");
  const double tail = 0.5 * (1.0 - probability);
  const double total_dof = dof * runs;
  return {chi_square_quantile(tail, total_dof) / runs, chi_square_quantile(1.0 - tail, total_dof) / runs};
}

}  // namespace cairn::filter
