// `cairn vslam --imu` (issue 40's input) on an EuRoC-layout folder written from the simulation of
// test_visual_inertial.cpp: the corridor flight at 20 Hz with a second of black images, cam0/cam1
// with their sensor.yaml (T_BS: the cameras on the IMU's body), imu0/data.csv in EuRoC's format from
// the simulator's ADIS16448 and imu0/sensor.yaml with its noise. Runs the cairn binary as
// tests/cli does, with and without the IMU, and checks report.json; then the flags' refusals and a
// broken IMU file.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cairn/sim/imu.hpp"
#include "cairn/vision/image_file.hpp"
#include "cli/cli_runner.hpp"
#include "inertial_flight.hpp"
#include "synthetic_world.hpp"

namespace cairn::test {
namespace {

namespace fs = std::filesystem;

constexpr double kFrameRate = 20.0, kDuration = 6.0, kBlankFrom = 3.0, kBlankTo = 4.0;
constexpr std::int64_t kStartNs = 1'000'000'000;  // the recording's clock starts at 1 s

fs::path scratch() { return scratch_folder("vslam_imu_cli"); }
std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }
CliResult run(const std::string& args) { return run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string matrix_yaml(const core::SE3& T) {
  const Eigen::Matrix4d M = T.matrix();
  std::string out = "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int k = 0; k < 16; ++k) {
    char number[40];
    std::snprintf(number, sizeof number, "%s%.17g", k ? ", " : "", M(k / 4, k % 4));
    out += number;
  }
  return out + "]\n";
}

void write_camera_yaml(const fs::path& path, const StereoCamera& camera, const core::SE3& T_body_camera) {
  std::ofstream out(path);
  out << "%YAML:1.0\nsensor_type: camera\ncomment: synthetic\n" << matrix_yaml(T_body_camera) << "rate_hz: 20\nresolution: ["
      << camera.width << ", " << camera.height << "]\ncamera_model: pinhole\nintrinsics: [" << camera.fx << ", " << camera.fy << ", "
      << camera.cx << ", " << camera.cy << "]\ndistortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n";
}

// The EuRoC folder (once per test process); returns its mav0.
fs::path euroc_folder() {
  static const fs::path mav0 = [] {
    const fs::path dir = scratch() / "flight" / "mav0";
    fs::remove_all(dir.parent_path());
    for (const char* sub : {"cam0/data", "cam1/data", "imu0"}) fs::create_directories(dir / sub);
    SyntheticWorld world;
    world.add_corridor_z(Eigen::Vector3d(-1.0, -1.0, -1.0), Eigen::Vector3d(1.0, 1.3, 22.0), 101);
    const StereoCamera camera;
    const core::SE3 T_body_left = T_body_camera();
    const core::SE3 T_left_right(core::SO3(), Eigen::Vector3d(camera.baseline_m, 0.0, 0.0));
    write_camera_yaml(dir / "cam0" / "sensor.yaml", camera, T_body_left);
    write_camera_yaml(dir / "cam1" / "sensor.yaml", camera, T_body_left * T_left_right);
    std::ofstream csv0(dir / "cam0" / "data.csv"), csv1(dir / "cam1" / "data.csv");
    csv0 << "#timestamp [ns],filename\n";
    csv1 << "#timestamp [ns],filename\n";
    const cv::Mat black = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    for (int k = 0; k <= static_cast<int>(kDuration * kFrameRate); ++k) {
      const double t = k / kFrameRate;
      const std::int64_t ns = kStartNs + static_cast<std::int64_t>(k) * 50'000'000LL;
      const std::string name = std::to_string(ns) + ".png";
      const bool dark = t >= kBlankFrom - 1e-9 && t < kBlankTo - 1e-9;
      const auto [left, right] = dark ? std::pair{black, black} : world.render_stereo(camera_in_render_world(t), camera);
      std::ofstream(dir / "cam0" / "data" / name, std::ios::binary) << vision::encode_png(left);
      std::ofstream(dir / "cam1" / "data" / name, std::ios::binary) << vision::encode_png(right);
      csv0 << ns << "," << name << "\n";
      csv1 << ns << "," << name << "\n";
    }
    sim::ImuSimulationOptions imu = *sim::imu_preset("adis16448");
    imu.seed = 7;
    const sim::SimulatedImu simulated = sim::simulate_imu(
        [](double t) { return kinematics_of([](double s) { return camera_in_render_world(s); }, t); }, 0.0, kDuration + 0.2, imu);
    std::ofstream csv(dir / "imu0" / "data.csv");
    csv << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
    char line[256];
    for (const inertial::ImuSample& s : simulated.samples) {
      std::snprintf(line, sizeof line, "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                    static_cast<long long>(s.stamp.nanoseconds() + kStartNs), s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z(),
                    s.accel_mps2.x(), s.accel_mps2.y(), s.accel_mps2.z());
      csv << line;
    }
    std::ofstream yaml(dir / "imu0" / "sensor.yaml");
    yaml << "%YAML:1.0\nsensor_type: imu\ncomment: simulated ADIS16448\n" << matrix_yaml(core::SE3()) << "rate_hz: 200\n"
         << "gyroscope_noise_density: " << imu.noise.gyro_noise_density << "\ngyroscope_random_walk: " << imu.noise.gyro_random_walk
         << "\naccelerometer_noise_density: " << imu.noise.accel_noise_density
         << "\naccelerometer_random_walk: " << imu.noise.accel_random_walk << "\n";
    return dir;
  }();
  return mav0;
}

nlohmann::json report(const fs::path& out) {
  std::ifstream in(out / "report.json");
  return nlohmann::json::parse(in);
}

TEST(VslamImuCli, EurocFolderWithItsImuCarriesTheBlankSecond) {
  const fs::path mav0 = euroc_folder();
  const int blank = static_cast<int>(std::lround((kBlankTo - kBlankFrom) * kFrameRate));
  const fs::path visual = scratch() / "visual", inertial = scratch() / "inertial";
  const CliResult without = run("vslam " + quoted(mav0.parent_path()) + " --out " + quoted(visual) + " --overwrite");
  ASSERT_EQ(without.status, 0) << without.err;
  const CliResult with = run("vslam " + quoted(mav0.parent_path()) + " --imu " + quoted(mav0) + " --out " + quoted(inertial) + " --overwrite");
  ASSERT_EQ(with.status, 0) << with.err;
  std::printf("%s%s", without.out.c_str(), with.out.c_str());
  const nlohmann::json a = report(visual), b = report(inertial);
  EXPECT_TRUE(a["inertial"].is_null());
  EXPECT_GE(a["summary"]["lost"].get<int>(), blank);
  ASSERT_TRUE(b["inertial"].is_object());
  EXPECT_TRUE(b["inertial"]["initialised"].get<bool>());
  EXPECT_EQ(b["inertial"]["frames_carried"].get<int>(), blank);
  EXPECT_EQ(b["summary"]["lost"].get<int>(), 0);
  // The camera's extrinsic as given in cam0/sensor.yaml (the pair is rectified already: the
  // rectifier turns the left camera by at most rounding).
  const core::SE3 T = T_body_camera();
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(b["inertial"]["T_imu_camera"]["translation"][static_cast<std::size_t>(i)].get<double>(), T.translation()[i], 1e-6);
  EXPECT_NE(with.err.find("camera extrinsic: the dataset's left camera"), std::string::npos) << with.err;
  EXPECT_NE(with.out.find("frames carried by it"), std::string::npos) << with.out;
  // The inertial options are configuration keys: carried for at most half a second, the IMU
  // carries 9 or 10 of the blank second's 20 frames (20 Hz; the tenth sits at 0.5 s, within
  // rounding), and the rest are lost.
  const fs::path half = scratch() / "inertial_half_second";
  const CliResult shorter = run("vslam " + quoted(mav0.parent_path()) + " --imu " + quoted(mav0) +
                                " --set inertial.max_carried_s=0.5 --out " + quoted(half) + " --overwrite");
  ASSERT_EQ(shorter.status, 0) << shorter.err;
  const nlohmann::json c = report(half);
  const int carried = c["inertial"]["frames_carried"].get<int>();
  EXPECT_GE(carried, 9);
  EXPECT_LE(carried, 10);
  EXPECT_GE(c["summary"]["lost"].get<int>(), blank - carried);
}

TEST(VslamImuCli, RefusesImuFlagsThatMakeNoSenseAndBrokenImuFiles) {
  const fs::path mav0 = euroc_folder();
  const fs::path out = scratch() / "refused";
  const CliResult calibration_alone = run("vslam " + quoted(mav0.parent_path()) + " --imu-calibration x.yaml --out " + quoted(out));
  EXPECT_EQ(calibration_alone.status, 2);
  EXPECT_NE(calibration_alone.err.find("--imu-calibration goes with --imu"), std::string::npos) << calibration_alone.err;
  const CliResult topic_of_folder = run("vslam " + quoted(mav0.parent_path()) + " --imu-topic /imu --out " + quoted(out));
  EXPECT_EQ(topic_of_folder.status, 2);
  EXPECT_NE(topic_of_folder.err.find("FOLDER is not a bag"), std::string::npos) << topic_of_folder.err;
  // A truncated line in the IMU's CSV: the file and the line are named, nothing is written.
  const fs::path broken = scratch() / "broken_imu.csv";
  {
    std::ifstream in(mav0 / "imu0" / "data.csv");
    std::ofstream copy(broken);
    std::string line;
    for (int k = 0; k < 10 && std::getline(in, line); ++k) copy << line << "\n";
    copy << "1050000000,0.1,0.2\n";
  }
  const CliResult bad = run("vslam " + quoted(mav0.parent_path()) + " --imu " + quoted(broken) + " --out " + quoted(scratch() / "bad"));
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.err.find("broken_imu.csv"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find(":11"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(scratch() / "bad" / "report.json"));
}

}  // namespace
}  // namespace cairn::test
