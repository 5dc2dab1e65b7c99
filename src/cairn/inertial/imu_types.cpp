#include "cairn/inertial/imu_types.hpp"

#include <cmath>

#include "cairn/core/problems.hpp"

namespace cairn::inertial {

bool ImuNoise::is_valid(std::string* why) const {
  core::Problems problems;
  const auto positive = [&](double value, const char* name) {
    if (!(std::isfinite(value) && value > 0.0)) problems.add(std::string(name) + " must be finite and > 0");
  };
  positive(gyro_noise_density, "gyro_noise_density");
  positive(accel_noise_density, "accel_noise_density");
  positive(gyro_random_walk, "gyro_random_walk");
  positive(accel_random_walk, "accel_random_walk");
  return problems.report(why);
}

}  // namespace cairn::inertial
