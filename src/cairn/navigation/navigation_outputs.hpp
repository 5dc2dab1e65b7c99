#pragma once
/// \file
/// What a GNSS-inertial navigation run writes (`navigation_report_json`, `write_navigation_states_csv`):
/// a JSON report (summary, alignment, dropouts, every fix with its error, Mahalanobis distance and
/// verdict) and a CSV of the states, so a command only parses flags, runs and prints.

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "cairn/navigation/gnss_inertial_odometry.hpp"

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

}  // namespace cairn::navigation
