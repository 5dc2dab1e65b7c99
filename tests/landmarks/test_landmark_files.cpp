// Reading a simulator directory, writing the outputs, and refusing bad observation files with
// file:line messages.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/landmarks/landmark_run.hpp"
#include "cairn/landmarks/landmark_slam.hpp"
#include "cairn/landmarks/outputs.hpp"
#include "cairn/sim/scenario.hpp"
#include "simulated_run.hpp"

namespace cairn::landmarks {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_landmarks_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

// The message of the ParseError `f` throws ("" when it does not throw).
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const io::ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(LandmarkFiles, SimulatorDirectoryGivesTheSameRunAsMemoryAndOutputsAreWritten) {
  const fs::path dir = temp_dir("sim");
  const sim::Scenario scenario = *sim::make_scenario("landmarks");
  const sim::SimulationResult simulated = sim::simulate(scenario, 1);
  sim::write_outputs(simulated, scenario, 1, dir.string());

  const LandmarkRun from_files = read_landmark_run(dir.string());
  const LandmarkRun in_memory = testing::simulated_run(1);
  ASSERT_EQ(from_files.observations.size(), in_memory.observations.size());
  ASSERT_EQ(from_files.odometry.size(), in_memory.odometry.size());
  EXPECT_EQ(from_files.true_landmarks.size(), 60u);
  EXPECT_EQ(from_files.ground_truth.size(), in_memory.ground_truth.size());

  LandmarkSlamOptions options;
  options.nees_checkpoints = 2;
  const LandmarkSlamResult a = run_landmark_slam(from_files, options);
  const LandmarkSlamResult b = run_landmark_slam(in_memory, options);
  EXPECT_NEAR(a.report.ate_rmse_m, b.report.ate_rmse_m, 1e-9);
  EXPECT_LT(a.report.ate_rmse_m, 0.1);

  const fs::path out = temp_dir("out");
  write_trajectory_tum((out / "trajectory.tum").string(), a.trajectory);
  write_landmark_estimates_csv((out / "landmarks.csv").string(), a.landmarks);
  write_report_json((out / "report.json").string(), a.report);
  write_landmarks_png((out / "landmarks.png").string(), from_files, a);
  const io::Trajectory back = io::read_tum((out / "trajectory.tum").string());
  ASSERT_EQ(back.size(), a.trajectory.size());
  EXPECT_NEAR(back.poses.back().translation().x(), a.trajectory.back().pose.x(), 1e-12);
  EXPECT_GT(fs::file_size(out / "landmarks.png"), 1000u);
  EXPECT_NE(report_json(a.report).find("\"rmse_m\""), std::string::npos);
  std::ifstream csv(out / "landmarks.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "index,id,x_m,y_m,cov_xx_m2,cov_xy_m2,cov_yy_m2,observations");
  fs::remove_all(dir);
  fs::remove_all(out);
}

TEST(LandmarkFiles, BadObservationsAreRefusedWithFileAndLine) {
  const fs::path dir = temp_dir("bad");
  const fs::path path = dir / "obs.csv";
  const std::map<std::int64_t, Vector2> map = {{0, Vector2(1, 2)}, {1, Vector2(3, 4)}};
  const std::string header = "time_s,landmark_id,range_m,bearing_rad\n";
  const std::string good = "0.100000,0,2.5,0.1\n";
  struct Case {
    std::string line;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"0.200000,1,nan,0.1\n", "obs.csv:3: expected a finite number for range_m"},
      {"0.200000,1,-1.5,0.1\n", "obs.csv:3: expected range_m > 0"},
      {"0.200000,1,0,0.1\n", "obs.csv:3: expected range_m > 0"},
      {"0.200000,7,2.0,0.1\n", "obs.csv:3: landmark_id 7 is not in the landmark map"},
      {"0.200000,-3,2.0,0.1\n", "obs.csv:3: expected a non-negative integer for landmark_id"},
      {"0.200000,1,2.0,4.0\n", "obs.csv:3: expected bearing_rad in [-pi, pi]"},
      {"0.050000,1,2.0,0.1\n", "obs.csv:3: time_s goes backwards"},
      {"0.200000,1,2.0\n", "obs.csv:3: expected 4 comma-separated fields"},
  };
  for (const Case& c : cases) {
    write_text(path, header + good + c.line);
    const std::string message = error_of([&] { read_landmark_observations(path.string(), &map); });
    EXPECT_NE(message.find(c.expected), std::string::npos) << "line " << c.line << " gave: " << message;
  }
  write_text(path, "id,x_m,y_m\n");
  EXPECT_NE(error_of([&] { read_landmark_observations(path.string(), &map); }).find("obs.csv:1: expected the header"),
            std::string::npos);
  write_text(path, header + good);
  EXPECT_EQ(read_landmark_observations(path.string(), &map).size(), 1u);
  EXPECT_NE(error_of([&] { read_landmark_run((dir / "missing").string()); }).find("expected a directory"), std::string::npos);
  EXPECT_NE(error_of([&] { read_landmark_run(dir.string()); }).find("log.clf"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cairn::landmarks
