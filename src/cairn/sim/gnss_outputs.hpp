#pragma once
/// \file
/// The simulated GNSS receiver's files and manifest entry (3D worlds, used by scenario.cpp and
/// manifest.cpp):
///  * `gnss/fixes.csv`: the fixes in the CSV layout gnss::read_gnss_csv reads (docs/formats.md,
///    "GNSS fixes (CSV)"): `time_s,lat_deg,lon_deg,alt_m,std_east_m,std_north_m,std_up_m,status`,
///    stamped with true time (the clock of times.txt and the scans), latitude and longitude with
///    12 decimals (1e-12 deg ~ 0.1 um), altitude with 6;
///  * `gnss/truth.csv`: `time_s,east_m,north_m,up_m,outlier`: the true antenna (LiDAR origin)
///    position of each fix in the ENU frame at the receiver's origin, and 1 for a simulated jump.
/// The manifest's `gnss` object repeats the model, the numbers used, the origin, T_enu_world and
/// the counts of fixes, outliers, epochs dropped in dropouts and blocked by a tunnel.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/sim/scenario.hpp"

namespace cairn::sim {

/// Writes the GNSS files into `directory` (creating gnss/) and returns their names.
/// Precondition: scenario.gnss_enabled and result.gnss filled.
std::vector<std::string> write_gnss_outputs(const SimulationResult& result, const Scenario& scenario,
                                            const std::string& directory);

/// The manifest's `gnss` object.
nlohmann::json gnss_manifest(const SimulationResult& result, const Scenario& scenario);

}  // namespace cairn::sim
