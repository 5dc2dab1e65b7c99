// IMU data: the EuRoC readers on the real V1_01_easy files, the plain CSV, the Husky bag's
// sensor_msgs/Imu, round trips of every writer, hostile inputs, and check_imu_data /
// apply_imu_input on constructed samples whose answers are known in closed form.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_csv.hpp"
#include "cairn/inertial/imu_input.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::inertial {
namespace {

namespace fs = std::filesystem;
using core::Timestamp;

constexpr const char* kEurocImu = "inertial/euroc_v1_01/mav0/imu0/data.csv";
constexpr const char* kEurocYaml = "inertial/euroc_v1_01/mav0/imu0/sensor.yaml";
constexpr const char* kEurocGroundTruth = "inertial/euroc_v1_01/groundtruth/V1_01_easy.csv";
constexpr const char* kHuskyBag = "bags/robot_localization_test1.bag";

class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("cairn_test_imu_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  fs::path write(const std::string& name, const std::string& bytes) const {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  fs::path path(const std::string& name) const { return dir_ / name; }

 private:
  fs::path dir_;
};

// Calls `read` and expects a ParseError naming `path` and `line` (0: the whole file), whose
// message contains `fragment`.
template <class Read>
void expect_parse_error(Read read, const fs::path& path, std::size_t line, const std::string& fragment) {
  try {
    read();
    ADD_FAILURE() << "no ParseError for " << path << " (expected line " << line << ": " << fragment << ")";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.file(), path.string()) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(path.string() + (line > 0 ? ":" + std::to_string(line) + ":" : ":")), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << "message lacks '" << fragment << "': " << e.what();
  }
}

void expect_same(const std::vector<ImuSample>& a, const std::vector<ImuSample>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].stamp, b[i].stamp) << i;
    ASSERT_TRUE(a[i].gyro_rad_s == b[i].gyro_rad_s) << i;  // bit for bit (== on doubles)
    ASSERT_TRUE(a[i].accel_mps2 == b[i].accel_mps2) << i;
  }
}

// ---------------------------------------------------------------------------------------------
// The real EuRoC V1_01_easy files.

TEST(EurocImu, ReadsTheRealRecording) {
  CAIRN_REQUIRE_DATA(kEurocImu);
  const auto samples = read_euroc_imu(test::data_path(kEurocImu));
  // SOURCE.txt: 29,120 samples, 1403715273.262 .. 1403715418.857 s, 200 Hz.
  ASSERT_EQ(samples.size(), 29120u);
  EXPECT_EQ(samples.front().stamp.nanoseconds(), 1403715273262142976);
  EXPECT_EQ(samples.back().stamp.nanoseconds(), 1403715418857143040);
  // The first data line, typed from the file.
  EXPECT_EQ(samples.front().gyro_rad_s, Vector3(-0.0020943951023931952, 0.017453292519943295, 0.07749261878854824));
  EXPECT_EQ(samples.front().accel_mps2, Vector3(9.0874956666666655, 0.13075533333333333, -3.6938381666666662));
  // The folder holding imu0/ and the imu0 folder name the same file.
  const fs::path mav0 = test::data_path("inertial/euroc_v1_01/mav0");
  EXPECT_EQ(read_euroc_imu(mav0).size(), 29120u);
  EXPECT_EQ(read_euroc_imu(mav0 / "imu0").size(), 29120u);
  EXPECT_EQ(read_imu_file(test::data_path(kEurocImu)).size(), 29120u);
}

