// `cairn slam3d --imu` end to end on the simulator's tunnel (`cairn simulate tunnel-3d`: scans,
// times, poses, and the IMU in EuRoC's layout: imu0/data.csv, imu0/sensor.yaml, lidar0/sensor.yaml,
// state_groundtruth_estimate0/data.csv). Expected values come from the simulator's files (the
// ground truth, the true biases, the LiDAR's mount, the number of IMU rows), never from the run.
// Loop closure is off: the verification of the tunnel's look-alike places costs seconds per run
// and is not what is tested here.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"

namespace {

namespace fs = std::filesystem;

using Result = cairn::test::CliResult;
using cairn::test::csv_rows;
using cairn::test::slurp;

fs::path scratch() { return cairn::test::scratch_folder("slam3d_imu_test"); }

Result cairn_run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string q(const fs::path& p) { return cairn::test::quoted(p); }

// The simulated tunnel (seed 1), written once per test program.
const fs::path& tunnel() {
  static const fs::path dir = [] {
    const fs::path d = scratch() / "tunnel";
    fs::remove_all(d);
    const Result r = cairn_run("simulate tunnel-3d --seed 1 -q --out " + q(d));
    EXPECT_EQ(r.status, 0) << r.err;
    return d;
  }();
  return dir;
}

// slam3d over the tunnel's scans with its times and ground truth, odometry only, into `out`.
Result slam3d(const fs::path& out, const std::string& extra) {
  fs::remove_all(out);
  const fs::path d = tunnel();
  return cairn_run("slam3d " + q(d / "scans") + " --times " + q(d / "times.txt") + " --ground-truth " + q(d / "poses.txt") +
                   " --ground-truth-format kitti --no-loop-closure -q " + extra + " --out " + q(out));
}

// Lines of a EuRoC data.csv that are samples (not the '#' header).
std::size_t sample_lines(const fs::path& file) {
  std::size_t n = 0;
  for (const auto& row : csv_rows(file)) n += !row.empty() && !row[0].empty() && row[0][0] != '#' ? 1 : 0;
  return n;
}

// The true biases of the last row of state_groundtruth_estimate0/data.csv: gyro (columns 11-13).
std::vector<double> true_final_gyro_bias() {
  const auto rows = csv_rows(tunnel() / "state_groundtruth_estimate0" / "data.csv");
  const std::vector<std::string>& last = rows.back();
  return {std::stod(last[11]), std::stod(last[12]), std::stod(last[13])};
}

// The whole tunnel with the LOAM front end (the default for the simulator's scans, which carry
// rings): with the IMU every output is written, the report's inertial section is filled, and the
// end-point error is a fraction of LiDAR-only's (docs/lidar3d.md, "LiDAR-inertial (--imu)").
TEST(Slam3dImuCli, TunnelWithImuWritesInertialOutputsAndEndsCloserThanLidarOnly) {
  const fs::path with_imu = scratch() / "loam_imu";
  const fs::path lidar_only = scratch() / "loam_only";
  Result r = slam3d(with_imu, "--imu " + q(tunnel() / "imu0"));
  ASSERT_EQ(r.status, 0) << r.err;
  r = slam3d(lidar_only, "");
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* file : {"trajectory.tum", "trajectory.kitti", "map.ply", "map.png", "report.json", "inertial_states.csv", "inertial.png"}) {
    EXPECT_TRUE(fs::exists(with_imu / file)) << file;
  }
  // A LiDAR-only run writes what it wrote before the IMU existed, and nothing of the IMU.
  EXPECT_FALSE(fs::exists(lidar_only / "inertial_states.csv"));
  EXPECT_FALSE(fs::exists(lidar_only / "inertial.png"));
  const nlohmann::json report = nlohmann::json::parse(slurp(with_imu / "report.json"));
  const nlohmann::json lidar = nlohmann::json::parse(slurp(lidar_only / "report.json"));
  EXPECT_FALSE(lidar.contains("inertial"));
  EXPECT_FALSE(lidar["options"].contains("imu"));
  EXPECT_EQ(lidar["options"]["registration"]["remap_degenerate_directions"], false);

  const double e_imu = report["ground_truth"]["end_point_error_m"].get<double>();
  const double e_lidar = lidar["ground_truth"]["end_point_error_m"].get<double>();
  const double path = report["ground_truth"]["path_length_m"].get<double>();
  std::printf("tunnel-3d, LOAM: end-point error with the IMU %.2f m, LiDAR-only %.2f m, of %.0f m\n", e_imu, e_lidar, path);
  // The command's check: the IMU it was given carries the axis (seed 1: 10.1 m against 13.6 m). The
  // accuracy over seeds is the library's test (LidarInertialSimulation.
  // CarriesTheTunnelAndHalvesLidarOnlyEndPointErrorOverFourSeeds); one seed's end moves by metres with the IMU's
  // bias random walk alone (docs/lidar3d.md, "LiDAR-inertial"), so no percentage is asserted on it.
  EXPECT_LT(e_imu, e_lidar);

