#include "cairn/navigation/config.hpp"

namespace cairn::navigation {

io::Parameters parameters(GnssInertialOdometryOptions& o) {
  return {
      {"imu", "gyro_noise_density", &o.noise.gyro_noise_density, "rad/s/sqrt(Hz): the gyroscope's white noise (a message covariance c at rate f: sqrt(c / f))"},
      {"imu", "accel_noise_density", &o.noise.accel_noise_density, "m/s^2/sqrt(Hz): the accelerometer's white noise"},
      {"imu", "gyro_random_walk", &o.noise.gyro_random_walk, "rad/s^2/sqrt(Hz): the gyroscope bias' random walk"},
      {"imu", "accel_random_walk", &o.noise.accel_random_walk, "m/s^3/sqrt(Hz): the accelerometer bias' random walk"},
      {"imu", "gravity_mps2", &o.gravity_mps2, "magnitude of gravity (also the static initialisation's)"},
      {"imu", "initialization_window_s", &o.initialization.window_s, "static initialisation: the IMU's first seconds it looks at"},
      {"imu", "initialization_block_s", &o.initialization.block_s, "... still when the means of its blocks this long ..."},
      {"imu", "initialization_gyro_block_spread_max_rad_s", &o.initialization.gyro_block_spread_max_rad_s, "... agree with the window's mean within this (every gyroscope axis) ..."},
      {"imu", "initialization_accel_block_spread_max_mps2", &o.initialization.accel_block_spread_max_mps2, "... and this (every accelerometer axis)"},
      {"window", "state_period_s", &o.state_period_s, "time between states, in [0.01, 1]"},
      {"window", "window_states", &o.window_states, "states in the sliding window (>= 3)"},
      {"window", "latency_s", &o.latency_s, "how late a measurement may arrive after a later one of another stream"},
      {"window", "max_iterations", &o.max_iterations, "Levenberg-Marquardt iterations per solve"},
      {"priors", "initial_velocity_sigma_mps", &o.initial_velocity_sigma_mps, "first state's velocity"},
      {"priors", "initial_gyro_bias_sigma_rad_s", &o.initial_gyro_bias_sigma_rad_s, "first gyroscope bias, when the start is not still (a still start measures it)"},
      {"priors", "initial_accel_bias_sigma_mps2", &o.initial_accel_bias_sigma_mps2, "first accelerometer bias"},
      {"priors", "initial_tilt_sigma_rad", &o.initial_tilt_sigma_rad, "first roll and pitch"},
      {"wheels", "speed_sigma_mps", &o.wheel_speed_sigma_mps, "forward speed's sigma when a message has no variance"},
      {"wheels", "min_speed_sigma_mps", &o.min_wheel_speed_sigma_mps, "floor on any message's speed sigma"},
      {"wheels", "nonholonomic_sigma_mps", &o.nonholonomic_sigma_mps, "the vehicle's lateral and vertical speed (zero, give or take this)"},
      {"wheels", "max_gap_s", &o.max_wheel_gap_s, "a speed is interpolated to a state only between messages this close"},
      {"gnss", "use_altitude", &o.use_gnss_altitude, "use the fixes' altitude (false: horizontal fixes only)"},
      {"gnss", "default_sigma_horizontal_m", &o.gnss.default_sigma_horizontal_m, "a fix without a covariance: horizontal standard deviation"},
      {"gnss", "default_sigma_vertical_m", &o.gnss.default_sigma_vertical_m, "... and vertical"},
      {"gnss", "min_sigma_m", &o.gnss.min_sigma_m, "floor on a fix's standard deviation along every axis"},
      {"gnss", "outlier_probability", &o.outliers.probability, "a fix beyond this chi-square(3) quantile is an outlier"},
      {"gnss", "dropout_gap_s", &o.outliers.max_gap_s, "a gap between fixes longer than this is a dropout"},
      {"gnss", "alignment_min_spread_m", &o.yaw.min_spread_m, "yaw counts as observable once the path's RMS horizontal spread reaches this"},
  };
}

void sync_gravity(GnssInertialOdometryOptions& options) { options.initialization.gravity_mps2 = options.gravity_mps2; }

const io::Configuration<GnssInertialOdometryOptions>& configuration() {
  static const io::Configuration<GnssInertialOdometryOptions> c(&parameters, "navigate",
                                                                "# cairn navigate configuration: every key, its value and what it means.");
  return c;
}

}  // namespace cairn::navigation