TEST(EurocImu, ChecksOfTheRealRecording) {
  CAIRN_REQUIRE_DATA(kEurocImu);
  const auto samples = read_euroc_imu(test::data_path(kEurocImu));
  ImuInputOptions options;
  options.gyro_saturation_rad_s = 1000.0 * std::numbers::pi / 180.0;  // ADIS16448 data sheet: +-1000 deg/s
  options.accel_saturation_mps2 = 18.0 * kStandardGravity;           // and +-18 g
  const ImuDataReport report = check_imu_data(samples, options);
  EXPECT_EQ(report.samples, 29120u);
  // The file's steps are 4999936 ns (21839 times) and 5000192 ns (7280 times), counted with
  // python3 over the stamps column.
  EXPECT_DOUBLE_EQ(report.median_dt_s, 4999936e-9);
  EXPECT_DOUBLE_EQ(report.min_dt_s, 4999936e-9);
  EXPECT_DOUBLE_EQ(report.max_dt_s, 5000192e-9);
  EXPECT_NEAR(report.duration_s, 145.595000064, 1e-9);
  EXPECT_NEAR(report.mean_rate_hz, 29119.0 / 145.595000064, 1e-9);
  EXPECT_TRUE(report.gaps.empty());
  EXPECT_EQ(report.gyro_saturated_samples, 0u);
  EXPECT_EQ(report.accel_saturated_samples, 0u);
  // The accelerometer's mean is dominated by gravity: its norm is near 9.81 (the MAV hovers
  // and moves slowly; the mean of its specific force is close to -g in the IMU frame).
  EXPECT_NEAR(report.accel_mean_mps2.norm(), kStandardGravity, 0.2);
  // Without limits the guess must not take a live recording for a clipped one.
  const ImuDataReport guessed = check_imu_data(samples, ImuInputOptions{});
  EXPECT_EQ(guessed.gyro_saturated_samples, 0u);
  EXPECT_EQ(guessed.accel_saturated_samples, 0u);
  const nlohmann::json json = to_json(report);
  EXPECT_EQ(json.at("samples").get<std::size_t>(), 29120u);
  EXPECT_EQ(json.at("first_stamp_ns").get<std::int64_t>(), 1403715273262142976);
  EXPECT_TRUE(json.at("gaps").empty());
}

TEST(EurocImu, ReadsTheRealSensorYaml) {
  CAIRN_REQUIRE_DATA(kEurocYaml);
  const ImuCalibration calibration = read_euroc_imu_calibration(test::data_path(kEurocYaml));
  // The values of imu0/sensor.yaml, typed from the file.
  EXPECT_EQ(calibration.noise.gyro_noise_density, 1.6968e-04);
  EXPECT_EQ(calibration.noise.gyro_random_walk, 1.9393e-05);
  EXPECT_EQ(calibration.noise.accel_noise_density, 2.0000e-3);
  EXPECT_EQ(calibration.noise.accel_random_walk, 3.0000e-3);
  EXPECT_EQ(calibration.rate_hz, 200.0);
  EXPECT_TRUE(calibration.T_body_imu.matrix().isIdentity(0.0));
  EXPECT_EQ(read_euroc_imu_calibration(test::data_path("inertial/euroc_v1_01/mav0")).rate_hz, 200.0);
}

TEST(EurocGroundTruth, ReadsTheRealFile) {
  CAIRN_REQUIRE_DATA(kEurocGroundTruth);
  const auto states = read_euroc_ground_truth(test::data_path(kEurocGroundTruth));
  ASSERT_EQ(states.size(), 2895u);  // lines of the file minus its header (wc -l)
  const GroundTruthState& first = states.front();
  EXPECT_EQ(first.stamp.nanoseconds(), 1403715273262142976);
  EXPECT_EQ(first.state.T_world_body.translation(), Vector3(0.878895, 2.1834, 0.948427));
  // q is w x y z in this file: 0.069433,-0.824237,-0.106942,-0.551702 (norm 1 to 1e-6).
  const Quaternion q = first.state.T_world_body.unit_quaternion();
  EXPECT_NEAR(q.w(), 0.069433, 1e-6);
  EXPECT_NEAR(q.x(), -0.824237, 1e-6);
  EXPECT_NEAR(q.y(), -0.106942, 1e-6);
  EXPECT_NEAR(q.z(), -0.551702, 1e-6);
  EXPECT_EQ(first.state.v_world_mps, Vector3(0.00157587, 0.00179383, -0.00231615));
  EXPECT_EQ(first.bias.gyro_rad_s, Vector3(-0.00224703, 0.0215352, 0.0770299));
  EXPECT_EQ(first.bias.accel_mps2, Vector3(-0.0180115, 0.0659796, 0.0309774));
  EXPECT_EQ(states.back().stamp.nanoseconds(), 1403715417962142976);
}

// ---------------------------------------------------------------------------------------------
// Round trips: what a writer writes reads back bit for bit (T_BS: to rounding).

TEST(RoundTrip, EurocImuAndPlainCsv) {
  CAIRN_REQUIRE_DATA(kEurocImu);
  ScratchDir dir;
  const auto samples = read_euroc_imu(test::data_path(kEurocImu));
  write_euroc_imu(dir.path("imu.csv"), samples);
  expect_same(samples, read_euroc_imu(dir.path("imu.csv")));
  write_imu_csv(dir.path("plain.csv"), samples);
  expect_same(samples, read_imu_csv(dir.path("plain.csv")));
  expect_same(samples, read_imu_file(dir.path("plain.csv")));
  expect_same(samples, read_imu_file(dir.path("imu.csv")));
}

