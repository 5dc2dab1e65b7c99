#include "cairn/sim/odometry.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cairn/core/assert.hpp"

namespace cairn::sim {

OdometryNoise OdometryNoise::none() {
  OdometryNoise n;
  n.forward_sigma_m_per_sqrt_m = 0.0;
  n.lateral_sigma_m_per_sqrt_m = 0.0;
  n.yaw_sigma_rad_per_sqrt_rad = 0.0;
  n.yaw_sigma_rad_per_sqrt_m = 0.0;
  n.scale_error = 0.0;
  n.yaw_scale_error = 0.0;
  n.yaw_bias_rad_per_m = 0.0;
  n.slip_rate_per_s = 0.0;
  n.slip_max_excess = 0.0;
  return n;
}

bool OdometryNoise::is_valid(std::string* why) const {
  std::ostringstream problems;
  auto non_negative = [&](double value, const char* name) {
    if (!(value >= 0.0) || !std::isfinite(value)) problems << name << " must be >= 0 (found " << value << "); ";
  };
  non_negative(forward_sigma_m_per_sqrt_m, "forward_sigma_m_per_sqrt_m");
  non_negative(lateral_sigma_m_per_sqrt_m, "lateral_sigma_m_per_sqrt_m");
  non_negative(yaw_sigma_rad_per_sqrt_rad, "yaw_sigma_rad_per_sqrt_rad");
  non_negative(yaw_sigma_rad_per_sqrt_m, "yaw_sigma_rad_per_sqrt_m");
  non_negative(slip_rate_per_s, "slip_rate_per_s");
  non_negative(slip_duration_s, "slip_duration_s");
  non_negative(slip_max_excess, "slip_max_excess");
  if (!(scale_error > -0.5 && scale_error < 0.5)) problems << "scale_error must be in (-0.5, 0.5) (found " << scale_error << "); ";
  if (!(yaw_scale_error > -0.5 && yaw_scale_error < 0.5)) {
    problems << "yaw_scale_error must be in (-0.5, 0.5) (found " << yaw_scale_error << "); ";
  }
  if (!std::isfinite(yaw_bias_rad_per_m)) problems << "yaw_bias_rad_per_m must be finite; ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

core::SE2 WheelOdometry::measure(const core::SE2& T_prev_next, double dt_s) {
  const double dx = T_prev_next.x();
  const double dy = T_prev_next.y();
  const double dtheta = T_prev_next.angle();
  const double d = std::sqrt(dx * dx + dy * dy);
  const double a = std::abs(dtheta);

  // Slip state: five draws per step, always, so noise streams do not shift with the settings.
  const double start_draw = random_.uniform();
  const double excess_draw = random_.uniform();
  if (slip_left_s_ <= 0.0) {
    slip_excess_ = 0.0;
    if (noise_.slip_rate_per_s > 0.0 && start_draw < -std::expm1(-noise_.slip_rate_per_s * dt_s)) {
      slip_excess_ = noise_.slip_max_excess * excess_draw;
      slip_left_s_ = noise_.slip_duration_s;
      ++slip_events_;
    }
  }
  const double n1 = random_.gaussian();
  const double n2 = random_.gaussian();
  const double n3 = random_.gaussian();
  const double gain = (1.0 + noise_.scale_error) * (1.0 + slip_excess_);
  if (slip_left_s_ > 0.0) slip_left_s_ -= dt_s;

  const double sqrt_d = std::sqrt(d);
  const double measured_x = gain * dx + noise_.forward_sigma_m_per_sqrt_m * sqrt_d * n1;
  const double measured_y = gain * dy + noise_.lateral_sigma_m_per_sqrt_m * sqrt_d * n2;
  const double yaw_variance = noise_.yaw_sigma_rad_per_sqrt_rad * noise_.yaw_sigma_rad_per_sqrt_rad * a +
                              noise_.yaw_sigma_rad_per_sqrt_m * noise_.yaw_sigma_rad_per_sqrt_m * d;
  const double measured_theta =
      (1.0 + noise_.yaw_scale_error) * dtheta + noise_.yaw_bias_rad_per_m * d + std::sqrt(yaw_variance) * n3;
  return core::SE2(measured_x, measured_y, measured_theta);
}

OdometryTrack simulate_odometry(const std::vector<TrajectorySample>& truth, const OdometryNoise& noise,
                                std::uint64_t seed, const std::vector<std::size_t>& carried_samples) {
  CAIRN_ASSERT(noise.is_valid(nullptr), "simulate_odometry: invalid noise options (check is_valid first)");
  OdometryTrack track;
  if (truth.empty()) return track;
  WheelOdometry sensor(noise, seed);
  track.poses.reserve(truth.size());
  track.poses.push_back(truth.front().T_world_body);
  track.speed_mps.assign(truth.size(), 0.0);
  track.yaw_rate_rad_s.assign(truth.size(), 0.0);
  for (std::size_t k = 1; k < truth.size(); ++k) {
    const double dt = static_cast<double>(truth[k].stamp.nanoseconds() - truth[k - 1].stamp.nanoseconds()) * 1e-9;
    const bool carried = std::binary_search(carried_samples.begin(), carried_samples.end(), k);
    const core::SE2 true_increment =
        carried ? core::SE2() : truth[k - 1].T_world_body.inverse() * truth[k].T_world_body;
    const core::SE2 measured = sensor.measure(true_increment, dt);
    track.poses.push_back(track.poses.back() * measured);
    track.speed_mps[k] = measured.x() / dt;
    track.yaw_rate_rad_s[k] = measured.angle() / dt;
  }
  track.slip_events = sensor.slip_events();
  return track;
}

}  // namespace cairn::sim
