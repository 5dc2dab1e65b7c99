#include "cairn/lidar3d/inertial_input.hpp"

#include <stdexcept>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_csv.hpp"

namespace cairn::lidar3d {
namespace {

namespace fs = std::filesystem;

bool is_file(const fs::path& path) {
  std::error_code error;
  return fs::is_regular_file(path, error);
}

// The folder holding the IMU's data.csv: the folder given (imu0/ inside a mav0 folder), or the
// file's folder. Empty for a bag's topic.
fs::path imu_folder(const InertialInputRequest& request) {
  if (request.imu.empty()) return {};
  std::error_code error;
  if (fs::is_directory(request.imu, error)) {
    return !is_file(request.imu / "data.csv") && is_file(request.imu / "imu0" / "data.csv") ? request.imu / "imu0" : request.imu;
  }
  return request.imu.has_parent_path() ? request.imu.parent_path() : fs::path(".");
}

void read_samples(const InertialInputRequest& request, InertialInput& input) {
  std::vector<std::string> warnings;
  if (!request.imu.empty()) {
    input.source = request.imu.string();
    input.samples = inertial::read_imu_file(request.imu, &warnings);
  } else if (!request.bag.empty() && !request.topic.empty()) {
    input.source = request.bag.string() + " topic " + request.topic;
    input.samples = inertial::read_imu_topic(request.bag, request.topic);
  } else {
    throw std::invalid_argument("no IMU: give an IMU file, or a bag and its sensor_msgs/Imu topic");
  }
  for (const std::string& w : warnings) input.notes.push_back(input.source + ": " + w);
}

// --imu-calibration, else sensor.yaml beside the data, else the ADIS16448's noise.
void read_calibration(const InertialInputRequest& request, const fs::path& folder, InertialInput& input) {
  fs::path file = request.calibration;
  if (file.empty() && !folder.empty() && is_file(folder / "sensor.yaml")) file = folder / "sensor.yaml";
  if (file.empty()) {
    input.notes.push_back("no IMU calibration (--imu-calibration, or sensor.yaml beside the IMU's data): EuRoC's "
                          "ADIS16448 noise taken, and the IMU as the body frame");
    return;
  }
  const inertial::ImuCalibration calibration = inertial::read_euroc_imu_calibration(file);
  input.calibration_file = file.string();
  input.noise = calibration.noise;
  input.T_body_imu = calibration.T_body_imu;
}

// --lidar-extrinsic, else lidar0/sensor.yaml beside the IMU's folder, else the identity.
void read_lidar_extrinsic(const InertialInputRequest& request, const fs::path& folder, InertialInput& input) {
  fs::path file = request.lidar_extrinsic;
  if (file.empty() && !folder.empty()) {
    const fs::path beside = folder.parent_path() / "lidar0" / "sensor.yaml";
    if (is_file(beside)) file = beside;
  }
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
  inertial::ImuInputOptions shift;
  shift.time_offset_s = request.time_offset_s;
  std::string why;
  if (!shift.is_valid(&why)) throw std::invalid_argument("--imu-time-offset: " + why);
  InertialInput input;
  input.time_offset_s = request.time_offset_s;
  read_samples(request, input);
  const fs::path folder = imu_folder(request);
  read_calibration(request, folder, input);
  read_lidar_extrinsic(request, folder, input);
  input.checks = inertial::check_imu_data(input.samples, inertial::ImuInputOptions{});
  // Only the clock moves: T_body_imu stays out of the samples (see the file comment).
  if (request.time_offset_s != 0.0) input.samples = inertial::apply_imu_input(input.samples, shift);
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
