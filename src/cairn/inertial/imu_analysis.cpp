#include "cairn/inertial/imu_analysis.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "cairn/core/problems.hpp"

namespace cairn::inertial {

bool ImuAnalysisOptions::is_valid(std::string* why) const {
  core::Problems problems;
  std::string nested;
  if (!input.is_valid(&nested)) problems.add_all("input: ", nested);
  nested.clear();
  if (!initialization.is_valid(&nested)) problems.add_all("initialization: ", nested);
  nested.clear();
  if (!allan_options.is_valid(&nested)) problems.add_all("allan: ", nested);
  nested.clear();
  if (!check.is_valid(&nested)) problems.add_all("check: ", nested);
  nested.clear();
  if (!moving.is_valid(&nested)) problems.add_all("moving initialisation: ", nested);
  return problems.report(why);
}

namespace {

/// The ground-truth state nearest the middle of the static window.
std::optional<InitializationVsTruth> compare_initialization(const StaticInitialization& init,
                                                            const std::vector<GroundTruthState>& states) {
  if (!init.ok || states.empty()) return std::nullopt;
  const double middle = 0.5 * (init.start_s + init.end_s);
  const GroundTruthState* nearest = nullptr;
  for (const GroundTruthState& s : states) {
    if (nearest == nullptr || std::abs(s.stamp.seconds() - middle) < std::abs(nearest->stamp.seconds() - middle)) nearest = &s;
  }
  if (std::abs(nearest->stamp.seconds() - middle) > 0.5 * (init.end_s - init.start_s)) return std::nullopt;
  InitializationVsTruth out;
  out.truth_time_s = nearest->stamp.seconds();
  out.true_gyro_bias_rad_s = nearest->bias.gyro_rad_s;
  out.gyro_bias_error_rad_s = (init.gyro_bias_rad_s - nearest->bias.gyro_rad_s).norm();
  const Vector3 true_gravity_body = nearest->state.T_world_body.so3().inverse() * Vector3(0.0, 0.0, -1.0);
  const double cosine = std::clamp(true_gravity_body.dot(init.gravity_direction_body), -1.0, 1.0);
  out.gravity_angle_error_deg = std::acos(cosine) * 180.0 / M_PI;
  return out;
}

nlohmann::json spread_json(const ErrorSpread& s) {
  return {{"median", s.median}, {"p90", s.p90}, {"mean", s.mean}, {"max", s.max}};
}

nlohmann::json vector_json(const Vector3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json to_json(const MovingInitializationCheck& c) {
  nlohmann::json windows = nlohmann::json::array();
  for (const MovingInitializationWindow& w : c.windows) {
    nlohmann::json j = {{"start_s", w.start_s}, {"ok", w.ok}};
    if (w.ok) {
      j["gravity_error_deg"] = w.gravity_error_deg;
      j["gyro_bias_error_rad_s"] = w.gyro_bias_error_rad_s;
      j["accel_bias_error_mps2"] = w.accel_bias_error_mps2;
    } else {
      j["why"] = w.why;
    }
    windows.push_back(std::move(j));
  }
  return {{"method", "inertial-only MAP (Campos et al., ICRA 2020) from the ground truth's poses, scale held"},
          {"windows_still_skipped", c.windows_still},
          {"gravity_error_deg", spread_json(c.gravity_deg)},
          {"gyro_bias_error_rad_s", spread_json(c.gyro_bias_rad_s)},
          {"accel_bias_error_mps2", spread_json(c.accel_bias_mps2)},
          {"windows", windows}};
}

}  // namespace

ImuAnalysis analyse_imu(const std::vector<ImuSample>& samples, const std::vector<GroundTruthState>& states,
                        const io::Trajectory& poses, const ImuAnalysisOptions& options) {
  ImuAnalysis analysis;
  analysis.noise = options.check.noise;
  analysis.data = check_imu_data(samples, options.input);
  analysis.initialization = initialize_static(samples, options.initialization);
  analysis.initialization_vs_truth = compare_initialization(analysis.initialization, states);
  if (options.allan && samples.size() >= 3) analysis.allan = imu_allan_deviation(samples, options.allan_options);
  if (states.size() >= 2) analysis.check = check_preintegration(samples, states, poses, options.check);
  if (options.moving_initialization && states.size() >= 3) {
    analysis.moving_initialization = check_moving_initialization(samples, states, options.check.noise, options.moving);
  }
  return analysis;
}

nlohmann::json to_json(const ImuAnalysis& a) {
  nlohmann::json out;
  out["data"] = to_json(a.data);
  const StaticInitialization& init = a.initialization;
  nlohmann::json init_json = {{"ok", init.ok},
                              {"samples", init.samples},
                              {"start_s", init.start_s},
                              {"end_s", init.end_s}};
  if (!init.ok) init_json["message"] = init.message;
  if (init.samples >= 10) {
    init_json["gyro_bias_rad_s"] = vector_json(init.gyro_bias_rad_s);
    init_json["gyro_bias_sigma_rad_s"] = vector_json(init.gyro_bias_sigma_rad_s);
    init_json["gyro_std_rad_s"] = vector_json(init.gyro_std_rad_s);
    init_json["accel_std_mps2"] = vector_json(init.accel_std_mps2);
    init_json["mean_accel_mps2"] = vector_json(init.mean_accel_mps2);
  }
  if (init.ok) {
    const Vector3 rpy = init.R_world_body.to_rpy() * 180.0 / M_PI;
    init_json["roll_deg"] = rpy.x();
    init_json["pitch_deg"] = rpy.y();
    init_json["gravity_direction_body"] = vector_json(init.gravity_direction_body);
    init_json["accel_bias_along_gravity_mps2"] = init.accel_bias_along_gravity_mps2;
  }
  if (a.initialization_vs_truth) {
    const InitializationVsTruth& t = *a.initialization_vs_truth;
    init_json["against_ground_truth"] = {{"truth_time_s", t.truth_time_s},
                                         {"true_gyro_bias_rad_s", vector_json(t.true_gyro_bias_rad_s)},
                                         {"gyro_bias_error_rad_s", t.gyro_bias_error_rad_s},
                                         {"gravity_angle_error_deg", t.gravity_angle_error_deg}};
  }
  out["static_initialization"] = init_json;
  if (a.allan) out["allan"] = to_json(*a.allan);
  out["noise"] = {{"gyro_noise_density", a.noise.gyro_noise_density},
                  {"accel_noise_density", a.noise.accel_noise_density},
                  {"gyro_random_walk", a.noise.gyro_random_walk},
                  {"accel_random_walk", a.noise.accel_random_walk}};
  if (a.check) {
    const PreintegrationCheck& c = *a.check;
    out["preintegration_check"] = {{"windows", c.windows.size()},
                                   {"windows_skipped", c.windows_skipped},
                                   {"poses_from_states", c.poses_from_states},
                                   {"rotation_error_deg", spread_json(c.rotation_deg)},
                                   {"velocity_error_mps", spread_json(c.velocity_mps)},
                                   {"position_error_m", spread_json(c.position_m)},
                                   {"nees", spread_json(c.nees)},
                                   {"nees_expected", 9}};
  }
  if (a.moving_initialization) out["initialization_while_moving"] = to_json(*a.moving_initialization);
  return out;
}

}  // namespace cairn::inertial
