#pragma once
/// \file
/// The chi-square distribution: CDF and quantile, for gates (Mahalanobis distance of an
/// innovation) and for the consistency bands of NEES (Bar-Shalom, Li & Kirubarajan 2001,
/// Sec. 5.4: the average NEES over N runs of a consistent n-dimensional estimator is
/// chi^2_{nN} / N distributed, so its two-sided 95% band is [chi2inv(0.025, nN), chi2inv(0.975, nN)] / N).

namespace cairn::filter {

/// P(X <= x) for X ~ chi^2 with `dof` degrees of freedom (dof > 0, x >= 0): the regularised
/// lower incomplete gamma function P(dof / 2, x / 2) (series / continued fraction, Numerical
/// Recipes 3rd ed. Sec. 6.2), accurate to about 1e-12.
double chi_square_cdf(double x, double dof);

/// The x with chi_square_cdf(x, dof) = probability, probability in (0, 1); bisection on the CDF
/// to a relative 1e-12.
double chi_square_quantile(double probability, double dof);

/// A two-sided band [lower, upper] for the mean of `runs` independent chi^2_dof variables,
/// containing it with probability `probability` (e.g. 0.95).
struct ChiSquareBand {
  double lower = 0.0;
  double upper = 0.0;
};
ChiSquareBand mean_chi_square_band(double dof, int runs, double probability);

}  // namespace cairn::filter