  const std::string inertial_png = slurp(with_imu / "inertial.png");
  EXPECT_EQ(inertial_png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));

  const nlohmann::json& in = report["inertial"];
  EXPECT_EQ(in["checks"]["samples"].get<std::size_t>(), sample_lines(tunnel() / "imu0" / "data.csv"));
  EXPECT_EQ(fs::path(in["calibration_file"].get<std::string>()), tunnel() / "imu0" / "sensor.yaml");
  EXPECT_EQ(fs::path(in["lidar_extrinsic_file"].get<std::string>()), tunnel() / "lidar0" / "sensor.yaml");
  // The simulator's LiDAR: 1.8 m straight above the IMU (docs/simulation.md, lidar3d.mount_height_m).
  const nlohmann::json& t = in["T_imu_lidar"]["t"];
  EXPECT_NEAR(t[0].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(t[1].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(t[2].get<double>(), 1.8, 1e-12);
  EXPECT_EQ(report["options"]["registration"]["remap_degenerate_directions"], true);
  EXPECT_TRUE(report["options"]["imu"].contains("window_states"));
  EXPECT_TRUE(in["initialization"].is_object());

  // Every scan whose sweep the IMU covered is fused: all but the last (its sweep ends after the
  // simulated IMU's last sample).
  const std::size_t scans = report["scans"].size();
  const nlohmann::json& c = in["consistency"];
  EXPECT_EQ(c["fused_scans"].get<std::size_t>() + c["scans_without_prediction"].get<std::size_t>(), scans);
  EXPECT_GE(c["fused_scans"].get<std::size_t>(), scans - 1);
  EXPECT_LE(c["median_chi2"].get<double>(), c["p90_chi2"].get<double>());
  // A registration consistent with the IMU has chi2 of the order of its 6 dof.
  EXPECT_LT(c["median_chi2"].get<double>(), 6.0);
  // Inside the tunnel (out of range of both portals: scans 187-236, manifest.json) every
  // registration is degenerate along the axis and the IMU carries it.
  EXPECT_GE(c["degenerate_scans_carried_by_imu"].get<std::size_t>(), 50u);
  // The gyro bias is observable on any drive: within 1e-3 rad/s of the simulator's true one.
  const std::vector<double> truth = true_final_gyro_bias();
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(in["final"]["gyro_bias_rad_s"][a].get<double>(), truth[static_cast<std::size_t>(a)], 1e-3) << a;
  }

  // inertial_states.csv: a header, one row per fused scan, 18 fields of finite numbers.
  const auto rows = csv_rows(with_imu / "inertial_states.csv");
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows[0].size(), 18u);
  EXPECT_EQ(rows[0][1], "time_s");
  EXPECT_EQ(rows.size() - 1, c["fused_scans"].get<std::size_t>());
  std::size_t degenerate = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 18u) << i;
    for (const std::string& field : rows[i]) EXPECT_TRUE(std::isfinite(std::stod(field))) << i << ": " << field;
    degenerate += rows[i][17] == "1" ? 1 : 0;
  }
  EXPECT_EQ(degenerate, c["degenerate_scans_carried_by_imu"].get<std::size_t>());
}

// Asked for by issue 38 and not met yet, measured (seed 1, --no-loop-closure): with the dense front
// end the IMU makes the tunnel worse, end-point error 375 m against 171 m LiDAR-only (80 scans:
// 14.9 m against 3.3 m). The tunnel starts from rest accelerating at 1.5 m/s^2, which the static
// initialisation takes for stillness with an 8.7 degree tilt; the dense front end is degenerate
// from scan 40 on, too early for the registrations to correct the tilt, and the prediction then
// decelerates by the leaked gravity (about 0.4 m/s^2). Enable when the initialisation is fixed.
TEST(Slam3dImuCli, DISABLED_DenseFrontEndWithImuEndsCloserThanWithout) {
  const fs::path with_imu = scratch() / "dense_imu";
  const fs::path lidar_only = scratch() / "dense_only";
  Result r = slam3d(with_imu, "--front-end dense --imu " + q(tunnel() / "imu0"));
  ASSERT_EQ(r.status, 0) << r.err;
  r = slam3d(lidar_only, "--front-end dense");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(with_imu / "report.json"));
  const nlohmann::json lidar = nlohmann::json::parse(slurp(lidar_only / "report.json"));
  EXPECT_EQ(report["inertial"]["remap_degenerate_directions_forced"], true);
  EXPECT_LT(report["ground_truth"]["end_point_error_m"].get<double>(), lidar["ground_truth"]["end_point_error_m"].get<double>());
}

