#pragma once
/// \file
/// The outputs of a SLAM run with GNSS (gnss_anchoring.hpp): report.json's `gnss` section,
/// gnss_fixes.csv (one row per fix: what became of it) and trajectory_enu.tum (the trajectory in
/// the ENU frame at the first fix, once the world was aligned to it).

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "cairn/io/trajectory.hpp"
#include "cairn/lidar3d/gnss_anchoring.hpp"

namespace cairn::lidar3d {

/// Counts, the alignment (yaw, spread, its fit's residual, when), the final T_enu_world, the ENU
/// origin, the outlier threshold, solve time, and horizontal / vertical error statistics of the
/// inliers after the last solve.
nlohmann::json gnss_json(const GnssAnchoring& gnss);

/// What the user should hear about: no fix placed (another clock?), never aligned (too little
/// motion), a large share of outliers (a wrong lever arm, frame or clock?). Also report.json's
/// `gnss.warnings`.
std::vector<std::string> gnss_warnings(const GnssAnchoring& gnss);

/// Header then one row per fix: time_s, east_m, north_m, up_m (the fix), keyframe (-1 not placed),
/// not_placed (why), used, outlier, chi2, error_east_m, error_north_m, error_up_m (estimate - fix).
void write_gnss_fixes_csv(std::ostream& out, const GnssAnchoring& gnss);

/// `trajectory` (world frame) moved into the ENU frame: T_enu_world * T_world_sensor.
io::Trajectory enu_trajectory(const GnssAnchoring& gnss, const io::Trajectory& trajectory);

}  // namespace cairn::lidar3d
