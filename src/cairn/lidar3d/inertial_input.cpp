#include "cairn/lidar3d/inertial_input.hpp"

#include <stdexcept>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_source.hpp"

namespace cairn::lidar3d {
namespace {

// --lidar-extrinsic, else lidar0/sensor.yaml beside the IMU's folder, else the identity.
void read_lidar_extrinsic(const InertialInputRequest& request, const inertial::ImuSource& imu, InertialInput& input) {
  std::filesystem::path file = request.lidar_extrinsic;
  if (file.empty()) file = inertial::sibling_sensor_yaml(imu, "lidar0");
  if (file.empty()) {
    input.notes.push_back("no LiDAR extrinsic (--lidar-extrinsic, or lidar0/sensor.yaml beside the IMU's folder): the "
                          "LiDAR taken to be at the IMU (identity)");
    return;
  }
  input.T_body_lidar = inertial::read_euroc_T_BS(file);
  input.lidar_extrinsic_file = file.string();
}

}  // namespace

InertialInput read_inertial_input(const InertialInputRequest& request) {
  inertial::ImuSource source = inertial::read_imu_source(request.imu);
  InertialInput input;
  input.source = std::move(source.source);
  input.calibration_file = std::move(source.calibration_file);
  input.samples = std::move(source.samples);
  input.checks = std::move(source.checks);
  input.noise = source.noise;
  input.T_body_imu = source.T_body_imu;
  input.time_offset_s = source.time_offset_s;
  input.notes = std::move(source.notes);
  read_lidar_extrinsic(request, source, input);
  return input;
}

InertialFusionOptions inertial_fusion_options(const InertialFusionOptions& configured, const InertialInput& input) {
  InertialFusionOptions options = configured;
  options.noise = input.noise;
  options.T_imu_lidar = input.T_imu_lidar();
  options.initialization.gravity_mps2 = options.gravity_mps2;
  return options;
}

bool prepare_for_inertial(LidarSlamOptions& options) {
  const bool was_off = !options.odometry.registration.remap_degenerate_directions;
  options.odometry.registration.remap_degenerate_directions = true;
  return was_off;
}

}  // namespace cairn::lidar3d
