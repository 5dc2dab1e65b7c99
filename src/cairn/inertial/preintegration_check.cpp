#include "cairn/inertial/preintegration_check.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "cairn/core/problems.hpp"
#include "cairn/inertial/imu_factors.hpp"

namespace cairn::inertial {

bool PreintegrationCheckOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(std::isfinite(window_s) && window_s > 0.0)) problems.add("window_s must be finite and > 0");
  if (stride < 1) problems.add("stride must be >= 1");
  std::string noise_why;
  if (!noise.is_valid(&noise_why)) problems.add_all("noise: ", noise_why);
  if (!(std::isfinite(gravity_mps2) && gravity_mps2 > 0.0)) problems.add("gravity_mps2 must be finite and > 0");
  if (!(std::isfinite(max_pose_gap_s) && max_pose_gap_s > 0.0)) problems.add("max_pose_gap_s must be finite and > 0");
  return problems.report(why);
}

ErrorSpread spread_of(std::vector<double> values) {
  ErrorSpread spread;
  if (values.empty()) return spread;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  spread.median = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  spread.p90 = values[static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(n))) - 1];
  spread.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(n);
  spread.max = values.back();
  return spread;
}

namespace {

/// The pose at `stamp` interpolated between the neighbouring poses (slerp and linear), when both lie
/// within max_gap_s of it.
std::optional<core::SE3> interpolate_pose(const io::Trajectory& poses, core::Timestamp stamp, double max_gap_s) {
  const auto& stamps = poses.stamps;
  const auto upper = std::lower_bound(stamps.begin(), stamps.end(), stamp);
  if (upper == stamps.end()) return std::nullopt;
  const std::size_t j = static_cast<std::size_t>(upper - stamps.begin());
  if (*upper == stamp) return poses.poses[j];
  if (j == 0) return std::nullopt;
  const double t0 = stamps[j - 1].seconds(), t1 = stamps[j].seconds(), t = stamp.seconds();
  if (t - t0 > max_gap_s || t1 - t > max_gap_s) return std::nullopt;
  const double u = (t - t0) / (t1 - t0);
  const core::SE3& A = poses.poses[j - 1];
  const core::SE3& B = poses.poses[j];
  const Quaternion q = A.so3().unit_quaternion().slerp(u, B.so3().unit_quaternion());
  return core::SE3(q, (1.0 - u) * A.translation() + u * B.translation());
}

/// The index of the state nearest to `target`, when within half the states' mean spacing.
std::optional<std::size_t> state_near(const std::vector<GroundTruthState>& states, core::Timestamp target) {
  const auto it = std::lower_bound(states.begin(), states.end(), target,
                                   [](const GroundTruthState& s, core::Timestamp t) { return s.stamp < t; });
  const double spacing = (states.back().stamp.seconds() - states.front().stamp.seconds()) /
                         static_cast<double>(std::max<std::size_t>(1, states.size() - 1));
  std::optional<std::size_t> best;
  double best_gap = 0.5 * spacing;
  for (auto c : {it - (it == states.begin() ? 0 : 1), it}) {
    if (c == states.end()) continue;
    const double gap = std::abs(c->stamp.seconds() - target.seconds());
    if (gap <= best_gap) {
      best_gap = gap;
      best = static_cast<std::size_t>(c - states.begin());
    }
  }
  return best;
}

/// A state with its pose replaced by the interpolated ground-truth pose when there is one.
NavState true_state(const GroundTruthState& s, const io::Trajectory& poses, double max_gap_s, int& from_states) {
  NavState state = s.state;
  if (const auto pose = interpolate_pose(poses, s.stamp, max_gap_s)) {
    state.T_world_body = *pose;
  } else {
    ++from_states;
  }
  return state;
}

}  // namespace

PreintegrationCheck check_preintegration(const std::vector<ImuSample>& samples,
                                         const std::vector<GroundTruthState>& states, const io::Trajectory& poses,
                                         const PreintegrationCheckOptions& options) {
  PreintegrationCheck check;
  if (states.size() < 2) return check;
  const Vector3 gravity = gravity_z_up(options.gravity_mps2);
  const auto window_ns = static_cast<std::int64_t>(std::llround(options.window_s * 1e9));
  for (std::size_t i = 0; i < states.size(); i += static_cast<std::size_t>(options.stride)) {
    const GroundTruthState& start = states[i];
    const auto end_index = state_near(states, core::Timestamp::from_nanoseconds(start.stamp.nanoseconds() + window_ns));
    if (!end_index || *end_index <= i) {
      ++check.windows_skipped;
      continue;
    }
    const GroundTruthState& end = states[*end_index];
    PreintegratedImu preintegrated(options.noise, start.bias);
    if (!integrate_interval(samples, start.stamp, end.stamp, preintegrated)) {
      ++check.windows_skipped;
      continue;
    }
    const NavState state_i = true_state(start, poses, options.max_pose_gap_s, check.poses_from_states);
    const NavState state_j = true_state(end, poses, options.max_pose_gap_s, check.poses_from_states);
    const NavState predicted = preintegrated.predict(state_i, start.bias, gravity);
    const ImuFactor factor(preintegrated, gravity);
    const Vector9 r = factor.raw_residual(state_i, state_j, start.bias);
    WindowError error;
    error.start_s = start.stamp.seconds();
    error.duration_s = preintegrated.delta_time_s();
    error.rotation_error_deg =
        (state_j.T_world_body.so3().inverse() * predicted.T_world_body.so3()).angle() * 180.0 / M_PI;
    error.velocity_error_mps = (predicted.v_world_mps - state_j.v_world_mps).norm();
    error.position_error_m = (predicted.T_world_body.translation() - state_j.T_world_body.translation()).norm();
    error.nees = r.dot(preintegrated.covariance().ldlt().solve(r));
    check.windows.push_back(error);
  }
  std::vector<double> rotation, velocity, position, nees;
  for (const WindowError& w : check.windows) {
    rotation.push_back(w.rotation_error_deg);
    velocity.push_back(w.velocity_error_mps);
    position.push_back(w.position_error_m);
    nees.push_back(w.nees);
  }
  check.rotation_deg = spread_of(rotation);
  check.velocity_mps = spread_of(velocity);
  check.position_m = spread_of(position);
  check.nees = spread_of(nees);
  return check;
}

}  // namespace cairn::inertial
