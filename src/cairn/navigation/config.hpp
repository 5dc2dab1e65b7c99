#pragma once
/// \file
/// The navigation configuration as YAML (`cairn navigate --print-config`, `--config`, `--set`): every
/// key of GnssInertialOdometryOptions under a section, each with what it means. The IMU's noise is a
/// section too (a bag's sensor_msgs/Imu carries covariances, not densities); the frames (the IMU in
/// the vehicle, the antenna) are flags of the command, not keys. report.json's "options" is
/// configuration().json of the options in effect.
///
///   imu:
///     gyro_noise_density: 3.65e-3
///   wheels:
///     nonholonomic_sigma_mps: 0.1

#include "cairn/io/parameters.hpp"
#include "cairn/navigation/gnss_inertial_odometry.hpp"

namespace cairn::navigation {

/// The keys: pointers into `options`, each with its section, name and meaning. `imu.gravity_mps2`
/// sets both gravity_mps2 and initialization.gravity_mps2 (call sync_gravity after setting keys).
io::Parameters parameters(GnssInertialOdometryOptions& options);
/// set / load / yaml (--print-config) / json (report.json's "options") over parameters().
const io::Configuration<GnssInertialOdometryOptions>& configuration();
/// The static initialisation's gravity follows the estimator's.
void sync_gravity(GnssInertialOdometryOptions& options);

}  // namespace cairn::navigation
