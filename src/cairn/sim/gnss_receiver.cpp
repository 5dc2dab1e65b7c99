#include "cairn/sim/gnss_receiver.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

// The pose at `time_ns` between the ground-truth samples around it.
core::SE3 interpolate(const std::vector<core::Timestamp>& stamps, const std::vector<core::SE3>& poses,
                      std::int64_t time_ns) {
  const auto after = std::upper_bound(stamps.begin(), stamps.end(), core::Timestamp::from_nanoseconds(time_ns));
  if (after == stamps.begin()) return poses.front();
  if (after == stamps.end()) return poses.back();
  const std::size_t j = static_cast<std::size_t>(after - stamps.begin());
  const double span = static_cast<double>(stamps[j].nanoseconds() - stamps[j - 1].nanoseconds());
  const double s = static_cast<double>(time_ns - stamps[j - 1].nanoseconds()) / span;
  const Quaternion q = poses[j - 1].unit_quaternion().slerp(s, poses[j].unit_quaternion());
  return core::SE3(q, (1.0 - s) * poses[j - 1].translation() + s * poses[j].translation());
}

bool in_dropout(const GnssReceiverOptions& options, double since_start_s) {
  for (const auto& [start_s, end_s] : options.dropouts_s) {
    if (since_start_s >= start_s && since_start_s < end_s) return true;
  }
  return false;
}

// A uniformly random direction (normalised Gaussian vector; Muller 1959).
Vector3 random_direction(Random& random) {
  for (;;) {
    const Vector3 v(random.gaussian(), random.gaussian(), random.gaussian());
    if (v.norm() > 1e-9) return v.normalized();
  }
}

}  // namespace

bool GnssReceiverOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0)) problems.add("rate_hz must be finite and > 0");
  if (!(std::isfinite(sigma_horizontal_m) && sigma_horizontal_m >= 0.0)) problems.add("sigma_horizontal_m must be >= 0");
  if (!(std::isfinite(sigma_vertical_m) && sigma_vertical_m >= 0.0)) problems.add("sigma_vertical_m must be >= 0");
  if (report_covariance && !(sigma_horizontal_m > 0.0 && sigma_vertical_m > 0.0)) {
    problems.add("report_covariance needs sigma_horizontal_m and sigma_vertical_m > 0");
  }
  if (!lever_arm_body_m.allFinite()) problems.add("lever_arm_body_m must be finite");
  std::string geodetic;
  if (!gnss::is_valid_geodetic(origin, &geodetic)) problems.add("origin: " + geodetic);
  for (const auto& [start_s, end_s] : dropouts_s) {
    if (!(std::isfinite(start_s) && std::isfinite(end_s) && start_s < end_s)) problems.add("each dropout needs start < end");
  }
  if (!(outlier_fraction >= 0.0 && outlier_fraction <= 1.0)) problems.add("outlier_fraction must be in [0, 1]");
  if (!(std::isfinite(outlier_max_m) && outlier_min_m >= 0.0 && outlier_min_m <= outlier_max_m)) {
    problems.add("outlier sizes need 0 <= outlier_min_m <= outlier_max_m");
  }
  return problems.report(why);
}

SimulatedGnss simulate_gnss_receiver(const std::vector<core::Timestamp>& stamps,
                                     const std::vector<core::SE3>& T_world_body, const GnssReceiverOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "simulate_gnss_receiver: options are not valid (check is_valid first)");
  CAIRN_ASSERT(stamps.size() == T_world_body.size() && stamps.size() >= 2, "simulate_gnss_receiver needs >= 2 poses, one per stamp");
  const gnss::LocalFrame frame(options.origin);
  Random noise(Random::derive_seed(options.seed, 1));
  Random outliers(Random::derive_seed(options.seed, 2));
  const double period_ns = 1e9 / options.rate_hz;
  const std::int64_t first_ns = stamps.front().nanoseconds();
  SimulatedGnss out;
  for (std::int64_t k = 0;; ++k) {
    const std::int64_t time_ns = first_ns + std::llround(static_cast<double>(k) * period_ns);
    if (time_ns > stamps.back().nanoseconds()) break;
    // Every epoch draws the same variates, dropped or not, so a dropout does not reshuffle the rest.
    const Vector3 white(noise.gaussian(options.sigma_horizontal_m), noise.gaussian(options.sigma_horizontal_m),
                        noise.gaussian(options.sigma_vertical_m));
    const bool is_outlier = outliers.bernoulli(options.outlier_fraction);
    const double jump_m = outliers.uniform(options.outlier_min_m, options.outlier_max_m);
    const Vector3 direction = random_direction(outliers);
    if (in_dropout(options, static_cast<double>(time_ns - first_ns) * 1e-9)) {
      ++out.dropped_in_dropouts;
      continue;
    }
    const Vector3 p_world = interpolate(stamps, T_world_body, time_ns) * options.lever_arm_body_m;
    if (options.sky_visible && !options.sky_visible(p_world)) {
      ++out.blocked_without_sky;
      continue;
    }
    const Vector3 p_true = options.T_enu_world * p_world;
    const Vector3 p_measured = p_true + white + (is_outlier ? Vector3(jump_m * direction) : Vector3::Zero());
    const gnss::GeodeticPosition position = frame.reverse(p_measured);
    gnss::GnssFix fix;
    fix.stamp = core::Timestamp::from_nanoseconds(time_ns);
    fix.latitude_deg = position.latitude_deg;
    fix.longitude_deg = position.longitude_deg;
    fix.altitude_m = position.altitude_m;
    fix.covariance_known = options.report_covariance;
    if (options.report_covariance) {
      fix.covariance_enu_m2.diagonal() << options.sigma_horizontal_m * options.sigma_horizontal_m,
          options.sigma_horizontal_m * options.sigma_horizontal_m, options.sigma_vertical_m * options.sigma_vertical_m;
    }
    out.fixes.push_back(fix);
    out.p_enu_true_m.push_back(p_true);
    out.p_enu_measured_m.push_back(p_measured);
    out.outlier.push_back(is_outlier);
  }
  return out;
}

}  // namespace cairn::sim
