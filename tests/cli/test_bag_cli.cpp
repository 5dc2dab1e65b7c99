// `cairn` on bags, end to end: info, slam2d on the real LaserScan bag with --mcap read back by
// Foxglove's @mcap/core, slam3d on python3-rosbag and @mcap/core bags of the KITTI scans against
// the folder run of the same scans, convert and eval BAG:/topic on the real Husky bag.
// Fixtures come from tests/bag/fixtures/make_all.sh ($CAIRN_BAG_FIXTURES, ctest fixture bag_fixtures).

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/cli_runner.hpp"
#include "test_data.hpp"

namespace {

using cairn::test::CliResult;
using cairn::test::slurp;
namespace fs = std::filesystem;

fs::path scratch() { return cairn::test::scratch_folder("bag_cli"); }
fs::path fixtures() {
  const char* dir = std::getenv("CAIRN_BAG_FIXTURES");
  return dir != nullptr ? dir : "";
}
std::string data(const std::string& relative) { return "'" + cairn::test::data_path(relative).string() + "'"; }
CliResult run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

#define REQUIRE_FIXTURE(name)                                                                              \
  do {                                                                                                     \
    if (!fs::exists(fixtures() / (name))) GTEST_SKIP() << "fixture " << (fixtures() / (name)) << " not made"; \
  } while (false)

std::size_t lines_of(const fs::path& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += (!line.empty() && line[0] != '#') ? 1 : 0;
  return n;
}

// Counts from bags/SOURCE.txt (rosbag's own listing of the file).
TEST(BagCli, InfoListsTheHuskyTopicsAsRosbagDoes) {
  CAIRN_REQUIRE_DATA("bags/robot_localization_test1.bag");
  const CliResult r = run("info " + data("bags/robot_localization_test1.bag") + " --json -");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["format"], "ROS 1 bag 2.0");
  EXPECT_EQ(j["messages"], 11865 + 3952 + 989);
  std::map<std::string, std::uint64_t> counts;
  for (const auto& t : j["topics"]) counts[t["name"].get<std::string>()] = t["messages"].get<std::uint64_t>();
  EXPECT_EQ(counts["/imu/data"], 11865u);
  EXPECT_EQ(counts["/husky_velocity_controller/odom"], 3952u);
  EXPECT_EQ(counts["/fix"], 989u);
  EXPECT_TRUE(j["files"][0]["chunks"].contains("bz2"));
  EXPECT_NEAR(j["duration_s"].get<double>(), 395.0, 1.0);
}

