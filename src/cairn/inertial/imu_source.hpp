#pragma once
/// \file
/// An IMU as a pipeline's user names it (`cairn slam3d --imu`, `cairn vslam --imu`): the samples
/// (EuRoC's imu0 folder or data.csv, a plain IMU CSV, or sensor_msgs/Imu from a bag: imu_csv.hpp),
/// the noise (an EuRoC/Kalibr sensor.yaml: euroc_files.hpp; default: sensor.yaml beside the data,
/// else EuRoC's ADIS16448) and a constant time offset onto the other sensor's clock, each default
/// taken said in a note. The other sensor's extrinsic is the pipeline's (lidar3d/inertial_input,
/// vslam/inertial_input).

#include <filesystem>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/inertial/imu_input.hpp"
#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

struct ImuSourceRequest {
  /// An EuRoC imu0 (or mav0) folder or imu0/data.csv, a plain IMU CSV, or a bag (its only
  /// sensor_msgs/Imu topic). Empty when the IMU is `topic` of `bag`.
  std::filesystem::path imu;
  /// A bag and its sensor_msgs/Imu topic, used when `imu` is empty.
  std::filesystem::path bag;
  std::string topic;
  /// A sensor.yaml with the noise densities and random walks (and T_BS). Empty: sensor.yaml beside
  /// the IMU's data (its folder, or imu0/ in a mav0 folder) when there is one, else EuRoC's
  /// ADIS16448 values (ImuNoise's defaults).
  std::filesystem::path calibration;
  /// Added to every IMU stamp to put it on the other sensor's clock, s (finite, |offset| <= 9.2e9).
  double time_offset_s = 0.0;
};

struct ImuSource {
  std::string source;            ///< the IMU's file, folder or bag as read; "BAG topic T" for a topic
  std::string calibration_file;  ///< empty: ADIS16448 defaults
  /// IMU frame, stamps on the other sensor's clock (time_offset_s added), strictly increasing.
  std::vector<ImuSample> samples;
  /// Rates, gaps, saturation and statistics of the samples as recorded (check_imu_data).
  ImuDataReport checks;
  ImuNoise noise;
  core::SE3 T_body_imu;  ///< the calibration's T_BS (identity without one)
  double time_offset_s = 0.0;
  /// The folder holding the IMU's data (where sensor.yaml and the other sensors' folders are
  /// looked for); empty for a bag's topic.
  std::filesystem::path folder;
  /// Defaults taken and readers' warnings, one sentence each.
  std::vector<std::string> notes;
};

/// `<sensor>/sensor.yaml` beside the IMU's folder (EuRoC's mav0 layout: lidar0/, cam0/ beside
/// imu0/) when that file exists; empty otherwise (or for a bag's topic).
std::filesystem::path sibling_sensor_yaml(const ImuSource& imu, const std::string& sensor);

/// Reads the IMU of `request`. Throws io::ParseError (file and line, or bag, topic and message)
/// for bad data or calibration files, std::invalid_argument for a bad time offset or a request
/// naming no IMU.
ImuSource read_imu_source(const ImuSourceRequest& request);

}  // namespace cairn::inertial
