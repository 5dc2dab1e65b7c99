#include "cairn/lidar3d/inertial_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <utility>

#include "cairn/io/number_format.hpp"
#include "cairn/viz/color.hpp"

namespace cairn::lidar3d {
namespace {

nlohmann::json vector_json(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json pose_json(const core::SE3& T) {
  const Eigen::Quaterniond& q = T.unit_quaternion();
  return {{"t", vector_json(T.translation())}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
}

// Linear interpolation between the closest ranks (numpy's default); `sorted` not empty.
double percentile(const std::vector<double>& sorted, double p) {
  const double rank = p * static_cast<double>(sorted.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(rank));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (rank - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

// x, y, z (and optionally the norm) of `value` of every state against time, as line series.
std::vector<viz::Series> xyz_series(const InertialRun& run, Vector3 (*value)(const InertialScanState&), bool norm) {
  static const char* kAxes[] = {"x", "y", "z"};
  std::vector<viz::Series> series(norm ? 4 : 3);
  for (std::size_t a = 0; a < series.size(); ++a) {
    series[a].label = a < 3 ? kAxes[a] : "norm";
    series[a].color = a < 3 ? viz::categorical(static_cast<int>(a)) : viz::kGrey;
    series[a].dashed = a == 3;
  }
  for (const InertialScanState& s : run.states()) {
    const Vector3 v = value(s);
    for (std::size_t a = 0; a < series.size(); ++a) {
      series[a].x.push_back(s.time_s);
      series[a].y.push_back(a < 3 ? v[static_cast<Eigen::Index>(a)] : v.norm());
    }
  }
  return series;
}

viz::Axes panel(std::string title, std::string y_label, std::vector<viz::Series> series) {
  viz::Axes a;
  a.title = std::move(title);
  a.x_label = "time [s]";
  a.y_label = std::move(y_label);
  a.series = std::move(series);
  return a;
}

nlohmann::json initialization_json(const InertialRun& run) {
  if (!run.initialization()) return nullptr;
  const InertialInitialization& init = *run.initialization();
  return {{"still", init.still},
          {"overruled_by_lidar", init.overruled_by_lidar},
          {"message", init.message},
          {"window_samples", init.statics.samples},
          {"window_s", {init.statics.start_s, init.statics.end_s}},
          {"gyro_bias_rad_s", vector_json(init.statics.gyro_bias_rad_s)},
          {"gyro_bias_sigma_rad_s", vector_json(init.statics.gyro_bias_sigma_rad_s)},
          {"gyro_std_rad_s", vector_json(init.statics.gyro_std_rad_s)},
          {"accel_std_mps2", vector_json(init.statics.accel_std_mps2)},
          {"gyro_block_spread_rad_s", init.statics.gyro_block_spread_rad_s},
          {"accel_block_spread_mps2", init.statics.accel_block_spread_mps2},
          {"accel_bias_along_gravity_mps2", init.statics.accel_bias_along_gravity_mps2}};
}

nlohmann::json input_json(const InertialRun& run) {
  const InertialInput& in = run.input();
  const auto file_or_null = [](const std::string& f) { return f.empty() ? nlohmann::json(nullptr) : nlohmann::json(f); };
  return {{"source", in.source},
          {"calibration_file", file_or_null(in.calibration_file)},
          {"lidar_extrinsic_file", file_or_null(in.lidar_extrinsic_file)},
          {"time_offset_s", in.time_offset_s},
          {"noise", {{"gyro_noise_density", in.noise.gyro_noise_density}, {"gyro_random_walk", in.noise.gyro_random_walk},
                     {"accel_noise_density", in.noise.accel_noise_density}, {"accel_random_walk", in.noise.accel_random_walk}}},
          {"T_body_imu", pose_json(in.T_body_imu)},
          {"T_body_lidar", pose_json(in.T_body_lidar)},
          {"T_imu_lidar", pose_json(in.T_imu_lidar())},
          {"notes", in.notes},
          {"checks", inertial::to_json(in.checks)}};
}

}  // namespace

InertialRun::InertialRun(InertialInput input, const InertialFusionOptions& options, bool remap_forced)
    : input_(std::move(input)), options_(options), remap_forced_(remap_forced) {}

void InertialRun::add_scan(std::size_t sequence_index, const std::optional<InertialScanState>& state) {
  if (!state) {
    without_prediction_.push_back(sequence_index);
    return;
  }
  states_.push_back(*state);
  state_scans_.push_back(sequence_index);
}

void InertialRun::finish(const LidarInertialFusion& fusion) {
  if (fusion.initialized()) initialization_ = fusion.initialization();
}

InertialSummary summarize(const InertialRun& run) {
  InertialSummary s;
  s.fused_scans = run.states().size();
  s.scans_without_prediction = run.scans_without_prediction().size();
  std::vector<double> chi2;
  for (const InertialScanState& state : run.states()) {
    if (state.imu_lidar_chi2 >= 0.0) chi2.push_back(state.imu_lidar_chi2);
    s.scans_contradicting_imu += state.contradicts_imu ? 1 : 0;
    s.degenerate_scans_carried += state.degenerate ? 1 : 0;
    s.scans_without_lidar += state.lidar_used ? 0 : 1;
  }
  std::sort(chi2.begin(), chi2.end());
  s.scans_with_chi2 = chi2.size();
  if (!chi2.empty()) {
    s.median_chi2 = percentile(chi2, 0.5);
    s.p90_chi2 = percentile(chi2, 0.9);
  }
  if (!run.states().empty()) {
    s.final_bias = run.states().back().bias;
    s.final_gravity = run.states().back().gravity_world;
  }
  const inertial::ImuDataReport& checks = run.input().checks;
  if (s.scans_without_prediction > s.fused_scans) {
    s.warnings.push_back("the IMU (" + std::to_string(checks.first_stamp.seconds() + run.input().time_offset_s) + " to " +
                         std::to_string(checks.last_stamp.seconds() + run.input().time_offset_s) +
                         " s on the scans' clock) covered only " + std::to_string(s.fused_scans) + " of " +
                         std::to_string(s.fused_scans + s.scans_without_prediction) +
                         " scans' sweeps: the others ran without it (check --imu-time-offset and the scans' times)");
  }
  if (s.scans_contradicting_imu > 0) {
    s.warnings.push_back(std::to_string(s.scans_contradicting_imu) + " registrations contradicted the IMU (degraded)");
  }
  return s;
}

void write_inertial_states_csv(std::ostream& out, const InertialRun& run) {
  out << "scan,time_s,velocity_x_mps,velocity_y_mps,velocity_z_mps,gyro_bias_x_rad_s,gyro_bias_y_rad_s,gyro_bias_z_rad_s,"
         "accel_bias_x_mps2,accel_bias_y_mps2,accel_bias_z_mps2,gravity_x_mps2,gravity_y_mps2,gravity_z_mps2,imu_lidar_chi2,"
         "contradicts_imu,lidar_used,degenerate\n";
  std::string line;
  for (std::size_t i = 0; i < run.states().size(); ++i) {
    const InertialScanState& s = run.states()[i];
    line = std::to_string(run.state_scans()[i]);
    const auto add = [&line](double value) {
      line += ',';
      io::append_number(line, value);
    };
    add(s.time_s);
    for (const Vector3* v : {&s.state.v_world_mps, &s.bias.gyro_rad_s, &s.bias.accel_mps2, &s.gravity_world}) {
      for (int a = 0; a < 3; ++a) add((*v)[a]);
    }
    add(s.imu_lidar_chi2);
    line += s.contradicts_imu ? ",1" : ",0";
    line += s.lidar_used ? ",1" : ",0";
    line += s.degenerate ? ",1\n" : ",0\n";
    out << line;
  }
}

viz::Figure inertial_figure(const InertialRun& run) {
  viz::Figure f;
  f.title = "LiDAR-inertial states (" + std::to_string(run.states().size()) + " fused scans)";
  f.width_px = 1000;
  f.height_px = 1000;
  f.panels = {panel("velocity (world frame)", "velocity [m/s]",
                    xyz_series(run, [](const InertialScanState& s) { return s.state.v_world_mps; }, true)),
              panel("gyroscope bias (IMU frame)", "bias [rad/s]",
                    xyz_series(run, [](const InertialScanState& s) { return s.bias.gyro_rad_s; }, false)),
              panel("accelerometer bias (IMU frame)", "bias [m/s^2]",
                    xyz_series(run, [](const InertialScanState& s) { return s.bias.accel_mps2; }, false))};
  return f;
}

nlohmann::json inertial_json(const InertialRun& run) {
  const InertialSummary s = summarize(run);
  nlohmann::json j = input_json(run);
  j["remap_degenerate_directions_forced"] = run.remap_forced();
  if (run.remap_forced()) {
    j["remap_note"] = "registration.remap_degenerate_directions set to true: with an IMU the prediction carries the "
                      "degenerate directions";
  }
  j["initialization"] = initialization_json(run);
  j["consistency"] = {{"fused_scans", s.fused_scans},
                      {"scans_without_prediction", s.scans_without_prediction},
                      {"scans_without_prediction_list", run.scans_without_prediction()},
                      {"scans_with_chi2", s.scans_with_chi2},
                      {"median_chi2", s.median_chi2},
                      {"p90_chi2", s.p90_chi2},
                      {"contradiction_chi2", run.options().contradiction_chi2},
                      {"scans_contradicting_imu", s.scans_contradicting_imu},
                      {"degenerate_scans_carried_by_imu", s.degenerate_scans_carried},
                      {"scans_without_lidar_factor", s.scans_without_lidar}};
  j["final"] = {{"gyro_bias_rad_s", vector_json(s.final_bias.gyro_rad_s)},
                {"accel_bias_mps2", vector_json(s.final_bias.accel_mps2)},
                {"gravity_mps2", vector_json(s.final_gravity)}};
  j["warnings"] = s.warnings;
  return j;
}

}  // namespace cairn::lidar3d
