#include "cairn/sim/imu_outputs.hpp"

#include <filesystem>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/sim/street_run.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;


nlohmann::json bias_json(const inertial::ImuBias& b) {
  return {{"gyro_rad_s", {b.gyro_rad_s.x(), b.gyro_rad_s.y(), b.gyro_rad_s.z()}},
          {"accel_mps2", {b.accel_mps2.x(), b.accel_mps2.y(), b.accel_mps2.z()}}};
}

/// lidar0/sensor.yaml: EuRoC's sensor.yaml layout (as cam0's) for the LiDAR.
void write_lidar_sensor_yaml(const std::string& path, const core::SE3& T_body_lidar, double rate_hz) {
  io::write_output(path, [&](std::ostream& out) {
    std::string text =
        "# cairn simulate: the 3D LiDAR in the body frame (the IMU frame: imu0/sensor.yaml T_BS is the identity)\n"
        "sensor_type: lidar\ncomment: spinning LiDAR, scans in scans/ or velodyne/\n\n"
        "# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n  data: [";
    const std::vector<double> values = row_major(T_body_lidar);
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (i > 0) text += (i % 4 == 0) ? ",\n         " : ", ";
      io::append_number(text, values[i]);
    }
    text += "]\n\nrate_hz: ";
    io::append_number(text, rate_hz);
    text += '\n';
    out << text;
  });
}

}  // namespace

std::vector<double> row_major(const core::SE3& T) {
  const Matrix4 M = T.matrix();
  std::vector<double> out;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out.push_back(M(r, c));
  }
  return out;
}

core::SE3 T_body_lidar(const Lidar3DOptions& lidar) { return lidar_pose(core::SE2(), lidar); }

std::vector<std::string> write_imu_outputs(const SimulationResult& result, const Scenario& scenario,
                                           const std::string& directory) {
  std::vector<std::string> files;
  auto path_of = [&](const std::string& name) {
    files.push_back(name);
    return fs::path(directory) / name;
  };
  for (const char* folder : {"imu0", "state_groundtruth_estimate0", "lidar0"}) {
    fs::create_directories(fs::path(directory) / folder);
  }
  inertial::write_euroc_imu(path_of("imu0/data.csv"), result.imu.samples);
  inertial::ImuCalibration calibration;
  calibration.noise = scenario.imu.noise;
  calibration.rate_hz = 1e9 / static_cast<double>(scenario.imu.period_ns());
  calibration.T_body_imu = core::SE3();
  inertial::write_euroc_imu_calibration(path_of("imu0/sensor.yaml"), calibration);
  inertial::write_euroc_ground_truth(path_of("state_groundtruth_estimate0/data.csv"), result.imu.truth);
  write_lidar_sensor_yaml(path_of("lidar0/sensor.yaml").string(), T_body_lidar(scenario.lidar3d),
                          1.0 / scenario.lidar3d.period_s);
  return files;
}

nlohmann::json imu_manifest(const SimulationResult& result, const Scenario& scenario) {
  const ImuSimulationOptions& o = scenario.imu;
  nlohmann::json j;
  j["preset"] = scenario.imu_preset;
  j["model"] = "Kalibr's IMU noise model (Forster et al., T-RO 2017, eq. 27): gyro = omega_body + b_g + eta_g, "
               "accel = R_world_body^T (a_world - g_world) + b_a + eta_a, g_world = (0, 0, -9.80665); eta discrete "
               "white with sigma = density sqrt(rate_hz); b[k+1] = b[k] + random_walk sqrt(dt) n; each axis clipped "
               "to +-saturation (0: none)";
  j["rate_hz"] = 1e9 / static_cast<double>(o.period_ns());
  j["samples"] = result.imu.samples.size();
  j["noise"] = {{"gyroscope_noise_density", o.noise.gyro_noise_density},
                {"gyroscope_random_walk", o.noise.gyro_random_walk},
                {"accelerometer_noise_density", o.noise.accel_noise_density},
                {"accelerometer_random_walk", o.noise.accel_random_walk}};
  j["gyro_saturation_rad_s"] = o.gyro_saturation_rad_s;
  j["accel_saturation_mps2"] = o.accel_saturation_mps2;
  j["time_offset_s"] = o.time_offset_s;
  j["initial_bias"] = bias_json(result.imu.initial_bias);
  if (!result.imu.truth.empty()) j["final_bias"] = bias_json(result.imu.truth.back().bias);
  j["clocks"] = "imu0/data.csv: the IMU's clock = true time + time_offset_s; state_groundtruth_estimate0/data.csv, "
                "times.txt, ground_truth.tum: true time";
  j["frames"] = {{"body", "x forward, y left, z up; origin on the ground (z = 0) at the ground-truth body pose"},
                 {"T_body_imu", row_major(core::SE3())},
                 {"T_body_lidar", row_major(T_body_lidar(scenario.lidar3d))},
                 {"T_body_camera", row_major(scenario.camera.T_body_camera())},
                 {"layout", "4x4 row-major; T_a_b maps points from frame b into frame a"}};
  j["files"] = {"imu0/data.csv", "imu0/sensor.yaml", "state_groundtruth_estimate0/data.csv", "lidar0/sensor.yaml"};
  return j;
}

}  // namespace cairn::sim