TEST(RoundTrip, ExtremeNumbers) {
  ScratchDir dir;
  std::vector<ImuSample> samples(3);
  samples[0] = {Timestamp::from_nanoseconds(-9'200'000'000'000'000'000), Vector3(1e-308, -0.0, 5e-324),
                Vector3(1.7976931348623157e308, -1.7976931348623157e308, 0.1)};
  samples[1] = {Timestamp::from_nanoseconds(0), Vector3(std::nextafter(1.0, 2.0), 1.0 / 3.0, -2.0 / 3.0), Vector3::Constant(1e22)};
  samples[2] = {Timestamp::from_nanoseconds(9'200'000'000'000'000'000), Vector3::Constant(std::numbers::pi), Vector3::Zero()};
  write_euroc_imu(dir.path("imu.csv"), samples);
  expect_same(samples, read_euroc_imu(dir.path("imu.csv")));
  write_imu_csv(dir.path("plain.csv"), samples);
  expect_same(samples, read_imu_csv(dir.path("plain.csv")));
}

TEST(RoundTrip, GroundTruth) {
  CAIRN_REQUIRE_DATA(kEurocGroundTruth);
  ScratchDir dir;
  const auto states = read_euroc_ground_truth(test::data_path(kEurocGroundTruth));
  write_euroc_ground_truth(dir.path("gt.csv"), states);
  const auto back = read_euroc_ground_truth(dir.path("gt.csv"));
  ASSERT_EQ(back.size(), states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    ASSERT_EQ(back[i].stamp, states[i].stamp);
    ASSERT_TRUE(back[i].state.T_world_body.translation() == states[i].state.T_world_body.translation());
    ASSERT_TRUE(back[i].state.T_world_body.unit_quaternion().coeffs() == states[i].state.T_world_body.unit_quaternion().coeffs()) << i;
    ASSERT_TRUE(back[i].state.v_world_mps == states[i].state.v_world_mps);
    ASSERT_TRUE(back[i].bias.gyro_rad_s == states[i].bias.gyro_rad_s);
    ASSERT_TRUE(back[i].bias.accel_mps2 == states[i].bias.accel_mps2);
  }
}

