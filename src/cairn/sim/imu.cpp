#include "cairn/sim/imu.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

Vector3 gaussian3(Random& random, double sigma) {
  const double x = random.gaussian(sigma);
  const double y = random.gaussian(sigma);
  const double z = random.gaussian(sigma);
  return {x, y, z};
}

Vector3 clip(const Vector3& value, double saturation) {
  if (saturation <= 0.0) return value;
  return value.cwiseMax(-saturation).cwiseMin(saturation);
}

}  // namespace

bool ImuSimulationOptions::is_valid(std::string* why) const {
  core::Problems problems;
  const auto non_negative = [&](double value, const std::string& name) {
    if (!(std::isfinite(value) && value >= 0.0)) problems.add(name + " must be finite and >= 0");
  };
  if (!(rate_hz >= 1.0 && rate_hz <= 10000.0)) problems.add("rate_hz must be in [1, 10000]");
  non_negative(noise.gyro_noise_density, "gyro_noise_density");
  non_negative(noise.accel_noise_density, "accel_noise_density");
  non_negative(noise.gyro_random_walk, "gyro_random_walk");
  non_negative(noise.accel_random_walk, "accel_random_walk");
  non_negative(initial_gyro_bias_sigma_rad_s, "initial_gyro_bias_sigma_rad_s");
  non_negative(initial_accel_bias_sigma_mps2, "initial_accel_bias_sigma_mps2");
  non_negative(gyro_saturation_rad_s, "gyro_saturation_rad_s");
  non_negative(accel_saturation_mps2, "accel_saturation_mps2");
  if (!(time_offset_s >= -10.0 && time_offset_s <= 10.0)) problems.add("time_offset_s must be in [-10, 10]");
  if (initial_bias && !(initial_bias->gyro_rad_s.allFinite() && initial_bias->accel_mps2.allFinite())) {
    problems.add("initial_bias must be finite");
  }
  return problems.report(why);
}

std::int64_t ImuSimulationOptions::period_ns() const { return std::llround(1e9 / rate_hz); }

std::vector<std::string> imu_preset_names() { return {"adis16448", "consumer-mems"}; }

std::optional<ImuSimulationOptions> imu_preset(std::string_view name) {
  ImuSimulationOptions o;
  if (name == "adis16448") {
    // EuRoC MAV's ADIS16448: imu0/sensor.yaml of every sequence (Burri et al., IJRR 2016) for the
    // noise and the 200 Hz rate; the ADIS16448 data sheet (Analog Devices, rev. D) for the ranges,
    // +-1000 deg/s and +-18 g. Initial biases of the order of EuRoC V1_01's estimated ones (their
    // rms over the axes: 0.046 rad/s and 0.095 m/s^2; groundtruth/V1_01_easy.csv).
    o.noise = inertial::ImuNoise{1.6968e-04, 2.0000e-03, 1.9393e-05, 3.0000e-03};
    o.rate_hz = 200.0;
    o.gyro_saturation_rad_s = 1000.0 * kDegree;
    o.accel_saturation_mps2 = 18.0 * inertial::kStandardGravity;
    o.initial_gyro_bias_sigma_rad_s = 0.04;
    o.initial_accel_bias_sigma_mps2 = 0.1;
  } else if (name == "consumer-mems") {
    // An MPU-9250 / BMI088-class consumer MEMS. White noise from the MPU-9250 product
    // specification (InvenSense PS-MPU-9250A-01 rev. 1.1): gyro rate noise spectral density
    // 0.01 deg/s/sqrt(Hz) = 1.745e-4 rad/s/sqrt(Hz); accelerometer noise power spectral density
    // 300 ug/sqrt(Hz) = 2.942e-3 m/s^2/sqrt(Hz). Data sheets give no bias random walk: the values
    // here (4e-5 rad/s^2/sqrt(Hz), 4e-3 m/s^3/sqrt(Hz)) are typical of Kalibr-format
    // calibrations of such IMUs, about twice EuRoC's for the gyro, not a measured figure. Full
    // scale +-2000 deg/s and +-16 g (the largest ranges of both parts). Initial biases: a third
    // of the MPU-9250's initial tolerances (+-5 deg/s zero-rate output, +-80 mg zero-g output).
    o.noise = inertial::ImuNoise{0.01 * kDegree, 300e-6 * inertial::kStandardGravity, 4.0e-05, 4.0e-03};
    o.rate_hz = 200.0;
    o.gyro_saturation_rad_s = 2000.0 * kDegree;
    o.accel_saturation_mps2 = 16.0 * inertial::kStandardGravity;
    o.initial_gyro_bias_sigma_rad_s = 5.0 * kDegree / 3.0;
    o.initial_accel_bias_sigma_mps2 = 0.080 * inertial::kStandardGravity / 3.0;
  } else {
    return std::nullopt;
  }
  return o;
}