TEST(BagCli, AMissingTopicListsTheTopicsThereAre) {
  CAIRN_REQUIRE_DATA("bags/scan_tools_laser_scan_matcher_demo.bag");
  const CliResult r = run("slam2d " + data("bags/scan_tools_laser_scan_matcher_demo.bag") + " --scan-topic /base_scan --out '" +
                          (scratch() / "missing").string() + "'");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("no topic '/base_scan'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/scan (sensor_msgs/LaserScan)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "missing"));
}

TEST(BagCli, Slam2dRunsOnTheRealLaserScanBagAndItsMcapReadsBackInMcapCore) {
  CAIRN_REQUIRE_DATA("bags/scan_tools_laser_scan_matcher_demo.bag");
  REQUIRE_FIXTURE("kitti_points.mcap.json");  // made by make_all.sh when @mcap/core is installed
  const fs::path out = scratch() / "slam2d";
  const fs::path mcap = scratch() / "slam2d.mcap";
  fs::remove_all(out);
  const CliResult r =
      run("slam2d " + data("bags/scan_tools_laser_scan_matcher_demo.bag") + " -q --out '" + out.string() + "' --mcap '" + mcap.string() + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* file : {"map.png", "map.pgm", "trajectory.tum", "report.json"}) EXPECT_TRUE(fs::exists(out / file)) << file;
  EXPECT_EQ(lines_of(out / "trajectory.tum"), 360u);  // every scan of the bag (rosbag: 360)
  const std::string reader = std::string(CAIRN_SOURCE_DIR) + "/tests/bag/fixtures/mcap/read_mcap.mjs";
  const CliResult read = cairn::test::run_command("node", "'" + reader + "' '" + mcap.string() + "'", scratch() / "node.txt");
  ASSERT_EQ(read.status, 0) << read.err;
  const nlohmann::json j = nlohmann::json::parse(read.out);
  EXPECT_EQ(j["indexed"], true);
  std::map<std::string, std::pair<std::string, std::uint64_t>> channels;
  for (const auto& c : j["channels"]) {
    channels[c["topic"].get<std::string>()] = {c["schemaName"].get<std::string>(), c["messageCount"].get<std::uint64_t>()};
  }
  EXPECT_EQ(channels["/pose"], std::make_pair(std::string("foxglove.PoseInFrame"), std::uint64_t{360}));
  EXPECT_EQ(channels["/tf"], std::make_pair(std::string("foxglove.FrameTransform"), std::uint64_t{360}));
  EXPECT_EQ(channels["/trajectory"], std::make_pair(std::string("foxglove.PosesInFrame"), std::uint64_t{1}));
  EXPECT_EQ(channels["/grid"], std::make_pair(std::string("foxglove.Grid"), std::uint64_t{1}));
  EXPECT_EQ(channels["/health"].first, "foxglove.Log");
}

TEST(BagCli, Localize2dOnTheBagInTheMapSlam2dSavedFromIt) {
  CAIRN_REQUIRE_DATA("bags/scan_tools_laser_scan_matcher_demo.bag");
  const fs::path map_run = scratch() / "slam2d_for_map";
  const fs::path map = scratch() / "scan_tools.cmap";
  const fs::path out = scratch() / "localize2d";
  fs::remove_all(map_run);
  fs::remove_all(out);
  fs::remove(map);
  const std::string bag = data("bags/scan_tools_laser_scan_matcher_demo.bag");
  ASSERT_EQ(run("slam2d " + bag + " -q --out '" + map_run.string() + "' --save-map '" + map.string() + "'").status, 0);
  const CliResult r = run("localize2d " + bag + " --map '" + map.string() + "' -q --out '" + out.string() + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  // Against the SLAM trajectory of the same scans: the localiser places them where the map was built.
  const CliResult e = run("eval ape '" + (map_run / "trajectory.tum").string() + "' '" + (out / "trajectory.tum").string() +
                          "' --align none --json -");
  ASSERT_EQ(e.status, 0) << e.err;
  const nlohmann::json j = nlohmann::json::parse(e.out);
  EXPECT_GE(j["association"]["pairs"].get<int>(), 340);
  EXPECT_LT(j["statistics"]["rmse"].get<double>(), 0.10);
}

TEST(BagCli, VslamOnAnRgbdBagWritesItsMcapForFoxglove) {
  REQUIRE_FIXTURE("frames20/tum_rgbd.bag");
  REQUIRE_FIXTURE("kitti_points.mcap.json");  // @mcap/core installed
  const fs::path out = scratch() / "vslam";
  const fs::path mcap = scratch() / "vslam.mcap";
  fs::remove_all(out);
  const CliResult r = run("vslam '" + (fixtures() / "frames20/tum_rgbd.bag").string() + "' --depth-scale 5000 -q --out '" +
                          out.string() + "' --mcap '" + mcap.string() + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string reader = std::string(CAIRN_SOURCE_DIR) + "/tests/bag/fixtures/mcap/read_mcap.mjs";
  const CliResult read = cairn::test::run_command("node", "'" + reader + "' '" + mcap.string() + "'", scratch() / "node.txt");
  ASSERT_EQ(read.status, 0) << read.err;
  const nlohmann::json j = nlohmann::json::parse(read.out);
  std::map<std::string, std::uint64_t> counts;
  for (const auto& c : j["channels"]) counts[c["topic"].get<std::string>()] = c["messageCount"].get<std::uint64_t>();
  EXPECT_EQ(counts["/pose"], lines_of(out / "trajectory.tum"));
  EXPECT_EQ(counts["/pose"], 20u);
  EXPECT_EQ(counts["/map"], 1u);
}

/// slam3d on a bag of the first 10 KITTI key frames (every point) against the folder run of the
/// same files with the same times: the trajectory files must be byte-identical.
void expect_slam3d_bag_equals_folder(const std::string& bag) {
  const fs::path folder_out = scratch() / "slam3d_folder";
  if (!fs::exists(folder_out / "trajectory.tum")) {
    const CliResult r = run("slam3d " + data("lidar3d/kitti00_keyframes/key_frames") + " --preset kitti --times " +
                            data("lidar3d/kitti00_keyframes/keyframes.txt") + " --times-column 4 --max-scans 10 -q --out '" +
                            folder_out.string() + "'");
    ASSERT_EQ(r.status, 0) << r.err;
  }
  const fs::path bag_out = scratch() / ("slam3d_" + fs::path(bag).filename().string());
  const fs::path mcap = scratch() / ("slam3d_" + fs::path(bag).filename().string() + ".mcap");
  const CliResult r = run("slam3d '" + (fixtures() / bag).string() + "' --preset kitti -q --out '" + bag_out.string() +
                          "' --mcap '" + mcap.string() + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string expected = slurp(folder_out / "trajectory.tum");
  EXPECT_EQ(lines_of(folder_out / "trajectory.tum"), 10u);
  EXPECT_EQ(slurp(bag_out / "trajectory.tum"), expected) << bag;
  EXPECT_EQ(slurp(bag_out / "trajectory.kitti"), slurp(folder_out / "trajectory.kitti")) << bag;
  EXPECT_TRUE(fs::exists(mcap));
}

TEST(BagCli, Slam3dOnARosbagWrittenBagEqualsTheFolderRun) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes");
  REQUIRE_FIXTURE("full/kitti_points.bag");
  expect_slam3d_bag_equals_folder("full/kitti_points.bag");
}

TEST(BagCli, Slam3dOnAnMcapCoreWrittenFileEqualsTheFolderRun) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes");
  REQUIRE_FIXTURE("full/kitti_points.mcap");
  expect_slam3d_bag_equals_folder("full/kitti_points.mcap");
}

TEST(BagCli, ConvertExtractsTheHuskyBagAndEvalReadsABagTopic) {
  CAIRN_REQUIRE_DATA("bags/robot_localization_test1.bag");
  const fs::path out = scratch() / "husky";
  fs::remove_all(out);
  const CliResult r = run("convert " + data("bags/robot_localization_test1.bag") + " '" + out.string() + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(lines_of(out / "imu_data.csv"), 11865u);
  EXPECT_EQ(lines_of(out / "fix.csv"), 989u);
  EXPECT_EQ(lines_of(out / "husky_velocity_controller_odom.tum"), 3952u);
  // The odometry topic read straight from the bag against its TUM extraction: the same poses.
  const CliResult e = run("eval ape " + data("bags/robot_localization_test1.bag") + ":/husky_velocity_controller/odom '" +
                          (out / "husky_velocity_controller_odom.tum").string() + "' --align none --json -");
  ASSERT_EQ(e.status, 0) << e.err;
  const nlohmann::json j = nlohmann::json::parse(e.out);
  EXPECT_EQ(j["association"]["pairs"], 3952);
  EXPECT_LT(j["statistics"]["max"].get<double>(), 1e-6);
  // A second convert into the same folder is refused without --overwrite.
  EXPECT_NE(run("convert " + data("bags/robot_localization_test1.bag") + " '" + out.string() + "'").status, 0);
}

}  // namespace
