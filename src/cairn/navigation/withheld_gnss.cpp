#include "cairn/navigation/withheld_gnss.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cairn::navigation {

WithheldFixes withhold_fixes(const std::vector<gnss::GnssFix>& fixes, double from_s, double to_s) {
  WithheldFixes split;
  for (const gnss::GnssFix& fix : fixes) {
    const double t = fix.stamp.seconds();
    (t >= from_s && t < to_s ? split.withheld : split.kept).push_back(fix);
  }
  return split;
}

core::SE3 vehicle_pose_at(const std::vector<NavigationState>& states, double t_s, bool predicted, const core::SE3& T_imu_vehicle) {
  const auto after = std::upper_bound(states.begin(), states.end(), t_s,
                                      [](double t, const NavigationState& s) { return t < s.time_s; });
  const NavigationState& s = *(after == states.begin() ? after : after - 1);
  const inertial::NavState& n = predicted ? s.predicted : s.state;
  const core::SE3 T_world_imu(n.T_world_body.so3(), n.T_world_body.translation() + n.v_world_mps * (t_s - s.time_s));
  return T_world_imu * T_imu_vehicle;
}

core::SE3 wheel_pose_at(const io::Trajectory& T_odom_vehicle, double t_s) {
  const std::vector<core::Timestamp>& stamps = T_odom_vehicle.stamps;
  const auto after = std::lower_bound(stamps.begin(), stamps.end(), core::Timestamp::from_seconds(t_s));
  const std::size_t j = std::clamp<std::size_t>(static_cast<std::size_t>(after - stamps.begin()), 1, T_odom_vehicle.size() - 1);
  const double t0 = stamps[j - 1].seconds(), t1 = stamps[j].seconds();
  const double w = t1 > t0 ? std::clamp((t_s - t0) / (t1 - t0), 0.0, 1.0) : 1.0;
  const core::SE3& a = T_odom_vehicle.poses[j - 1];
  const core::SE3& b = T_odom_vehicle.poses[j];
  return core::SE3(w < 0.5 ? a.so3() : b.so3(), (1.0 - w) * a.translation() + w * b.translation());
}

namespace {

double heading(const core::SE3& T) { return std::atan2(T.so3().matrix()(1, 0), T.so3().matrix()(0, 0)); }

}  // namespace

WithheldComparison compare_with_withheld(const std::vector<NavigationState>& states, const WithheldFixes& split,
                                         double from_s, double to_s, const gnss::GeodeticPosition& enu_origin,
                                         const core::SE3& T_imu_vehicle, const io::Trajectory& wheel_poses) {
  if (states.empty()) throw std::invalid_argument("compare_with_withheld: no estimated state");
  if (split.withheld.empty()) throw std::invalid_argument("compare_with_withheld: no fix was withheld");
  const gnss::LocalFrame frame(enu_origin);
  // The wheel odometry, turned about the vertical and moved onto the fused vehicle pose at from_s.
  const bool wheels = wheel_poses.size() >= 2 && wheel_poses.has_stamps();
  core::SO3 R_enu_odom;
  Vector3 t_enu_odom = Vector3::Zero();
  if (wheels) {
    const core::SE3 T_enu_vehicle = vehicle_pose_at(states, from_s, false, T_imu_vehicle);
    const core::SE3 T_odom_vehicle = wheel_pose_at(wheel_poses, from_s);
    R_enu_odom = core::SO3::exp(Vector3(0.0, 0.0, heading(T_enu_vehicle) - heading(T_odom_vehicle)));
    t_enu_odom = T_enu_vehicle.translation() - R_enu_odom * T_odom_vehicle.translation();
  }
  const auto error_at = [&](const gnss::GnssFix& fix) {
    const Vector3 p_enu = frame.forward(fix);
    const double t = fix.stamp.seconds();
    WithheldFixError e;
    e.time_s = t;
    e.fused_m = (vehicle_pose_at(states, t, true, T_imu_vehicle).translation() - p_enu).head<2>().norm();
    if (wheels) e.wheel_m = (R_enu_odom * wheel_pose_at(wheel_poses, t).translation() + t_enu_odom - p_enu).head<2>().norm();
    return e;
  };
  WithheldComparison c;
  c.from_s = from_s;
  c.to_s = to_s;
  double fused_sq = 0.0, wheel_sq = 0.0;
  for (const gnss::GnssFix& fix : split.withheld) {
    c.fixes.push_back(error_at(fix));
    fused_sq += c.fixes.back().fused_m * c.fixes.back().fused_m;
    if (wheels) wheel_sq += *c.fixes.back().wheel_m * *c.fixes.back().wheel_m;
  }
  const double n = static_cast<double>(c.fixes.size());
  c.fused_rms_m = std::sqrt(fused_sq / n);
  if (wheels) c.wheel_rms_m = std::sqrt(wheel_sq / n);
  const auto back = std::find_if(split.kept.begin(), split.kept.end(), [&](const gnss::GnssFix& f) { return f.stamp.seconds() >= to_s; });
  if (back != split.kept.end()) c.first_fix_back = error_at(*back);
  return c;
}

}  // namespace cairn::navigation