// Flags that do not go together are usage errors (status 2), found before any work.
TEST(Slam3dImuCli, BadFlagCombinationsAreUsageErrors) {
  const fs::path out = scratch() / "o_usage";
  fs::remove_all(out);
  const std::string scans = q(tunnel() / "scans") + " --times " + q(tunnel() / "times.txt") + " --out " + q(out);
  const std::string imu = q(tunnel() / "imu0");
  const std::string yaml = q(tunnel() / "imu0" / "sensor.yaml");
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {"--imu-topic /imu", "SCANS are not a bag"},
           {"--imu " + imu + " --imu-topic /imu", "--imu and --imu-topic"},
           {"--imu-calibration " + yaml, "--imu-calibration goes with --imu"},
           {"--lidar-extrinsic " + yaml, "--lidar-extrinsic goes with --imu"},
           {"--imu-time-offset 0.5", "--imu-time-offset goes with --imu"},
           {"--imu " + imu + " --set imu.window_states=1", "window_states must be >= 2"}}) {
    const Result r = cairn_run("slam3d " + scans + " " + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
}

// --print-config lists the imu section; with --imu it shows the remapping the IMU turns on.
TEST(Slam3dImuCli, PrintConfigHasTheImuSection) {
  Result r = cairn_run("slam3d --print-config");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\nimu:\n  window_states: 10  #"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  remap_degenerate_directions: false  #"), std::string::npos) << r.out;
  r = cairn_run("slam3d --print-config --imu " + q(tunnel() / "imu0") + " --set imu.contradiction_chi2=30");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\n  remap_degenerate_directions: true  #"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  contradiction_chi2: 30  #"), std::string::npos) << r.out;
}

// Hostile IMU input: a NaN in the IMU file stops the run with file:line and writes nothing; so
// does a LiDAR extrinsic that is not a rigid transform.
TEST(Slam3dImuCli, BadImuFilesStopWithFileAndLine) {
  const fs::path dir = scratch() / "bad_imu" / "imu0";
  fs::remove_all(dir.parent_path());
  fs::create_directories(dir);
  {
    std::istringstream lines(slurp(tunnel() / "imu0" / "data.csv"));
    std::ofstream csv(dir / "data.csv");
    std::string line;
    for (int k = 1; k <= 50 && std::getline(lines, line); ++k) {
      csv << (k == 5 ? line.substr(0, line.find(',')) + ",nan,0,0,0,0,9.8" : line) << '\n';
    }
  }
  const fs::path out = scratch() / "o_bad_imu";
  fs::remove_all(out);
  const std::string scans = q(tunnel() / "scans") + " --times " + q(tunnel() / "times.txt") + " --max-scans 5 --out " + q(out);
  Result r = cairn_run("slam3d " + scans + " --imu " + q(dir));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("data.csv:5:"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));

  const fs::path extrinsic = scratch() / "bad_imu" / "lidar.yaml";
  std::ofstream(extrinsic) << "sensor_type: lidar\nT_BS:\n  cols: 4\n  rows: 4\n  data: [2, 0, 0, 0,\n"
                              "         0, 1, 0, 0,\n         0, 0, 1, 1.8,\n         0, 0, 0, 1]\n";
  r = cairn_run("slam3d " + scans + " --imu " + q(tunnel() / "imu0") + " --lidar-extrinsic " + q(extrinsic));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("lidar.yaml:5:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not orthonormal"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// Without a sensor.yaml beside a plain copy of the IMU's data, the ADIS16448's noise and an
// identity extrinsic are taken and said so; an IMU on another clock (a 1000 s offset) covers no
// scan's sweep: the run goes on LiDAR-only and warns. (The first scan is still counted as fused:
// the fusion starts its state where the IMU starts and holds it back over the first sweep.)
TEST(Slam3dImuCli, DefaultsAndAnImuOffTheScansClockAreReported) {
  const fs::path dir = scratch() / "bare_imu";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(tunnel() / "imu0" / "data.csv", dir / "imu.csv");
  const fs::path out = scratch() / "o_bare";
  fs::remove_all(out);
  const std::string scans = q(tunnel() / "scans") + " --times " + q(tunnel() / "times.txt") + " --max-scans 10 --no-loop-closure";
  Result r = cairn_run("slam3d " + scans + " --imu " + q(dir / "imu.csv") + " --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("ADIS16448"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("identity"), std::string::npos) << r.err;
  nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_TRUE(report["inertial"]["calibration_file"].is_null());
  EXPECT_TRUE(report["inertial"]["lidar_extrinsic_file"].is_null());
  EXPECT_EQ(report["inertial"]["notes"].size(), 2u);
  EXPECT_GE(report["inertial"]["consistency"]["fused_scans"].get<int>(), 9);

  fs::remove_all(out);
  r = cairn_run("slam3d " + scans + " --imu " + q(tunnel() / "imu0") + " --imu-time-offset 1000 --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("covered only"), std::string::npos) << r.err;
  report = nlohmann::json::parse(slurp(out / "report.json"));
  const nlohmann::json& c = report["inertial"]["consistency"];
  EXPECT_LE(c["fused_scans"].get<int>(), 1);
  EXPECT_EQ(c["fused_scans"].get<int>() + c["scans_without_prediction"].get<int>(), 10);
  EXPECT_EQ(report["inertial"]["time_offset_s"].get<double>(), 1000.0);
}

}  // namespace
