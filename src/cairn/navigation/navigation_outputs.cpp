#include "cairn/navigation/navigation_outputs.hpp"

#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>

#include "cairn/io/parse_error.hpp"

namespace cairn::navigation {

namespace {

std::string to_string(NavigationStatus status) {
  switch (status) {
    case NavigationStatus::kOk: return "ok";
    case NavigationStatus::kNoImu: return "no_imu";
    case NavigationStatus::kNotAligned: return "not_aligned";
  }
  return "unknown";
}

nlohmann::json summary_json(const NavigationSummary& s) {
  return {{"status", to_string(s.status)},
          {"message", s.message},
          {"states", s.states},
          {"imu_samples", s.imu_samples},
          {"wheel_readings", s.wheel_readings},
          {"states_without_wheel", s.states_without_wheel},
          {"fixes_received", s.fixes_received},
          {"fixes_used", s.fixes_used},
          {"fixes_late", s.fixes_late},
          {"outliers", s.outliers},
          {"gate_squared_mahalanobis", s.gate_squared_mahalanobis},
          {"still_start", s.still_start},
          {"solve_s", s.solve_s},
          {"max_step_s", s.max_step_s}};
}

}  // namespace

nlohmann::json navigation_report_json(const NavigationSummary& summary, const std::vector<GnssFixResult>& fixes) {
  nlohmann::json report;
  report["summary"] = summary_json(summary);
  const gnss::YawAlignment& a = summary.alignment;
  report["alignment"] = {{"ok", a.ok()},         {"message", a.message},         {"time_s", summary.alignment_time_s},
                         {"yaw_rad", a.yaw_rad}, {"yaw_sigma_rad", a.yaw_sigma_rad}, {"spread_m", a.spread_m},
                         {"rms_residual_m", a.rms_residual_m}, {"pairs_used", a.pairs_used}, {"pairs_rejected", a.pairs_rejected}};
  if (summary.enu_origin) {
    report["enu_origin"] = {{"latitude_deg", summary.enu_origin->latitude_deg},
                            {"longitude_deg", summary.enu_origin->longitude_deg},
                            {"altitude_m", summary.enu_origin->altitude_m}};
  }
  report["dropouts"] = nlohmann::json::array();
  for (const auto& d : summary.dropouts) report["dropouts"].push_back({{"start_s", d.start.seconds()}, {"duration_s", d.duration_s}});
  report["fixes"] = nlohmann::json::array();
  for (const GnssFixResult& f : fixes) {
    report["fixes"].push_back({{"time_s", f.time_s},
                               {"error_enu_m", {f.error_enu_m.x(), f.error_enu_m.y(), f.error_enu_m.z()}},
                               {"squared_mahalanobis", f.squared_mahalanobis},
                               {"used", f.used},
                               {"outlier", f.outlier}});
  }
  return report;
}

void write_navigation_states_csv(const std::string& path, const std::vector<NavigationState>& states) {
  std::ofstream out(path);
  if (!out) throw io::ParseError(path, 0, "could not open the file for writing");
  out << "time_s,x_m,y_m,z_m,qx,qy,qz,qw,vx_mps,vy_mps,vz_mps,bgx_rad_s,bgy_rad_s,bgz_rad_s,"
         "bax_mps2,bay_mps2,baz_mps2,wheel,gnss_fixes\n";
  for (const NavigationState& s : states) {
    const Vector3& p = s.state.T_world_body.translation();
    const Quaternion q = s.state.T_world_body.so3().unit_quaternion();
    const Vector3& v = s.state.v_world_mps;
    out << std::setprecision(17) << s.time_s << std::setprecision(9);
    for (const double x : {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w(), v.x(), v.y(), v.z(), s.bias.gyro_rad_s.x(),
                           s.bias.gyro_rad_s.y(), s.bias.gyro_rad_s.z(), s.bias.accel_mps2.x(), s.bias.accel_mps2.y(),
                           s.bias.accel_mps2.z()}) {
      out << ',' << x;
    }
    out << ',' << (s.wheel_used ? 1 : 0) << ',' << s.gnss_fixes << '\n';
  }
  out.flush();
  if (!out) throw io::ParseError(path, 0, "could not write the file (disk full?)");
}

}  // namespace cairn::navigation
