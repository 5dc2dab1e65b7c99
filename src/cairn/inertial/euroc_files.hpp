#pragma once
/// \file
/// EuRoC MAV's ASL files for an IMU (Burri et al., "The EuRoC micro aerial vehicle datasets",
/// IJRR 35(10), 2016; the layout of mav0/ in every EuRoC sequence), read and written:
///  * `imu0/data.csv`: `#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_z [m s^-2]`;
///  * `imu0/sensor.yaml`: rate, noise densities, random walks, T_BS (the IMU in the body frame);
///  * `state_groundtruth_estimate0/data.csv`: time [ns], p_RS_R xyz [m], q_RS wxyz, v_RS_R xyz
///    [m/s], b_w_RS_S xyz [rad/s], b_a_RS_S xyz [m/s^2] (also OpenVINS' re-estimated ground
///    truth files, ov_data/euroc_mav/*.csv, which use the same columns).
/// Readers throw io::ParseError naming file, line, what was expected and what was found; writers go
/// through io's output_file (written whole or not at all, docs/conventions.md "Outputs") and write
/// stamps as integer nanoseconds and numbers in their shortest exact form, so that what they write
/// reads back bit for bit (T_BS: to rounding, see write_euroc_imu_calibration). Format details and
/// strictness: docs/formats.md, "IMU data".

#include <filesystem>
#include <string>
#include <vector>

#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

/// imu0/sensor.yaml's content.
struct ImuCalibration {
  ImuNoise noise;
  double rate_hz = 200.0;
  core::SE3 T_body_imu;  ///< EuRoC's T_BS
};

/// One row of a state ground-truth file.
struct GroundTruthState {
  core::Timestamp stamp;
  NavState state;  ///< T_world_body and v_world_mps
  ImuBias bias;
};

/// Reads `imu0/data.csv` (also accepted: the imu0 folder or the mav0 folder holding it). Samples
/// are checked as they are read: finite numbers, 7 columns, strictly increasing stamps (a
/// duplicated or earlier stamp is an error, naming both lines). Lines starting with '#' and blank
/// lines are skipped; a file without a sample is an error.
std::vector<ImuSample> read_euroc_imu(const std::filesystem::path& path);
/// The same; when the last line has no newline (a copy cut short may end inside a number that
/// still parses), a warning saying so is appended to `*warnings` (when given).
std::vector<ImuSample> read_euroc_imu(const std::filesystem::path& path, std::vector<std::string>* warnings);
/// Throws io::ParseError (naming `path`, line 0) for an empty list, a non-finite value or stamps
/// that do not increase: what cannot be read back is not written.
void write_euroc_imu(const std::filesystem::path& path, const std::vector<ImuSample>& samples);

/// Reads `imu0/sensor.yaml` (also accepted: the imu0 or mav0 folder). Required keys:
/// gyroscope_noise_density, gyroscope_random_walk, accelerometer_noise_density,
/// accelerometer_random_walk (finite, > 0) and the rate, `rate_hz` (EuRoC; Kalibr's imu.yaml says
/// `update_rate`). `T_BS` {rows: 4, cols: 4, data: [16 numbers, row-major]} must be a rigid
/// transform (|R^T R - I| <= 1e-6, det R > 0, last row 0 0 0 1); without it (Kalibr's imu.yaml)
/// T_body_imu is the identity. Other keys (sensor_type, comment, rostopic) are ignored. OpenCV's
/// `%YAML:1.0` first line is accepted. Errors name the key and its line.
ImuCalibration read_euroc_imu_calibration(const std::filesystem::path& path);

/// Any sensor's extrinsic from EuRoC's sensor.yaml layout (mav0/<sensor>/sensor.yaml, also the
/// simulator's lidar0/sensor.yaml): `T_BS`, the sensor in the body frame, {rows: 4, cols: 4,
/// data: [16 numbers, row-major]}, of the sensor.yaml at `path` (or in the folder `path`); other
/// keys are ignored. T_BS must be rigid: last row 0 0 0 1, rotation block orthonormal to 1e-6 with
/// det > 0. Throws io::ParseError naming the file and line for a file that is missing, not YAML,
/// larger than 1 MiB, without T_BS, or with a bad T_BS (the same checks as the IMU's T_BS above).
core::SE3 read_euroc_T_BS(const std::filesystem::path& path);
/// Writes EuRoC's keys. T_BS is written as its 4x4 matrix (the format's), so its rotation reads
/// back to rounding (about 1e-16), not bit for bit; the rate and noise values read back exactly.
void write_euroc_imu_calibration(const std::filesystem::path& path, const ImuCalibration& calibration);

/// Reads / writes a state ground-truth file (17 columns, strictly increasing stamps, quaternion w
/// first with a norm within 1e-2 of 1, normalised on reading; the 6-decimal files published
/// are 1e-6 from unit).
std::vector<GroundTruthState> read_euroc_ground_truth(const std::filesystem::path& path);
void write_euroc_ground_truth(const std::filesystem::path& path, const std::vector<GroundTruthState>& states);

}  // namespace cairn::inertial
