#include "cairn/lidar3d/gnss_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <vector>


namespace cairn::lidar3d {
namespace {

nlohmann::json vector_json(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json pose_json(const core::SE3& T) {
  const Eigen::Quaterniond q = T.so3().unit_quaternion();
  return {{"t", vector_json(T.translation())}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
}

nlohmann::json error_statistics(std::vector<double> values) {
  if (values.empty()) return nullptr;
  std::sort(values.begin(), values.end());
  const auto at = [&](double q) { return values[static_cast<std::size_t>(q * static_cast<double>(values.size() - 1))]; };
  double sum2 = 0.0;
  for (const double v : values) sum2 += v * v;
  return {{"rmse_m", std::sqrt(sum2 / static_cast<double>(values.size()))}, {"median_m", at(0.5)}, {"p90_m", at(0.9)},
          {"max_m", values.back()}};
}

}  // namespace

std::vector<std::string> gnss_warnings(const GnssAnchoring& gnss) {
  const GnssAnchoringSummary& s = gnss.summary();
  std::vector<std::string> warnings;
  if (s.fixes > 0 && s.placed == 0) {
    warnings.push_back("none of the " + std::to_string(s.fixes) + " GNSS fixes (from " + std::to_string(gnss.fixes().front().time_s) +
                       " s to " + std::to_string(gnss.fixes().back().time_s) +
                       " s) falls among the scans: are they on the scans' clock? (" + gnss.fixes().front().not_placed + ")");
  } else if (s.placed > 0 && !s.aligned) {
    warnings.push_back("the GNSS was never aligned (" + s.alignment.message + "): no fix was used");
  }
  if (s.used > 0 && 5 * s.outliers > s.used) {
    warnings.push_back(std::to_string(s.outliers) + " of " + std::to_string(s.used) +
                       " GNSS fixes are outliers: a wrong --gnss-lever-arm, clock or covariance?");
  }
  return warnings;
}

nlohmann::json gnss_json(const GnssAnchoring& gnss) {
  const GnssAnchoringSummary& s = gnss.summary();
  nlohmann::json j;
  j["fixes"] = s.fixes;
  j["placed"] = s.placed;
  j["used"] = s.used;
  j["outliers"] = s.outliers;
  j["outlier_chi2"] = s.outlier_chi2;
  j["aligned"] = s.aligned;
  if (s.enu_origin) {
    j["enu_origin"] = {{"latitude_deg", s.enu_origin->latitude_deg}, {"longitude_deg", s.enu_origin->longitude_deg},
                       {"altitude_m", s.enu_origin->altitude_m}};
  } else {
    j["enu_origin"] = nullptr;
  }
  if (s.aligned) {
    j["alignment"] = {{"time_s", s.alignment_time_s},
                      {"yaw_rad", s.alignment.yaw_rad},
                      {"yaw_sigma_rad", s.alignment.yaw_sigma_rad},
                      {"spread_m", s.alignment.spread_m},
                      {"rms_residual_m", s.alignment.rms_residual_m},
                      {"pairs_used", s.alignment.pairs_used},
                      {"pairs_rejected", s.alignment.pairs_rejected}};
    j["T_enu_world"] = pose_json(s.T_enu_world);
  } else {
    j["alignment"] = nullptr;
    j["T_enu_world"] = nullptr;
  }
  std::size_t not_placed = 0;
  std::vector<double> horizontal, vertical;
  for (const GnssFixResult& fix : gnss.fixes()) {
    not_placed += fix.keyframe < 0 ? 1 : 0;
    if (!fix.used || fix.outlier) continue;
    horizontal.push_back(fix.error_enu_m.head<2>().norm());
    vertical.push_back(std::abs(fix.error_enu_m.z()));
  }
  j["not_placed"] = not_placed;
  j["inlier_error_horizontal"] = error_statistics(horizontal);
  j["inlier_error_vertical"] = error_statistics(vertical);
  j["solves"] = s.solves;
  j["solve_s"] = s.solve_s;
  j["warnings"] = gnss_warnings(gnss);
  return j;
}

void write_gnss_fixes_csv(std::ostream& out, const GnssAnchoring& gnss) {
  out << "time_s,east_m,north_m,up_m,keyframe,not_placed,used,outlier,chi2,error_east_m,error_north_m,error_up_m\n";
  out.precision(17);
  for (const GnssFixResult& fix : gnss.fixes()) {
    out << fix.time_s << ',' << fix.p_enu_m.x() << ',' << fix.p_enu_m.y() << ',' << fix.p_enu_m.z() << ',' << fix.keyframe << ','
        << '"' << fix.not_placed << '"' << ',' << (fix.used ? 1 : 0) << ',' << (fix.outlier ? 1 : 0) << ',' << fix.chi2 << ','
        << fix.error_enu_m.x() << ',' << fix.error_enu_m.y() << ',' << fix.error_enu_m.z() << '\n';
  }
}

io::Trajectory enu_trajectory(const GnssAnchoring& gnss, const io::Trajectory& trajectory) {
  io::Trajectory out = trajectory;
  for (core::SE3& T : out.poses) T = gnss.summary().T_enu_world * T;
  return out;
}

}  // namespace cairn::lidar3d
