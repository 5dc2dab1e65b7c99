#include "cairn/gnss/gnss_outliers.hpp"

#include <cmath>
#include <numbers>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"

namespace cairn::gnss {
namespace {

// Q(x) = 1 - P(x) for chi^2(3), computed without cancellation in the upper tail.
double chi_square_3_upper_tail(double x) {
  if (!(x > 0.0)) return 1.0;
  return std::erfc(std::sqrt(0.5 * x)) + std::sqrt(2.0 * x / std::numbers::pi) * std::exp(-0.5 * x);
}

}  // namespace

double chi_square_3_cdf(double x) {
  if (!(x > 0.0)) return 0.0;
  return std::erf(std::sqrt(0.5 * x)) - std::sqrt(2.0 * x / std::numbers::pi) * std::exp(-0.5 * x);
}

double chi_square_3_quantile(double probability) {
  CAIRN_ASSERT(probability > 0.0 && probability < 1.0, "chi_square_3_quantile needs a probability in (0, 1)");
  const double tail = 1.0 - probability;
  double low = 0.0;
  double high = 1.0;
  while (chi_square_3_upper_tail(high) > tail) high *= 2.0;  // Q decreases; Q(1500) underflows to 0
  for (int i = 0; i < 200 && high - low > 1e-14 * high; ++i) {
    const double middle = 0.5 * (low + high);
    (chi_square_3_upper_tail(middle) > tail ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

bool GnssOutlierOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(probability > 0.0 && probability < 1.0)) problems.add("probability must be in (0, 1)");
  if (!(std::isfinite(max_gap_s) && max_gap_s > 0.0)) problems.add("max_gap_s must be finite and > 0");
  return problems.report(why);
}

std::vector<GnssDropout> find_dropouts(const std::vector<core::Timestamp>& stamps, double max_gap_s) {
  std::vector<GnssDropout> dropouts;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    const double gap_s = static_cast<double>(stamps[i].nanoseconds() - stamps[i - 1].nanoseconds()) * 1e-9;
    if (gap_s > max_gap_s) dropouts.push_back({stamps[i - 1], gap_s});
  }
  return dropouts;
}

GnssOutlierReport gnss_outlier_report(const std::vector<GnssFix>& fixes, const std::vector<core::SE3>& T_world_body,
                                      const LocalFrame& frame, const GnssFactorOptions& factor_options,
                                      const GnssOutlierOptions& options) {
  CAIRN_ASSERT(fixes.size() == T_world_body.size(), "gnss_outlier_report needs one solved pose per fix");
  GnssOutlierReport report;
  report.threshold = chi_square_3_quantile(options.probability);
  std::vector<core::Timestamp> stamps;
  stamps.reserve(fixes.size());
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    const auto factor = make_gnss_factor(fixes[i], frame, factor_options);
    GnssFixCheck check;
    check.stamp = fixes[i].stamp;
    check.squared_mahalanobis = factor->squared_mahalanobis(T_world_body[i]);
    check.error_m = factor->error_enu_m(T_world_body[i]).norm();
    check.outlier = !(check.squared_mahalanobis <= report.threshold);
    report.outliers += check.outlier ? 1 : 0;
    report.fixes.push_back(check);
    stamps.push_back(fixes[i].stamp);
  }
  report.dropouts = find_dropouts(stamps, options.max_gap_s);
  return report;
}

}  // namespace cairn::gnss
