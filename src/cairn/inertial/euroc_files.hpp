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
/// through io's output_file (written whole or not at all, docs/conventions.md "Outputs").

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
/// are checked as they are read: finite numbers, 7 columns, strictly increasing stamps.
std::vector<ImuSample> read_euroc_imu(const std::filesystem::path& path);
void write_euroc_imu(const std::filesystem::path& path, const std::vector<ImuSample>& samples);

/// Reads / writes `imu0/sensor.yaml`.
ImuCalibration read_euroc_imu_calibration(const std::filesystem::path& path);
void write_euroc_imu_calibration(const std::filesystem::path& path, const ImuCalibration& calibration);

/// Reads / writes a state ground-truth file (17 columns, strictly increasing stamps).
std::vector<GroundTruthState> read_euroc_ground_truth(const std::filesystem::path& path);
void write_euroc_ground_truth(const std::filesystem::path& path, const std::vector<GroundTruthState>& states);

}  // namespace cairn::inertial
