#include "cairn/sim/gnss_outputs.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <ostream>

#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/sim/imu_outputs.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;

/// `value` with exactly `decimals` decimals (no exponent, locale-independent).
void append_fixed(std::string& out, double value, int decimals) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, decimals);
  out.append(buffer, result.ptr);
}

/// gnss/fixes.csv: read_gnss_csv's layout, with the standard deviations when the fixes carry them.
void write_fixes_csv(const std::string& path, const SimulatedGnss& gnss, bool with_std) {
  io::write_output(path, [&](std::ostream& out) {
    std::string text =
        "# cairn simulate: GNSS fixes of the LiDAR's origin (the antenna); time_s is true time (times.txt's clock);\n"
        "# WGS84 latitude / longitude in degrees, height above the ellipsoid in metres; read by gnss::read_gnss_csv\n";
    text += with_std ? "time_s,lat_deg,lon_deg,alt_m,std_east_m,std_north_m,std_up_m,status\n"
                     : "time_s,lat_deg,lon_deg,alt_m,status\n";
    for (const gnss::GnssFix& fix : gnss.fixes) {
      text += fix.stamp.to_seconds_string();
      text += ',';
      append_fixed(text, fix.latitude_deg, 12);
      text += ',';
      append_fixed(text, fix.longitude_deg, 12);
      text += ',';
      append_fixed(text, fix.altitude_m, 6);
      if (with_std) {
        for (int axis = 0; axis < 3; ++axis) {
          text += ',';
          io::append_number(text, std::sqrt(fix.covariance_enu_m2(axis, axis)));
        }
      }
      text += ',' + std::to_string(fix.status) + '\n';
    }
    out << text;
  });
}

/// gnss/truth.csv: the true antenna position of each fix (ENU at the origin) and its outlier flag.
void write_truth_csv(const std::string& path, const SimulatedGnss& gnss) {
  io::write_output(path, [&](std::ostream& out) {
    std::string text =
        "# cairn simulate: the true antenna (LiDAR origin) position of each fix of gnss/fixes.csv in the ENU frame at\n"
        "# the receiver's origin (manifest.json gnss.origin), metres; outlier 1: the fix is a simulated jump\n"
        "time_s,east_m,north_m,up_m,outlier\n";
    for (std::size_t i = 0; i < gnss.fixes.size(); ++i) {
      text += gnss.fixes[i].stamp.to_seconds_string();
      for (int axis = 0; axis < 3; ++axis) {
        text += ',';
        io::append_number(text, gnss.p_enu_true_m[i](axis));
      }
      text += gnss.outlier[i] ? ",1\n" : ",0\n";
    }
    out << text;
  });
}

}  // namespace

std::vector<std::string> write_gnss_outputs(const SimulationResult& result, const Scenario& scenario,
                                            const std::string& directory) {
  fs::create_directories(fs::path(directory) / "gnss");
  write_fixes_csv((fs::path(directory) / "gnss" / "fixes.csv").string(), result.gnss, scenario.gnss.report_covariance);
  write_truth_csv((fs::path(directory) / "gnss" / "truth.csv").string(), result.gnss);
  return {"gnss/fixes.csv", "gnss/truth.csv"};
}

nlohmann::json gnss_manifest(const SimulationResult& result, const Scenario& scenario) {
  const GnssReceiverOptions o = scenario.effective_gnss();
  const SimulatedGnss& g = result.gnss;
  nlohmann::json j;
  j["model"] = "a fix every 1 / rate_hz s from the first ground-truth stamp: p_enu = T_enu_world p_world_antenna + "
               "(n_e, n_n, n_u), n ~ N(0, diag(h^2, h^2, v^2)), h = sigma_horizontal_m, v = sigma_vertical_m; with "
               "probability outlier_fraction plus a jump of uniform size in [outlier_min_m, outlier_max_m] in a "
               "uniformly random 3D direction; converted to WGS84 around origin (GeographicLib LocalCartesian)";
  j["rate_hz"] = o.rate_hz;
  j["sigma_horizontal_m"] = o.sigma_horizontal_m;
  j["sigma_vertical_m"] = o.sigma_vertical_m;
  j["outlier_fraction"] = o.outlier_fraction;
  j["outlier_min_m"] = o.outlier_min_m;
  j["outlier_max_m"] = o.outlier_max_m;
  j["dropouts_s"] = nlohmann::json::array();
  for (const auto& [start_s, end_s] : o.dropouts_s) j["dropouts_s"].push_back({start_s, end_s});
  j["origin"] = {{"latitude_deg", o.origin.latitude_deg},
                 {"longitude_deg", o.origin.longitude_deg},
                 {"altitude_m", o.origin.altitude_m}};
  j["world_yaw_deg"] = scenario.gnss_world_yaw_deg;
  j["frames"] = {{"enu", "east, north, up at origin (WGS84 ellipsoid tangent plane)"},
                 {"T_enu_world", row_major(o.T_enu_world)},
                 {"antenna", "the LiDAR's origin (lever arm 0 in the LiDAR frame)"},
                 {"T_body_antenna", row_major(T_body_lidar(scenario.lidar3d) *
                                              core::SE3(Quaternion::Identity(), o.lever_arm_body_m))},
                 {"layout", "4x4 row-major; T_a_b maps points from frame b into frame a"}};
  j["sky_visibility"] = "no fix while the antenna lies inside a tunnel (its position projected on the tunnel's axis "
                        "between the portals)";
  std::size_t outliers = 0;
  for (const bool is_outlier : g.outlier) outliers += is_outlier ? 1 : 0;
  j["epochs"] = g.fixes.size() + g.dropped_in_dropouts + g.blocked_without_sky;
  j["fixes"] = g.fixes.size();
  j["outliers"] = outliers;
  j["dropped_in_dropouts"] = g.dropped_in_dropouts;
  j["blocked_by_tunnel"] = g.blocked_without_sky;
  if (!g.fixes.empty()) {
    // Divided, not multiplied by 1e-9: 40.2 s reads 40.2, not 40.200000000000003.
    j["fix_time_s"] = {static_cast<double>(g.fixes.front().stamp.nanoseconds()) / 1e9,
                       static_cast<double>(g.fixes.back().stamp.nanoseconds()) / 1e9};
  }
  j["clocks"] = "gnss/fixes.csv and gnss/truth.csv: true time (the clock of times.txt and ground_truth.tum)";
  j["files"] = {"gnss/fixes.csv", "gnss/truth.csv"};
  return j;
}

}  // namespace cairn::sim
