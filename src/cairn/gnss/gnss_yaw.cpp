#include "cairn/gnss/gnss_yaw.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::gnss {
namespace {

struct Fit {
  double yaw_rad = 0.0;
  Vector3 translation = Vector3::Zero();
  double spread_m = 0.0;
  double sum_squared_spread = 0.0;
};

// The closed-form 4-DoF fit over the pairs whose `keep` flag is set (see the header).
Fit fit_yaw(const std::vector<Vector3>& p_world, const std::vector<Vector3>& p_enu, const std::vector<bool>& keep) {
  Vector3 mean_world = Vector3::Zero();
  Vector3 mean_enu = Vector3::Zero();
  double n = 0.0;
  for (std::size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    mean_world += p_world[i];
    mean_enu += p_enu[i];
    n += 1.0;
  }
  mean_world /= n;
  mean_enu /= n;
  double cross = 0.0;
  double dot = 0.0;
  Fit fit;
  for (std::size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    const Vector2 x = (p_world[i] - mean_world).head<2>();
    const Vector2 y = (p_enu[i] - mean_enu).head<2>();
    cross += x.x() * y.y() - x.y() * y.x();
    dot += x.dot(y);
    fit.sum_squared_spread += x.squaredNorm();
  }
  fit.yaw_rad = std::atan2(cross, dot);
  fit.spread_m = std::sqrt(fit.sum_squared_spread / n);
  fit.translation = mean_enu - core::SO3::exp(Vector3(0.0, 0.0, fit.yaw_rad)).matrix() * mean_world;
  return fit;
}

std::vector<double> horizontal_residuals(const std::vector<Vector3>& p_world, const std::vector<Vector3>& p_enu,
                                         const Fit& fit) {
  const Matrix3 R = core::SO3::exp(Vector3(0.0, 0.0, fit.yaw_rad)).matrix();
  std::vector<double> residuals(p_world.size());
  for (std::size_t i = 0; i < p_world.size(); ++i) {
    residuals[i] = (R * p_world[i] + fit.translation - p_enu[i]).head<2>().norm();
  }
  return residuals;
}

double median_of(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// One trimming round: keeps the pairs within the threshold; returns how many it kept.
std::size_t trim(const std::vector<double>& residuals, const YawAlignmentOptions& options, std::vector<bool>& keep) {
  std::vector<double> kept;
  for (std::size_t i = 0; i < keep.size(); ++i) {
    if (keep[i]) kept.push_back(residuals[i]);
  }
  const double threshold =
      std::max(options.outlier_factor * 1.4826 * median_of(kept), options.min_outlier_threshold_m);
  std::size_t count = 0;
  for (std::size_t i = 0; i < keep.size(); ++i) {
    keep[i] = residuals[i] <= threshold;
    count += keep[i] ? 1 : 0;
  }
  return count;
}

}  // namespace

bool YawAlignmentOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(std::isfinite(min_spread_m) && min_spread_m > 0.0)) problems.add("min_spread_m must be finite and > 0");
  if (min_pairs < 2) problems.add("min_pairs must be >= 2");
  if (!(std::isfinite(outlier_factor) && outlier_factor > 0.0)) problems.add("outlier_factor must be finite and > 0");
  if (!(std::isfinite(min_outlier_threshold_m) && min_outlier_threshold_m > 0.0)) {
    problems.add("min_outlier_threshold_m must be finite and > 0");
  }
  if (trim_iterations < 0) problems.add("trim_iterations must be >= 0");
  return problems.report(why);
}

YawAlignment align_world_to_enu(const std::vector<Vector3>& p_world, const std::vector<Vector3>& p_enu,
                                const YawAlignmentOptions& options) {
  CAIRN_ASSERT(p_world.size() == p_enu.size(), "align_world_to_enu needs one ENU position per world position");
  YawAlignment result;
  std::vector<bool> keep(p_world.size(), true);
  std::size_t kept = p_world.size();
  if (kept < options.min_pairs) {
    result.message = std::to_string(kept) + " position pairs, fewer than min_pairs " + std::to_string(options.min_pairs);
    return result;
  }
  Fit fit = fit_yaw(p_world, p_enu, keep);
  for (int round = 0; round < options.trim_iterations; ++round) {
    const std::size_t before = kept;
    kept = trim(horizontal_residuals(p_world, p_enu, fit), options, keep);
    if (kept < options.min_pairs) {
      result.message = "only " + std::to_string(kept) + " position pairs agree with the fit, fewer than min_pairs";
      return result;
    }
    fit = fit_yaw(p_world, p_enu, keep);
    if (kept == before) break;
  }
  const std::vector<double> residuals = horizontal_residuals(p_world, p_enu, fit);
  double sum_squared = 0.0;
  for (std::size_t i = 0; i < keep.size(); ++i) sum_squared += keep[i] ? residuals[i] * residuals[i] : 0.0;
  result.yaw_rad = fit.yaw_rad;
  result.T_enu_world = core::SE3(core::SO3::exp(Vector3(0.0, 0.0, fit.yaw_rad)), fit.translation);
  result.spread_m = fit.spread_m;
  result.rms_residual_m = std::sqrt(sum_squared / static_cast<double>(kept));
  result.yaw_sigma_rad = result.rms_residual_m / std::sqrt(std::max(fit.sum_squared_spread, 1e-300));
  result.pairs_used = kept;
  result.pairs_rejected = p_world.size() - kept;
  if (fit.spread_m < options.min_spread_m) {
    result.status = YawAlignmentStatus::kTooLittleMotion;
    result.message = "the path spreads " + std::to_string(fit.spread_m) + " m (RMS) from its centroid, below min_spread_m " +
                     std::to_string(options.min_spread_m) + " m: yaw is not yet observable";
    return result;
  }
  result.status = YawAlignmentStatus::kOk;
  return result;
}

}  // namespace cairn::gnss
