// `cairn navigate` end to end on the real Husky bag (robot_localization's test1.bag: IMU, wheel
// odometry and GPS, 395 s; bags/SOURCE.txt), with 60 s of GPS withheld, and its usage and
// bad-input errors. The reference for the withheld stretch is the receiver's own fixes (the bag),
// never the run. The Husky's parameters are docs/navigation.md's (the IMU's mounting from the
// bag's launch file, its white noise from the messages' covariances; the gyro-bias prior is the
// one tuned to this bag, as the library's test says).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"
#include "test_data.hpp"

namespace {

namespace fs = std::filesystem;

using Result = cairn::test::CliResult;
using cairn::test::csv_rows;
using cairn::test::slurp;

constexpr const char* kBag = "bags/robot_localization_test1.bag";

fs::path scratch() { return cairn::test::scratch_folder("navigate_test"); }

Result cairn_run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string q(const fs::path& p) { return cairn::test::quoted(p); }

// base_link -> imu_link of the launch file (x y z yaw pitch roll), the IMU's white noise from its
// covariances at 30 Hz, consumer-MEMS random walks, horizontal fixes (the altitude wanders).
const char* kHusky =
    " --imu-in-vehicle 0,-0.3,0.52,-1.570796327,0,1.570796327 --set gnss.use_altitude=false"
    " --set imu.gyro_noise_density=0.0036514837 --set imu.accel_noise_density=0.0178929"
    " --set imu.gyro_random_walk=4e-5 --set imu.accel_random_walk=4e-3"
    " --set priors.initial_gyro_bias_sigma_rad_s=0.0034906585";

TEST(NavigateCli, HuskyWithSixtySecondsOfGpsWithheldEndsCloserThanWheelOdometry) {
  CAIRN_REQUIRE_DATA(kBag);
  const fs::path out = scratch() / "husky";
  fs::remove_all(out);
  const Result r = cairn_run("navigate " + q(cairn::test::data_path(kBag)) + kHusky + " --withhold-gnss 150,210 --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  std::printf("%s", r.out.c_str());
  for (const char* file : {"report.json", "states.csv", "trajectory.tum", "navigation.png"}) EXPECT_TRUE(fs::exists(out / file)) << file;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["summary"]["status"], "ok");
  const nlohmann::json& w = report["withheld"];
  ASSERT_TRUE(w.is_object()) << report.dump();
  EXPECT_GT(w["fixes_withheld"].get<std::size_t>(), 100u);  // 2.5 Hz for 60 s
  EXPECT_EQ(w["fixes"].size(), w["fixes_withheld"].get<std::size_t>());
  ASSERT_TRUE(w["first_fix_back"].is_object());
  // The dead reckoning (IMU + wheels) ends closer to the first fix back than the wheels alone, and
  // stays closer over the gap (docs/navigation.md, "Measured").
  EXPECT_LT(w["first_fix_back"]["fused_m"].get<double>(), w["first_fix_back"]["wheel_odometry_m"].get<double>());
  EXPECT_LT(w["fused_rms_m"].get<double>(), w["wheel_odometry_rms_m"].get<double>());
  EXPECT_EQ(report["options"]["gnss"]["use_altitude"], false);
  EXPECT_EQ(report["inputs"]["gnss_fixes"].get<std::size_t>(),
            report["summary"]["fixes_received"].get<std::size_t>() + w["fixes_withheld"].get<std::size_t>());
  // One states.csv row and one trajectory pose per state.
  const auto rows = csv_rows(out / "states.csv", false);
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows.size() - 1, report["summary"]["states"].get<std::size_t>());
  EXPECT_EQ(csv_rows(out / "trajectory.tum", false).size(), report["summary"]["states"].get<std::size_t>());
  EXPECT_EQ(slurp(out / "navigation.png").substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
}

TEST(NavigateCli, PrintConfigNeedsNoBag) {
  const Result r = cairn_run("navigate --print-config --set wheels.nonholonomic_sigma_mps=0.2");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("nonholonomic_sigma_mps: 0.2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("gyro_noise_density"), std::string::npos);
}

TEST(NavigateCli, UsageErrorsStopBeforeAnyWork) {
  CAIRN_REQUIRE_DATA(kBag);
  const std::string bag = q(cairn::test::data_path(kBag));
  const fs::path out = scratch() / "usage";
  fs::remove_all(out);
  for (const std::string& args : {"navigate " + bag + " --withhold-gnss 210,150 --out " + q(out),
                                  "navigate " + bag + " --set wheels.no_such_key=1 --out " + q(out),
                                  "navigate " + bag + " --set window.window_states=1 --out " + q(out),
                                  "navigate " + bag + " --imu-in-vehicle 0,0,0,0,0 --out " + q(out),
                                  "navigate " + bag + " --antenna 0,nan,0 --out " + q(out),
                                  "navigate " + bag}) {
    const Result r = cairn_run(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_FALSE(r.err.empty()) << args;
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST(NavigateCli, BadInputsNameTheBagAndWriteNothing) {
  CAIRN_REQUIRE_DATA(kBag);
  const fs::path out = scratch() / "bad";
  fs::remove_all(out);
  // A missing file; a topic the bag does not have; a bag without IMU, odometry or GPS (a LaserScan bag).
  const fs::path missing = scratch() / "no_such.bag";
  Result r = cairn_run("navigate " + q(missing) + " --out " + q(out));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("no_such.bag"), std::string::npos) << r.err;
  r = cairn_run("navigate " + q(cairn::test::data_path(kBag)) + " --imu-topic /no/such/topic --out " + q(out));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("/no/such/topic"), std::string::npos) << r.err;
  const fs::path laser = cairn::test::data_path("bags/scan_tools_laser_scan_matcher_demo.bag");
  if (fs::exists(laser)) {
    r = cairn_run("navigate " + q(laser) + " --out " + q(out));
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find("scan_tools_laser_scan_matcher_demo.bag"), std::string::npos) << r.err;
  }
  // A file that is not a bag at all.
  const fs::path text = scratch() / "not_a_bag.bag";
  { std::ofstream(text) << "hello\n"; }
  r = cairn_run("navigate " + q(text) + " --out " + q(out));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("not_a_bag.bag"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
