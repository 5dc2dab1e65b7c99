#include "cairn/navigation/navigation_outputs.hpp"

#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "cairn/gnss/local_frame.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/viz/figure.hpp"
#include "cairn/viz/render.hpp"

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
  io::write_output(path, [&](std::ostream& out) {
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
  });
}

nlohmann::json withheld_json(const WithheldComparison& c, double start_s) {
  const auto fix_json = [start_s](const WithheldFixError& e) {
    nlohmann::json j = {{"time_s", e.time_s}, {"since_start_s", e.time_s - start_s}, {"fused_m", e.fused_m}};
    j["wheel_odometry_m"] = e.wheel_m ? nlohmann::json(*e.wheel_m) : nlohmann::json(nullptr);
    return j;
  };
  nlohmann::json j = {{"from_s", c.from_s - start_s}, {"to_s", c.to_s - start_s}, {"fixes_withheld", c.fixes.size()},
                      {"fused_rms_m", c.fused_rms_m}};
  j["wheel_odometry_rms_m"] = c.wheel_rms_m ? nlohmann::json(*c.wheel_rms_m) : nlohmann::json(nullptr);
  j["first_fix_back"] = c.first_fix_back ? fix_json(*c.first_fix_back) : nlohmann::json(nullptr);
  j["fixes"] = nlohmann::json::array();
  for (const WithheldFixError& e : c.fixes) j["fixes"].push_back(fix_json(e));
  j["definition"] = "horizontal distance from each withheld fix: fused = the estimator's prediction (no measurement from the gap "
                    "or after it); wheel odometry = its own poses turned and moved onto the fused vehicle pose at the gap's start";
  return j;
}

namespace {

/// The vehicle's trajectory in the world (ENU at the first fix once aligned), one pose per state.
io::Trajectory vehicle_trajectory(const std::vector<NavigationState>& states, const core::SE3& T_imu_vehicle) {
  io::Trajectory t;
  for (const NavigationState& s : states) {
    t.stamps.push_back(core::Timestamp::from_seconds(s.time_s));
    t.poses.push_back(s.state.T_world_body * T_imu_vehicle);
  }
  return t;
}

viz::Series points(const std::string& label, viz::Rgb color, double width_px) {
  viz::Series s;
  s.label = label;
  s.style = viz::SeriesStyle::kPoints;
  s.color = color;
  s.width_px = width_px;
  return s;
}

/// Top view (east, north) of the fused path and the fixes; with a withholding, the withheld fixes
/// and the prediction over the gap, and beside it both estimates' errors against them over time.
viz::Figure navigation_figure(const NavigationRun& run, const io::Trajectory& vehicle, const GnssInertialOdometryOptions& options) {
  viz::Figure figure;
  const bool fixes = !run.fix_results.empty();
  figure.title = run.summary.enu_origin ? "cairn navigate: east-north at the first fix"
                 : fixes               ? "cairn navigate (GNSS never aligned: the IMU's start frame)"
                                       : "cairn navigate (no GNSS: the IMU's start frame)";
  viz::Axes top;
  top.x_label = run.summary.enu_origin ? "east [m]" : "x [m]";
  top.y_label = run.summary.enu_origin ? "north [m]" : "y [m]";
  top.equal_aspect = true;
  viz::Series path;
  path.label = fixes ? "fused (IMU + wheels + GNSS)" : "fused (IMU + wheels)";
  path.color = viz::categorical(0);
  for (const core::SE3& T : vehicle.poses) {
    path.x.push_back(T.translation().x());
    path.y.push_back(T.translation().y());
  }
  top.series.push_back(path);
  if (run.summary.enu_origin) {
    const gnss::LocalFrame frame(*run.summary.enu_origin);
    viz::Series used = points("fixes given", viz::kGrey, 2.5), outliers = points("fixes rejected", viz::categorical(3), 5.0);
    for (const GnssFixResult& f : run.fix_results) {
      viz::Series& s = f.outlier ? outliers : used;
      s.x.push_back(f.p_enu_m.x());
      s.y.push_back(f.p_enu_m.y());
    }
    top.series.push_back(used);
    if (!outliers.x.empty()) top.series.push_back(outliers);
    if (run.split && run.withheld) {
      viz::Series withheld = points("fixes withheld", viz::categorical(1), 3.5);
      for (const gnss::GnssFix& f : run.split->withheld) {
        const Vector3 p = frame.forward(f);
        withheld.x.push_back(p.x());
        withheld.y.push_back(p.y());
      }
      top.series.push_back(withheld);
      viz::Series predicted;
      predicted.label = "fused prediction over the gap";
      predicted.color = viz::categorical(2);
      predicted.width_px = 2.5;
      for (const WithheldFixError& e : run.withheld->fixes) {
        const Vector3 p = vehicle_pose_at(run.states, e.time_s, true, options.T_imu_vehicle).translation();
        predicted.x.push_back(p.x());
        predicted.y.push_back(p.y());
      }
      top.series.push_back(predicted);
    }
  }
  figure.panels.push_back(top);
  if (run.withheld) {
    const WithheldComparison& c = *run.withheld;
    viz::Axes errors;
    errors.title = "against the withheld fixes";
    errors.x_label = "time since the start [s]";
    errors.y_label = "horizontal error [m]";
    errors.y_from_zero = true;
    viz::Series fused, wheels;
    fused.label = "fused prediction";
    fused.color = viz::categorical(2);
    wheels.label = "wheel odometry alone";
    wheels.color = viz::categorical(4);
    for (const WithheldFixError& e : c.fixes) {
      fused.x.push_back(e.time_s - run.start_s);
      fused.y.push_back(e.fused_m);
      if (e.wheel_m) {
        wheels.x.push_back(e.time_s - run.start_s);
        wheels.y.push_back(*e.wheel_m);
      }
    }
    errors.series.push_back(fused);
    if (!wheels.x.empty()) errors.series.push_back(wheels);
    figure.panels.push_back(errors);
    figure.columns = 2;
    figure.width_px = 1600;
  }
  return figure;
}

}  // namespace

std::vector<std::string> write_navigation_outputs(io::OutputDirectory& out, const NavigationRun& run,
                                                  const GnssInertialOdometryOptions& options, const nlohmann::json& inputs,
                                                  const nlohmann::json& options_json) {
  nlohmann::json report = navigation_report_json(run.summary, run.fix_results);
  report["inputs"] = inputs;
  report["options"] = options_json;
  if (run.split) {
    report["withheld"] = run.withheld ? withheld_json(*run.withheld, run.start_s) : nlohmann::json{{"note", run.withheld_note}};
  }
  const io::Trajectory vehicle = vehicle_trajectory(run.states, options.T_imu_vehicle);
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  write_navigation_states_csv(out.staging_path("states.csv"), run.states);
  io::write_tum(out.staging_path("trajectory.tum"), vehicle);
  const viz::RenderResult png = viz::render(navigation_figure(run, vehicle, options), viz::ImageFormat::kPng);
  if (!png.ok) throw std::runtime_error("cannot draw navigation.png: " + png.message);
  io::write_output(out.staging_path("navigation.png"), [&](std::ostream& o) { o << png.bytes; });
  return {"report.json", "states.csv", "trajectory.tum", "navigation.png"};
}

}  // namespace cairn::navigation
