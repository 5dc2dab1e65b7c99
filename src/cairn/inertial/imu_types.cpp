#include "cairn/inertial/imu_types.hpp"

#include <cmath>

#include "cairn/core/problems.hpp"

namespace cairn::inertial {

bool ImuNoise::is_valid(std::string* why) const {
  core::Problems problems;
  problems.require_positive(gyro_noise_density, "gyro_noise_density");
  problems.require_positive(accel_noise_density, "accel_noise_density");
  problems.require_positive(gyro_random_walk, "gyro_random_walk");
  problems.require_positive(accel_random_walk, "accel_random_walk");
  return problems.report(why);
}

}  // namespace cairn::inertial
