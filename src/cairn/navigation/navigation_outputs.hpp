#pragma once
/// \file
/// What a GNSS-inertial navigation run writes (`navigation_report_json`, `write_navigation_states_csv`,
/// `write_navigation_outputs` for `cairn navigate`):
/// a JSON report (summary, alignment, dropouts, every fix with its error, Mahalanobis distance and
/// verdict) and a CSV of the states, so a command only parses flags, runs and prints.

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "cairn/io/output_file.hpp"
#include "cairn/navigation/gnss_inertial_odometry.hpp"
#include "cairn/navigation/navigation_run.hpp"

namespace cairn::navigation {

/// The report: "summary" (status, counts, timings), "alignment" (yaw, sigma, spread, residual,
/// time), "enu_origin" (lat/lon/alt of the first fix), "dropouts" ([start_s, duration_s]) and
/// "fixes" ([time_s, east/north/up error m, squared Mahalanobis, used, outlier]). Times in seconds
/// as the stamps give them.
nlohmann::json navigation_report_json(const NavigationSummary& summary, const std::vector<GnssFixResult>& fixes);

/// One line per state: time_s, x_m, y_m, z_m (world = ENU at the first fix once aligned), qx, qy,
/// qz, qw (R_world_imu), vx_mps, vy_mps, vz_mps, gyro bias (rad/s) and accelerometer bias (m/s^2)
/// xyz, wheel (0/1), gnss_fixes. Numbers with 17 significant digits for times, 9 otherwise.
/// Throws io::ParseError when the file cannot be written.
void write_navigation_states_csv(const std::string& path, const std::vector<NavigationState>& states);

/// The withheld-GNSS comparison: the interval (seconds since `start_s`), the counts, the RMS and the
/// first fix back for both estimates, and every withheld fix.
nlohmann::json withheld_json(const WithheldComparison& comparison, double start_s);

/// `cairn navigate`'s outputs into `out`'s staging directory: report.json (navigation_report_json
/// with "inputs", "options" and, with a withholding, "withheld"), states.csv, trajectory.tum (the
/// vehicle frame's poses, T_world_vehicle, world = ENU at the first fix once aligned) and
/// navigation.png (top view; with a withholding, the errors against the withheld fixes). Returns
/// the names written. Throws io::ParseError when a file cannot be written.
std::vector<std::string> write_navigation_outputs(io::OutputDirectory& out, const NavigationRun& run,
                                                  const GnssInertialOdometryOptions& options, const nlohmann::json& inputs,
                                                  const nlohmann::json& options_json);

}  // namespace cairn::navigation
