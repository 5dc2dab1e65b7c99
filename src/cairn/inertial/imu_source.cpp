#include "cairn/inertial/imu_source.hpp"

#include <stdexcept>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_csv.hpp"

namespace cairn::inertial {
namespace {

namespace fs = std::filesystem;

bool is_file(const fs::path& path) {
  std::error_code error;
  return fs::is_regular_file(path, error);
}

// The folder holding the IMU's data.csv: the folder given (imu0/ inside a mav0 folder), or the
// file's folder. Empty for a bag's topic.
fs::path imu_folder(const ImuSourceRequest& request) {
  if (request.imu.empty()) return {};
  std::error_code error;
  if (fs::is_directory(request.imu, error)) {
    return !is_file(request.imu / "data.csv") && is_file(request.imu / "imu0" / "data.csv") ? request.imu / "imu0" : request.imu;
  }
  return request.imu.has_parent_path() ? request.imu.parent_path() : fs::path(".");
}

void read_samples(const ImuSourceRequest& request, ImuSource& input) {
  std::vector<std::string> warnings;
  if (!request.imu.empty()) {
    input.source = request.imu.string();
    input.samples = read_imu_file(request.imu, &warnings);
  } else if (!request.bag.empty() && !request.topic.empty()) {
    input.source = request.bag.string() + " topic " + request.topic;
    input.samples = read_imu_topic(request.bag, request.topic);
  } else {
    throw std::invalid_argument("no IMU: give an IMU file, or a bag and its sensor_msgs/Imu topic");
  }
  for (const std::string& w : warnings) input.notes.push_back(input.source + ": " + w);
}

// The calibration asked for, else sensor.yaml beside the data, else the ADIS16448's noise.
void read_calibration(const ImuSourceRequest& request, ImuSource& input) {
  fs::path file = request.calibration;
  if (file.empty() && !input.folder.empty() && is_file(input.folder / "sensor.yaml")) file = input.folder / "sensor.yaml";
  if (file.empty()) {
    input.notes.push_back("no IMU calibration (--imu-calibration, or sensor.yaml beside the IMU's data): EuRoC's "
                          "ADIS16448 noise taken, and the IMU as the body frame");
    return;
  }
  const ImuCalibration calibration = read_euroc_imu_calibration(file);
  input.calibration_file = file.string();
  input.noise = calibration.noise;
  input.T_body_imu = calibration.T_body_imu;
}

}  // namespace

std::filesystem::path sibling_sensor_yaml(const ImuSource& imu, const std::string& sensor) {
  if (imu.folder.empty()) return {};
  const fs::path beside = imu.folder.parent_path() / sensor / "sensor.yaml";
  return is_file(beside) ? beside : fs::path();
}

ImuSource read_imu_source(const ImuSourceRequest& request) {
  ImuInputOptions shift;
  shift.time_offset_s = request.time_offset_s;
  std::string why;
  if (!shift.is_valid(&why)) throw std::invalid_argument("--imu-time-offset: " + why);
  ImuSource input;
  input.time_offset_s = request.time_offset_s;
  read_samples(request, input);
  input.folder = imu_folder(request);
  read_calibration(request, input);
  input.checks = check_imu_data(input.samples, ImuInputOptions{});
  // Only the clock moves: T_body_imu stays out of the samples (the pipelines keep the IMU's frame).
  if (request.time_offset_s != 0.0) input.samples = apply_imu_input(input.samples, shift);
  return input;
}

}  // namespace cairn::inertial