SimulatedImu simulate_imu(const std::function<BodyKinematics(double t_s)>& truth, double start_s, double end_s,
                          const ImuSimulationOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "simulate_imu: invalid options (check is_valid first)");
  CAIRN_ASSERT(start_s <= end_s, "simulate_imu: start_s must not be after end_s");
  const std::int64_t period_ns = options.period_ns();
  const std::int64_t start_ns = std::llround(start_s * 1e9);
  const std::int64_t end_ns = std::llround(end_s * 1e9);
  const std::int64_t offset_ns = std::llround(options.time_offset_s * 1e9);
  const double dt_s = static_cast<double>(period_ns) * 1e-9;
  // Discrete-time sigmas of Kalibr's model: white noise sigma_d = sigma / sqrt(dt), bias step
  // sigma_bd = sigma_b sqrt(dt) (Forster et al. 2017, eq. 27 and the text after it).
  const double gyro_white = options.noise.gyro_noise_density / std::sqrt(dt_s);
  const double accel_white = options.noise.accel_noise_density / std::sqrt(dt_s);
  const double gyro_step = options.noise.gyro_random_walk * std::sqrt(dt_s);
  const double accel_step = options.noise.accel_random_walk * std::sqrt(dt_s);
  const Vector3 g_world(0.0, 0.0, -inertial::kStandardGravity);

  Random random(options.seed);
  SimulatedImu out;
  // Drawn whether or not a bias is given, so the noise that follows is the same either way.
  inertial::ImuBias bias;
  bias.gyro_rad_s = gaussian3(random, options.initial_gyro_bias_sigma_rad_s);
  bias.accel_mps2 = gaussian3(random, options.initial_accel_bias_sigma_mps2);
  if (options.initial_bias) bias = *options.initial_bias;
  out.initial_bias = bias;

  const std::int64_t count = (end_ns - start_ns) / period_ns + 1;
  out.samples.reserve(static_cast<std::size_t>(count));
  out.truth.reserve(static_cast<std::size_t>(count));
  for (std::int64_t k = 0; k < count; ++k) {
    const std::int64_t t_ns = start_ns + k * period_ns;
    const BodyKinematics body = truth(static_cast<double>(t_ns) * 1e-9);
    const Matrix3 R_world_body = body.T_world_body.rotation_matrix();
    inertial::ImuSample sample;
    sample.stamp = core::Timestamp::from_nanoseconds(t_ns + offset_ns);
    const Vector3 gyro_noise = gaussian3(random, gyro_white);
    const Vector3 accel_noise = gaussian3(random, accel_white);
    sample.gyro_rad_s = clip(body.omega_body_rad_s + bias.gyro_rad_s + gyro_noise, options.gyro_saturation_rad_s);
    sample.accel_mps2 = clip(R_world_body.transpose() * (body.a_world_mps2 - g_world) + bias.accel_mps2 + accel_noise,
                             options.accel_saturation_mps2);
    out.samples.push_back(sample);

    inertial::GroundTruthState state;
    state.stamp = core::Timestamp::from_nanoseconds(t_ns);
    state.state.T_world_body = body.T_world_body;
    state.state.v_world_mps = body.v_world_mps;
    state.bias = bias;
    out.truth.push_back(state);

    // The biases of the next sample: one random-walk step (drawn for every sample, the last too).
    bias.gyro_rad_s += gaussian3(random, gyro_step);
    bias.accel_mps2 += gaussian3(random, accel_step);
  }
  return out;
}

}  // namespace cairn::sim
