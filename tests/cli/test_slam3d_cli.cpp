// `cairn slam3d` end to end: a short stretch of the real KITTI key frames with ground truth, and
// bad input (missing or empty folders, broken times tables, corrupt scans) with messages naming
// the file and line and a non-zero exit, never a partial output directory.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_runner.hpp"
#include "test_data.hpp"

namespace {

namespace fs = std::filesystem;

using Result = cairn::test::CliResult;
using cairn::test::slurp;

std::filesystem::path scratch() { return cairn::test::scratch_folder("slam3d_test"); }

Result run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY + std::string(" slam3d"), args, scratch() / "stderr.txt"); }

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

const char* kKitti = "lidar3d/kitti00_keyframes";

// A folder of `count` links to the first KITTI key frames, named 0.pcd.xz, 1.pcd.xz, ...
fs::path linked_scans(const std::string& name, int count) {
  const fs::path dir = scratch() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (int k = 0; k < count; ++k) {
    fs::create_symlink(cairn::test::data_path(std::string(kKitti) + "/key_frames/key_frame_" + std::to_string(k) + ".pcd.xz"),
                       dir / (std::to_string(k) + ".pcd.xz"));
  }
  return dir;
}

TEST(Slam3dCli, RealKittiStretchWritesEveryOutputAndMeasuresIt) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const fs::path root = cairn::test::data_path(kKitti);
  const fs::path out = scratch() / "kitti_run";
  fs::remove_all(out);
  const Result r = run(q(root / "key_frames") + " --max-scans 8 --times " + q(root / "keyframes.txt") +
                       " --times-column 4 --ground-truth " + q(root / "poses_keyframes.txt") +
                       " --ground-truth-format kitti --preset kitti --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("end-point error"), std::string::npos) << r.out;
  const auto report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["input"]["scans_processed"], 8);
  EXPECT_EQ(report["scans"].size(), 8u);
  EXPECT_EQ(report["summary"]["scans_ok"], 8);
  // Natural order: key_frame_10 must not come before key_frame_2 (the folder has 110 scans).
  EXPECT_NE(report["scans"][2]["file"].get<std::string>().find("key_frame_2.pcd.xz"), std::string::npos);
  // 8 key frames, about 14 m: the odometry must stay within decimetres of the GNSS/INS truth.
  EXPECT_LT(report["ground_truth"]["end_point_error_m"].get<double>(), 0.3);
  EXPECT_LT(report["ground_truth"]["rpe_translation_rmse_m"].get<double>(), 0.1);
  EXPECT_GT(report["ground_truth"]["path_length_m"].get<double>(), 10.0);
  // The trajectory files hold one pose per scan; the map is a readable PLY of the stated size.
  std::istringstream kitti(slurp(out / "trajectory.kitti"));
  std::string line;
  int lines = 0;
  while (std::getline(kitti, line)) ++lines;
  EXPECT_EQ(lines, 8);
  const std::string ply = slurp(out / "map.ply");
  const std::string count = "element vertex " + std::to_string(report["summary"]["map_points"].get<std::size_t>()) + "\n";
  EXPECT_EQ(ply.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(ply.find(count), std::string::npos);
  const std::size_t header_end = ply.find("end_header\n") + 11;
  EXPECT_EQ(ply.size() - header_end, 12 * report["summary"]["map_points"].get<std::size_t>());
  EXPECT_EQ(slurp(out / "map.png").substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // The same run again into the same folder is refused without --overwrite.
  const Result again = run(q(root / "key_frames") + " --max-scans 2 --out " + q(out) + " -q");
  EXPECT_EQ(again.status, 1);
}

TEST(Slam3dCli, MissingOrEmptyInputsAreNamed) {
  const fs::path empty = scratch() / "empty_folder";
  fs::create_directories(empty);
  Result r = run(q(scratch() / "no_such_folder") + " --out " + q(scratch() / "o1"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no_such_folder"), std::string::npos) << r.err;
  r = run(q(empty) + " --out " + q(scratch() / "o2"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no scan files"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "o2"));
  r = run(q(empty));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
}

TEST(Slam3dCli, BrokenTimesTablesNameFileAndLine) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const fs::path scans = linked_scans("three", 3);
  const fs::path bad_number = scratch() / "times_bad.txt";
  std::ofstream(bad_number) << "# t\n0.0\n0.1\nnan\n";
  Result r = run(q(scans) + " --times " + q(bad_number) + " --out " + q(scratch() / "o3"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("times_bad.txt:4"), std::string::npos) << r.err;
  const fs::path short_table = scratch() / "times_short.txt";
  std::ofstream(short_table) << "0.0\n0.1\n";
  r = run(q(scans) + " --times " + q(short_table) + " --out " + q(scratch() / "o4"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("times_short.txt"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("3 scans"), std::string::npos) << r.err;
  const fs::path backwards = scratch() / "times_back.txt";
  std::ofstream(backwards) << "1 0.0\n2 0.2\n3 0.1\n";
  r = run(q(scans) + " --times " + q(backwards) + " --times-column 2 --out " + q(scratch() / "o5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("times_back.txt:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("increase"), std::string::npos) << r.err;
  r = run(q(scans) + " --times " + q(backwards) + " --times-column 3 --out " + q(scratch() / "o6"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("times_back.txt:1"), std::string::npos) << r.err;
  // Windows line ends are read, not refused.
  const fs::path crlf = scratch() / "times_crlf.txt";
  std::ofstream(crlf) << "# t\r\n0.0\r\n0.1\r\n0.2\r\n";
  r = run(q(scans) + " --times " + q(crlf) + " --out " + q(scratch() / "o6b") + " -q");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "o3"));
}

TEST(Slam3dCli, ACorruptScanStopsTheRunOrIsSkippedWithLenient) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const fs::path scans = linked_scans("with_corrupt", 4);
  fs::remove(scans / "2.pcd.xz");
  std::ofstream(scans / "2.pcd") << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                                    "WIDTH 1000\nHEIGHT 1\nPOINTS 1000\nDATA binary\nshort";
  const fs::path out = scratch() / "o7";
  Result r = run(q(scans) + " --out " + q(out));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("2.pcd"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));  // written whole or not at all
  r = run(q(scans) + " --lenient --out " + q(out) + " -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["input"]["scans_processed"], 3);
  ASSERT_EQ(report["input"]["skipped"].size(), 1u);
  EXPECT_NE(report["input"]["skipped"][0]["file"].get<std::string>().find("2.pcd"), std::string::npos);
}

TEST(Slam3dCli, AShortGroundTruthAndBadOptionsAreRefused) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const fs::path scans = linked_scans("gt", 3);
  const fs::path gt = scratch() / "gt.kitti";
  std::ofstream(gt) << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n";
  Result r = run(q(scans) + " --ground-truth " + q(gt) + " --ground-truth-format kitti --out " + q(scratch() / "o8"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("gt.kitti"), std::string::npos) << r.err;
  r = run(q(scans) + " --preset nope --out " + q(scratch() / "o9"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("preset"), std::string::npos) << r.err;
  // A flag value out of its range is refused while the flags are parsed (status 2, as every
  // usage error), before any scan is read.
  r = run(q(scans) + " --map-voxel 0 --out " + q(scratch() / "o10"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--map-voxel"), std::string::npos) << r.err;
  r = run(q(scans) + " --metric nearest --out " + q(scratch() / "o11"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--metric"), std::string::npos) << r.err;
}

}  // namespace
