#pragma once
/// \file
/// After a solve: which GNSS fixes disagree with the estimated trajectory, and where the fixes
/// stop (`GnssOutlierReport`). A fix is an outlier when its squared Mahalanobis residual
/// e^T Sigma^-1 e at the solved pose (GnssPositionFactor::squared_mahalanobis) exceeds the
/// chi-square(3) quantile of GnssOutlierOptions::probability; a dropout is a gap between
/// consecutive fixes longer than max_gap_s. The 3-dof chi-square has a closed form, so this
/// module needs no link to cairn::filter (whose chi_square_quantile handles any dof).

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/gnss/gnss_factor.hpp"
#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/gnss/local_frame.hpp"

namespace cairn::gnss {

/// P(X <= x) for X ~ chi^2(3), x >= 0: erf(sqrt(x/2)) - sqrt(2x/pi) exp(-x/2) (the regularised
/// lower incomplete gamma P(3/2, x/2) by P(a+1, y) = P(a, y) - y^a e^-y / Gamma(a+1) from
/// P(1/2, y) = erf(sqrt(y)); Abramowitz & Stegun 6.5.21-22, 26.4.4).
double chi_square_3_cdf(double x);
/// The x with chi_square_3_cdf(x) = probability, probability in (0, 1): bisection on the upper
/// tail Q(x) = erfc(sqrt(x/2)) + sqrt(2x/pi) exp(-x/2), accurate near probability 1.
double chi_square_3_quantile(double probability);

struct GnssOutlierOptions {
  /// Chi-square(3) probability of the gate, in (0, 1): a correct fix is flagged with probability
  /// 1 - probability. 0.999 gives 16.27 (4.03 sigma of a 3D residual).
  double probability = 0.999;
  /// A gap between consecutive fixes longer than this is a dropout, seconds, > 0. 2 s is several
  /// missed fixes of a 1-10 Hz receiver but above a 2.5 Hz receiver's jitter.
  double max_gap_s = 2.0;
  bool is_valid(std::string* why) const;
};

/// One fix judged against the solved trajectory.
struct GnssFixCheck {
  core::Timestamp stamp;
  double squared_mahalanobis = 0.0;
  double error_m = 0.0;  ///< ||e||, metres
  bool outlier = false;
};

struct GnssDropout {
  core::Timestamp start;    ///< the last fix before the gap
  double duration_s = 0.0;  ///< to the next fix
};

struct GnssOutlierReport {
  double threshold = 0.0;  ///< chi2_3^-1(probability)
  std::vector<GnssFixCheck> fixes;
  std::size_t outliers = 0;
  std::vector<GnssDropout> dropouts;
};

/// The gaps longer than max_gap_s between consecutive `stamps` (increasing).
std::vector<GnssDropout> find_dropouts(const std::vector<core::Timestamp>& stamps, double max_gap_s);

/// Judges fix i at T_world_body[i] (the solved pose at the fix's time; same sizes, precondition)
/// with the factor the fix would get (make_gnss_factor(fix, frame, factor_options)).
GnssOutlierReport gnss_outlier_report(const std::vector<GnssFix>& fixes, const std::vector<core::SE3>& T_world_body,
                                      const LocalFrame& frame, const GnssFactorOptions& factor_options,
                                      const GnssOutlierOptions& options);

}  // namespace cairn::gnss