TEST(RoundTrip, SensorYaml) {
  ScratchDir dir;
  ImuCalibration calibration;
  calibration.noise = {1.23456789012345e-4, 2.5e-3, 3.0000000000000004e-5, 7e-4};
  calibration.rate_hz = 398.7;
  calibration.T_body_imu = core::SE3(core::SO3::exp(Vector3(0.3, -1.2, 2.9)), Vector3(-0.0216401454975, -0.064676986768, 0.00981073058949));
  write_euroc_imu_calibration(dir.path("sensor.yaml"), calibration);
  const ImuCalibration back = read_euroc_imu_calibration(dir.path("sensor.yaml"));
  EXPECT_EQ(back.noise.gyro_noise_density, calibration.noise.gyro_noise_density);
  EXPECT_EQ(back.noise.accel_noise_density, calibration.noise.accel_noise_density);
  EXPECT_EQ(back.noise.gyro_random_walk, calibration.noise.gyro_random_walk);
  EXPECT_EQ(back.noise.accel_random_walk, calibration.noise.accel_random_walk);
  EXPECT_EQ(back.rate_hz, calibration.rate_hz);
  EXPECT_TRUE(back.T_body_imu.translation() == calibration.T_body_imu.translation());
  EXPECT_LT((back.T_body_imu.matrix() - calibration.T_body_imu.matrix()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(RoundTrip, WritersRefuseWhatReadersWouldRefuse) {
  ScratchDir dir;
  std::vector<ImuSample> samples(2);
  samples[1].stamp = Timestamp::from_nanoseconds(5);
  samples[1].gyro_rad_s.x() = std::nan("");
  EXPECT_THROW(write_euroc_imu(dir.path("a.csv"), samples), io::ParseError);
  EXPECT_THROW(write_imu_csv(dir.path("a.csv"), samples), io::ParseError);
  samples[1].gyro_rad_s.x() = 0.0;
  samples[1].stamp = samples[0].stamp;  // duplicated
  EXPECT_THROW(write_euroc_imu(dir.path("a.csv"), samples), io::ParseError);
  EXPECT_THROW(write_euroc_imu(dir.path("a.csv"), {}), io::ParseError);
  EXPECT_THROW(write_euroc_ground_truth(dir.path("a.csv"), {}), io::ParseError);
  EXPECT_FALSE(fs::exists(dir.path("a.csv")));
}

// ---------------------------------------------------------------------------------------------
// Hostile input: every failure is a ParseError naming the file and the line.

constexpr const char* kHeader = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
constexpr const char* kRow1 = "1000000000,0.1,0.2,0.3,0.0,0.0,9.8\n";
constexpr const char* kRow2 = "1005000000,0.1,0.2,0.3,0.0,0.0,9.8\n";

TEST(HostileEurocImu, EveryFailureNamesFileAndLine) {
  ScratchDir dir;
  const auto check = [&](const std::string& name, const std::string& text, std::size_t line, const std::string& fragment) {
    SCOPED_TRACE(name);
    const fs::path path = dir.write(name, text);
    expect_parse_error([&] { return read_euroc_imu(path); }, path, line, fragment);
    expect_parse_error([&] { return read_imu_file(path); }, path, line, fragment);
  };
  const std::string head = std::string(kHeader) + kRow1;
  check("nan.csv", head + "1005000000,nan,0.2,0.3,0.0,0.0,9.8\n", 3, "finite number for w_RS_S_x");
  check("inf.csv", head + "1005000000,0.1,0.2,0.3,0.0,-inf,9.8\n", 3, "a_RS_S_y");
  check("missing_column.csv", head + "1005000000,0.1,0.2,0.3,0.0,9.8\n", 3, "expected 7 comma-separated columns");
  check("extra_column.csv", head + "1005000000,0.1,0.2,0.3,0.0,0.0,9.8,1\n", 3, "found 8");
  check("text.csv", head + "1005000000,0.1,0.2,abc,0.0,0.0,9.8\n", 3, "'abc'");
  check("trailing.csv", head + "1005000000,0.1,0.2,0.3x,0.0,0.0,9.8\n", 3, "w_RS_S_z");
  check("out_of_order.csv", head + "999999999,0.1,0.2,0.3,0.0,0.0,9.8\n", 3, "stamp out of order");
  check("duplicate.csv", head + kRow1, 3, "duplicated stamp");
  check("truncated.csv", head + "1005000000,0.1,0.2,0.", 3, "found 4");
  check("empty.csv", "", 0, "no IMU samples");
  check("header_only.csv", kHeader, 0, "no IMU samples");
  check("binary.csv", head + std::string("\x00\x01\xff\xfe junk", 9), 3, "");
  check("huge.csv", head + "1005000000,1e999,0.2,0.3,0.0,0.0,9.8\n", 3, "1e999");
  check("huge_stamp.csv", head + "99999999999999999999999,0.1,0.2,0.3,0.0,0.0,9.8\n", 3, "nanoseconds");
  check("seconds_stamp.csv", head + "1.005,0.1,0.2,0.3,0.0,0.0,9.8\n", 3, "nanoseconds");
  // A directory without data.csv.
  expect_parse_error([&] { return read_euroc_imu(dir.path("")); }, dir.path(""), 0, "data.csv");
}

TEST(HostileEurocImu, UnterminatedLastLineIsReportedNotRefused) {
  ScratchDir dir;
  const fs::path path = dir.write("cut.csv", std::string(kHeader) + kRow1 + "1005000000,0.1,0.2,0.3,0.0,0.0,9.8");
  std::vector<std::string> warnings;
  EXPECT_EQ(read_euroc_imu(path, &warnings).size(), 2u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("newline"), std::string::npos) << warnings[0];
  const fs::path plain = dir.write("cut_plain.csv", "time_ns,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_mps2,accel_y_mps2,accel_z_mps2\n1,1,2,3,4,5,6");
  warnings.clear();
  EXPECT_EQ(read_imu_file(plain, &warnings).size(), 1u);
  EXPECT_EQ(warnings.size(), 1u);
  // Terminated files give no warning.
  warnings.clear();
  read_imu_file(dir.write("whole.csv", std::string(kHeader) + kRow1 + kRow2), &warnings);
  EXPECT_TRUE(warnings.empty());
}

TEST(HostileGroundTruth, EveryFailureNamesFileAndLine) {
  ScratchDir dir;
  const std::string row = "1000,1,2,3,1,0,0,0,0.1,0.2,0.3,0,0,0,0,0,0\n";
  const auto check = [&](const std::string& name, const std::string& text, std::size_t line, const std::string& fragment) {
    SCOPED_TRACE(name);
    const fs::path path = dir.write(name, text);
    expect_parse_error([&] { return read_euroc_ground_truth(path); }, path, line, fragment);
  };
  check("short.csv", "#h\n" + row + "2000,1,2,3,1,0,0,0,0.1,0.2,0.3,0,0,0,0,0\n", 3, "expected 17");
  check("nan.csv", "#h\n" + row + "2000,1,2,3,1,0,0,0,0.1,nan,0.3,0,0,0,0,0,0\n", 3, "v_RS_R_y");
  check("quaternion.csv", "#h\n" + row + "2000,1,2,3,0.5,0,0,0,0.1,0.2,0.3,0,0,0,0,0,0\n", 3, "unit quaternion");
  check("zero_quaternion.csv", "#h\n" + row + "2000,1,2,3,0,0,0,0,0.1,0.2,0.3,0,0,0,0,0,0\n", 3, "unit quaternion");
  check("order.csv", "#h\n" + row + row, 3, "duplicated stamp");
  check("empty.csv", "", 0, "no ground-truth states");
  check("imu_file.csv", std::string(kHeader) + kRow1, 2, "expected 17");
}

TEST(HostileSensorYaml, EveryFailureNamesFileLineAndKey) {
  ScratchDir dir;
  const std::string noise =
      "gyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\naccelerometer_noise_density: 2.0e-3\n"
      "accelerometer_random_walk: 3.0e-3\nrate_hz: 200\n";
  const auto check = [&](const std::string& name, const std::string& text, std::size_t line, const std::string& fragment) {
    SCOPED_TRACE(name);
    const fs::path path = dir.write(name, text);
    expect_parse_error([&] { return read_euroc_imu_calibration(path); }, path, line, fragment);
  };
  const auto T_BS = [](const std::string& data) { return "T_BS:\n  cols: 4\n  rows: 4\n  data: [" + data + "]\n"; };
  // A rotation about z by 90 degrees, valid; then broken in several ways (line 9 holds data).
  const std::string valid = "0, -1, 0, 0.1, 1, 0, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1";
  EXPECT_NEAR(read_euroc_imu_calibration(dir.write("ok.yaml", noise + T_BS(valid))).T_body_imu.so3().log().z(),
              std::numbers::pi / 2, 1e-15);
  check("scaled.yaml", noise + T_BS("2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1"), 9, "\"T_BS\": expected a rigid transform");
  check("reflection.yaml", noise + T_BS("-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1"), 9, "reflection");
  check("last_row.yaml", noise + T_BS("1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1"), 9, "last row 0 0 0 1");
  check("fifteen.yaml", noise + T_BS("1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0"), 9, "found 15");
  check("text_in_T.yaml", noise + T_BS("1, 0, 0, 0, 0, 1, 0, zero, 0, 0, 1, 0, 0, 0, 0, 1"), 9, "T_BS.data[7]");
  check("nan_in_T.yaml", noise + T_BS("1, 0, 0, 0, 0, 1, 0, .nan, 0, 0, 1, 0, 0, 0, 0, 1"), 9, "T_BS.data[7]");
  check("rows.yaml", noise + "T_BS:\n  cols: 4\n  rows: 3\n  data: [1]\n", 8, "T_BS.rows");
  check("missing.yaml", "gyroscope_noise_density: 1.6968e-04\nrate_hz: 200\n", 0, "missing key \"gyroscope_random_walk\"");
  check("negative.yaml", "gyroscope_noise_density: -1\n", 1, "\"gyroscope_noise_density\": expected a finite number > 0");
  check("text.yaml", "gyroscope_noise_density: abc\n", 1, "\"gyroscope_noise_density\": expected a number");
  check("huge.yaml", "gyroscope_noise_density: 1e999\n", 1, "gyroscope_noise_density");
  check("no_rate.yaml", "gyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\naccelerometer_noise_density: 2.0e-3\n"
        "accelerometer_random_walk: 3.0e-3\n", 0, "rate_hz");
  check("empty.yaml", "", 0, "expected a YAML map");
  check("list.yaml", "- 1\n- 2\n", 0, "expected a YAML map");
  check("broken.yaml", "a: [1, 2\nb: 3\n", 2, "not valid YAML");
  check("binary.yaml", std::string("\x00\x01\xff\xfe\x80junk", 9), 0, "");
}

TEST(HostilePlainCsv, EveryFailureNamesFileAndLine) {
  ScratchDir dir;
  const std::string header = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_mps2,accel_y_mps2,accel_z_mps2\n";
  const auto check = [&](const std::string& name, const std::string& text, std::size_t line, const std::string& fragment) {
    SCOPED_TRACE(name);
    const fs::path path = dir.write(name, text);
    expect_parse_error([&] { return read_imu_csv(path); }, path, line, fragment);
    expect_parse_error([&] { return read_imu_file(path); }, path, line, fragment);
  };
  check("no_time.csv", "# c\nt,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_mps2,accel_y_mps2,accel_z_mps2\n", 2,
        "lacks: time_s or time_ns");
  check("no_accel.csv", "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s\n0,1,2,3\n", 1,
        "accel_x_mps2 or accel_x_g; accel_y_mps2 or accel_y_g; accel_z_mps2 or accel_z_g");
  check("twice.csv", "time_s,gyro_x_rad_s,gyro_x_deg_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_mps2,accel_y_mps2,accel_z_mps2\n", 1,
        "two columns for one quantity");
  check("nan.csv", header + "0.0,1,2,3,4,5,6\n0.01,1,nan,3,4,5,6\n", 3, "gyro y");
  check("missing_column.csv", header + "0.0,1,2,3,4,5,6\n0.01,1,2,3,4,5\n", 3, "expected 7 comma-separated columns");
  check("text.csv", header + "0.0,1,2,3,4,5,6\n0.01,1,2,3,four,5,6\n", 3, "'four'");
  check("out_of_order.csv", header + "0.02,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n", 3, "stamp out of order");
  check("duplicate.csv", header + "0.01,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n", 3, "duplicated stamp");
  check("truncated.csv", header + "0.0,1,2,3,4,5,6\n0.01,1,2", 3, "found 3");
  check("header_only.csv", header, 0, "no IMU samples");
  check("huge.csv", header + "0.0,1,2,3,4,5,6\n0.01,1,2,3,4,5,1e400\n", 3, "accel z");
  check("huge_time.csv", header + "1e300,1,2,3,4,5,6\n", 2, "time_s");
  check("binary.csv", header + std::string("\x00\x01\xff\xfe\x80junk", 9), 2, "");
  // deg/s that overflow once converted are refused too.
  check("overflow.csv", "time_s,gyro_x_deg_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_g,accel_y_mps2,accel_z_mps2\n0,1,2,3,1e308,5,6\n", 2,
        "accel_x_mps2 or accel_x_g");
}

TEST(PlainCsv, ConvertsDegreesAndG) {
  ScratchDir dir;
  // Columns in another order, an extra column holding text, comments and a blank line.
  const fs::path path = dir.write("imu.csv",
                                  "# my IMU, 100 Hz\n\n"
                                  "accel_z_g, temperature_c, gyro_z_deg_s,time_s,gyro_x_deg_s,gyro_y_rad_s,accel_x_g,accel_y_mps2\n"
                                  "1.0, n/a, 90, 1403715273.262142976, -180, 0.5, 0.5, -9.5\n"
                                  "# a comment between rows\n"
                                  "-2.0, 25.1, 0, 1403715273.272142976, 45, 0, 0, 0\n");
  const auto samples = read_imu_csv(path);
  ASSERT_EQ(samples.size(), 2u);
  EXPECT_EQ(samples[0].stamp.nanoseconds(), 1403715273262142976);
  EXPECT_EQ(samples[1].stamp.nanoseconds(), 1403715273272142976);
  EXPECT_DOUBLE_EQ(samples[0].gyro_rad_s.x(), -std::numbers::pi);
  EXPECT_DOUBLE_EQ(samples[0].gyro_rad_s.y(), 0.5);
  EXPECT_DOUBLE_EQ(samples[0].gyro_rad_s.z(), std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(samples[0].accel_mps2.x(), 0.5 * 9.80665);
  EXPECT_DOUBLE_EQ(samples[0].accel_mps2.y(), -9.5);
  EXPECT_DOUBLE_EQ(samples[0].accel_mps2.z(), 9.80665);
  EXPECT_DOUBLE_EQ(samples[1].gyro_rad_s.x(), std::numbers::pi / 4);
  EXPECT_DOUBLE_EQ(samples[1].accel_mps2.z(), -2.0 * 9.80665);
  expect_same(samples, read_imu_file(path));
  // time_ns and SI units.
  const fs::path ns = dir.write("ns.csv", "time_ns,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_mps2,accel_y_mps2,accel_z_mps2\n"
                                          "-5,1,2,3,4,5,6\n");
  const auto one = read_imu_file(ns);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].stamp.nanoseconds(), -5);
  EXPECT_EQ(one[0].accel_mps2, Vector3(4, 5, 6));
}

// ---------------------------------------------------------------------------------------------
// The Husky bag's sensor_msgs/Imu.

TEST(BagImu, ReadsTheHuskyTopic) {
  CAIRN_REQUIRE_DATA(kHuskyBag);
  const fs::path bag = test::data_path(kHuskyBag);
  const auto samples = read_imu_topic(bag, "");
  // Counted independently with python3-rosbag (/usr/bin/python3):
  //   b = rosbag.Bag(path); sum(1 for _ in b.read_messages(topics=['/imu/data']))  -> 11865
  // and its header stamps msg.header.stamp.to_nsec(): first 1432235497988949113, last
  // 1432235893280979189, none equal to or before its predecessor.
  ASSERT_EQ(samples.size(), 11865u);
  EXPECT_EQ(samples.front().stamp.nanoseconds(), 1432235497988949113);
  EXPECT_EQ(samples.back().stamp.nanoseconds(), 1432235893280979189);
  expect_same(samples, read_imu_topic(bag, "/imu/data"));
  expect_same(samples, read_imu_file(bag));
  // A still or slowly driving ground robot: the mean specific force is about g.
  const ImuDataReport report = check_imu_data(samples, ImuInputOptions{});
  EXPECT_NEAR(report.accel_mean_mps2.norm(), kStandardGravity, 0.5);
  // Topics that do not exist or are not IMU topics are named in the error.
  try {
    read_imu_topic(bag, "/imu/dta");
    ADD_FAILURE() << "no error for a missing topic";
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("/imu/data"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_imu_topic(bag, "/fix"), io::ParseError);
}

// ---------------------------------------------------------------------------------------------
// check_imu_data and apply_imu_input on samples whose answers are known.

std::vector<ImuSample> regular(std::size_t count, std::int64_t step_ns) {
  std::vector<ImuSample> samples(count);
  for (std::size_t i = 0; i < count; ++i) {
    samples[i].stamp = Timestamp::from_nanoseconds(1'000'000'000 + static_cast<std::int64_t>(i) * step_ns);
    // Alternating +-1 about a mean: mean (1, 2, 3), sample std sqrt(n / (n - 1)) for even n.
    const double sign = i % 2 == 0 ? 1.0 : -1.0;
    samples[i].gyro_rad_s = Vector3(1.0, 2.0, 3.0) + sign * Vector3::Ones();
    samples[i].accel_mps2 = Vector3(0.0, 0.0, 9.8) + sign * 0.5 * Vector3::Ones();
  }
  return samples;
}

TEST(CheckImuData, RatesGapsAndStatistics) {
  auto samples = regular(1000, 10'000'000);  // 100 Hz
  // Remove 3 samples after index 500: one gap of 40 ms between samples 500 and 504.
  samples.erase(samples.begin() + 501, samples.begin() + 504);
  const ImuDataReport report = check_imu_data(samples, ImuInputOptions{});
  EXPECT_EQ(report.samples, 997u);
  EXPECT_DOUBLE_EQ(report.median_dt_s, 0.01);
  EXPECT_DOUBLE_EQ(report.median_rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(report.duration_s, 9.99);
  EXPECT_DOUBLE_EQ(report.mean_rate_hz, 996.0 / 9.99);
  ASSERT_EQ(report.gaps.size(), 1u);
  EXPECT_EQ(report.gaps[0].before.nanoseconds(), 1'000'000'000LL + 500LL * 10'000'000);
  EXPECT_EQ(report.gaps[0].after.nanoseconds(), 1'000'000'000LL + 504LL * 10'000'000);
  EXPECT_DOUBLE_EQ(report.gaps[0].dt_s, 0.04);
  EXPECT_DOUBLE_EQ(report.gap_time_s, 0.04);
  // 997 samples: 499 at +1 (even i, minus 502), 498 at -1 (odd, minus 501 and 503).
  const double n = 997.0, plus = 499.0, minus = 498.0;
  const double mean_shift = (plus - minus) / n;
  const double variance = (plus * std::pow(1.0 - mean_shift, 2) + minus * std::pow(1.0 + mean_shift, 2)) / (n - 1.0);
  EXPECT_NEAR(report.gyro_mean_rad_s.x(), 1.0 + mean_shift, 1e-12);
  EXPECT_NEAR(report.gyro_std_rad_s.z(), std::sqrt(variance), 1e-12);
  EXPECT_NEAR(report.accel_mean_mps2.z(), 9.8 + 0.5 * mean_shift, 1e-12);
  EXPECT_NEAR(report.accel_std_mps2.x(), 0.5 * std::sqrt(variance), 1e-12);
  // A larger factor hides the gap.
  ImuInputOptions tolerant;
  tolerant.gap_factor = 5.0;
  EXPECT_TRUE(check_imu_data(samples, tolerant).gaps.empty());
}

TEST(CheckImuData, SaturationWithAndWithoutLimits) {
  auto samples = regular(200, 5'000'000);
  // The gyro's z axis clipped at 8.0 for samples 50..59; the accelerometer's y at -160 for 100..103.
  for (std::size_t i = 50; i < 60; ++i) samples[i].gyro_rad_s.z() = 8.0;
  for (std::size_t i = 100; i < 104; ++i) samples[i].accel_mps2.y() = -160.0;
  // One isolated extreme value on gyro x (a run of 1): not a guessed saturation.
  samples[150].gyro_rad_s.x() = 50.0;
  const ImuDataReport guessed = check_imu_data(samples, ImuInputOptions{});
  EXPECT_FALSE(guessed.gyro_limit_known);
  EXPECT_EQ(guessed.gyro_saturated_samples, 10u);
  EXPECT_EQ(guessed.accel_saturated_samples, 4u);
  ASSERT_EQ(guessed.saturation.size(), 2u);
  EXPECT_TRUE(guessed.saturation[0].gyro);
  EXPECT_EQ(guessed.saturation[0].axis, 2);
  EXPECT_EQ(guessed.saturation[0].samples, 10u);
  EXPECT_EQ(guessed.saturation[0].first, samples[50].stamp);
  EXPECT_EQ(guessed.saturation[0].last, samples[59].stamp);
  EXPECT_FALSE(guessed.saturation[0].from_limit);
  EXPECT_EQ(guessed.saturation[1].value, -160.0);

  ImuInputOptions limits;
  limits.gyro_saturation_rad_s = 8.0;
  limits.accel_saturation_mps2 = 150.0;
  const ImuDataReport known = check_imu_data(samples, limits);
  // |8.0| >= 8 on z for 10 samples, and 50 on x once: 11 samples.
  EXPECT_EQ(known.gyro_saturated_samples, 11u);
  EXPECT_EQ(known.accel_saturated_samples, 4u);
  EXPECT_TRUE(known.saturation[0].from_limit);
  const nlohmann::json json = to_json(known);
  EXPECT_EQ(json.at("gyro_saturated_samples").get<std::size_t>(), 11u);
  EXPECT_EQ(json.at("saturation").size(), known.saturation.size());
}

TEST(ApplyImuInput, ShiftsStampsAndRotatesIntoTheBody) {
  std::vector<ImuSample> samples{{Timestamp::from_nanoseconds(1'000'000'000), Vector3(1, 0, 0), Vector3(0, 2, 9.8)},
                                 {Timestamp::from_nanoseconds(1'005'000'000), Vector3(0, 0, 1), Vector3(3, 0, 0)}};
  ImuInputOptions options;
  options.time_offset_s = -0.0125;
  // The IMU turned by +90 degrees about z in the body: x_imu = y_body, y_imu = -x_body.
  options.T_body_imu = core::SE3(core::SO3::exp(Vector3(0, 0, std::numbers::pi / 2)), Vector3(0.1, 0, 0));
  ASSERT_TRUE(options.is_valid(nullptr));
  const auto body = apply_imu_input(samples, options);
  ASSERT_EQ(body.size(), 2u);
  EXPECT_EQ(body[0].stamp.nanoseconds(), 987'500'000);
  EXPECT_EQ(body[1].stamp.nanoseconds(), 992'500'000);
  EXPECT_LT((body[0].gyro_rad_s - Vector3(0, 1, 0)).norm(), 1e-15);
  EXPECT_LT((body[0].accel_mps2 - Vector3(-2, 0, 9.8)).norm(), 1e-15);
  EXPECT_LT((body[1].gyro_rad_s - Vector3(0, 0, 1)).norm(), 1e-15);
  EXPECT_LT((body[1].accel_mps2 - Vector3(0, 3, 0)).norm(), 1e-15);
  // A shift past the representable range is refused, not wrapped.
  options.time_offset_s = 9.0e9;
  const std::vector<ImuSample> late{{Timestamp::from_nanoseconds(1'000'000'000'000'000'000), Vector3::Zero(), Vector3::Zero()}};
  EXPECT_THROW(apply_imu_input(late, options), std::out_of_range);
}

TEST(ImuInputOptions, ValidationReportsEveryProblem) {
  ImuInputOptions options;
  EXPECT_TRUE(options.is_valid(nullptr));
  options.time_offset_s = std::nan("");
  options.gyro_saturation_rad_s = -1.0;
  options.accel_saturation_mps2 = std::numeric_limits<double>::infinity();
  options.gap_factor = 1.0;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  for (const char* name : {"time_offset_s", "gyro_saturation_rad_s", "accel_saturation_mps2", "gap_factor"}) {
    EXPECT_NE(why.find(name), std::string::npos) << why;
  }
}

}  // namespace
}  // namespace cairn::inertial
