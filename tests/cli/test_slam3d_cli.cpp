// `cairn slam3d` end to end: a short stretch of the real KITTI key frames with ground truth, and
// bad input (missing or empty folders, broken times tables, corrupt scans) with messages naming
// the file and line and a non-zero exit, never a partial output directory.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

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

// The configuration (lidar3d/config.hpp): --print-config lists every key of LidarSlamOptions and of
// the LiDAR-inertial fusion (InertialFusionOptions, section imu), and
// what it prints reads back through --config to the same text, with every key read from the file
// (the printed file starts from another preset and still gives the same configuration).
TEST(Slam3dCli, PrintConfigListsEveryKeyAndReadsBack) {
  const Result defaults = run("--print-config");
  ASSERT_EQ(defaults.status, 0) << defaults.err;
  EXPECT_EQ(defaults.out.rfind("# cairn slam3d configuration", 0), 0u) << defaults.out;
  std::istringstream lines(defaults.out);
  std::string line, section;
  std::set<std::string> keys;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (line[0] != ' ') {
      section = line.substr(0, line.find(':'));
    } else {
      EXPECT_NE(line.find("  # "), std::string::npos) << "a key without its meaning: " << line;
      keys.insert(section + "." + line.substr(2, line.find(':') - 2));
    }
  }
  // One key per field: LidarOdometryOptions 12 (with threads), RegistrationOptions 5,
  // LoamFeatureOptions 9, health 5, keyframes 2, ScanContextOptions 10, loop closure 14, back end 7;
  // InertialFusionOptions 16 (12 of its own, 4 of its static initialisation; noise and T_imu_lidar
  // come from files); GnssAnchoringOptions 9 (the lever arm is a flag).
  EXPECT_EQ(keys.size(), 89u) << defaults.out;
  for (const char* key : {"odometry.front_end", "odometry.deskew", "odometry.voxel_size_m", "odometry.threads",
                          "registration.metric", "registration.remap_degenerate_directions", "loam.neighbours",
                          "loam.less_flat_voxel_m", "health.min_scan_points", "health.lost_rms_max_correspondence_fraction",
                          "keyframes.distance_m", "keyframes.angle_rad", "scan_context.max_distance",
                          "scan_context.lateral_offsets_m", "loop_closure.enabled", "loop_closure.min_fitness",
                          "loop_closure.ambiguity_fitness_margin", "back_end.segment_break_rotation_sigma_rad",
                          "back_end.final_gnc"}) {
    EXPECT_EQ(keys.count(key), 1u) << key;
  }
  EXPECT_NE(defaults.out.find("\n  front_end: auto  #"), std::string::npos) << defaults.out;
  EXPECT_NE(defaults.out.find("\n  lateral_offsets_m: -4 -2 2 4  #"), std::string::npos) << defaults.out;

  const Result kitti = run("--print-config --preset kitti --set registration.metric=point-to-point "
                           "--set scan_context.lateral_offsets_m=none --set keyframes.distance_m=2.5 --set loam.neighbours=4");
  ASSERT_EQ(kitti.status, 0) << kitti.err;
  EXPECT_NE(kitti.out, defaults.out);
  EXPECT_NE(kitti.out.find("\n  front_end: dense  #"), std::string::npos) << kitti.out;
  EXPECT_NE(kitti.out.find("\n  metric: point-to-point  #"), std::string::npos) << kitti.out;
  EXPECT_NE(kitti.out.find("\n  lateral_offsets_m: none  #"), std::string::npos) << kitti.out;
  EXPECT_NE(kitti.out.find("\n  distance_m: 2.5  #"), std::string::npos) << kitti.out;
  const fs::path file = scratch() / "printed.yaml";
  std::ofstream(file) << kitti.out;
  const Result again = run("--print-config --config " + q(file));
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(again.out, kitti.out);
  std::ofstream(file) << defaults.out;
  const Result back = run("--print-config --preset kitti --config " + q(file));
  ASSERT_EQ(back.status, 0) << back.err;
  EXPECT_EQ(back.out, defaults.out);
}

// --set is applied after --preset and --config; the dedicated flags win over both.
TEST(Slam3dCli, DedicatedFlagsWinOverSettings) {
  Result r = run("--print-config --set odometry.threads=3 --set registration.metric=point-to-point");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\n  threads: 3  #"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  metric: point-to-point  #"), std::string::npos) << r.out;
  r = run("--print-config --set odometry.threads=3 --threads 1 --set registration.metric=point-to-point --metric "
          "point-to-plane --set loop_closure.enabled=true --no-loop-closure --set odometry.deskew=off --deskew azimuth");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\n  threads: 1  #"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  metric: point-to-plane  #"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  enabled: false  #"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  deskew: azimuth  #"), std::string::npos) << r.out;
}

// An unknown key, a value of the wrong type and options the validation refuses are usage errors
// (status 2) naming the key, found before any scan is read; a bad --config names file and line.
TEST(Slam3dCli, BadSettingsAreUsageErrorsNamingTheKey) {
  const fs::path out = scratch() / "o_bad_set";
  const std::string scans = q(scratch() / "no_such_folder");
  for (const auto& [assignment, expected] : std::vector<std::pair<std::string, std::string>>{
           {"odometry.no_such_key=1", "unknown key 'odometry.no_such_key'"},
           {"no_such_section.voxel_size_m=1", "unknown key 'no_such_section.voxel_size_m'"},
           {"registration.max_iterations=many", "registration.max_iterations"},
           {"registration.max_iterations=2.5", "registration.max_iterations"},
           {"odometry.voxel_size_m=abc", "odometry.voxel_size_m"},
           {"odometry.deskew=sideways", "odometry.deskew"},
           {"loop_closure.enabled=maybe", "loop_closure.enabled"},
           {"odometry.voxel_size_m=-1", "voxel_size_m must be > 0"},
           {"loam.neighbours=-1", "loam.neighbours"},
           {"scan_context.max_distance=3", "max_distance must be in [0, 2]"}}) {
    Result r = run(scans + " --out " + q(out) + " --set " + q(assignment));
    EXPECT_EQ(r.status, 2) << assignment << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << assignment << "\n" << r.err;
    r = run("--print-config --set " + q(assignment));
    EXPECT_EQ(r.status, 2) << assignment << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << assignment << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
  const fs::path config = scratch() / "bad_config.yaml";
  std::ofstream(config) << "odometry:\n  voxel_size_m: 0.5\n  no_such_key: 1\n";
  Result r = run("--print-config --config " + q(config));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad_config.yaml:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("odometry.no_such_key"), std::string::npos) << r.err;
  // Without --print-config, SCANS are required as before.
  r = run("--set odometry.voxel_size_m=0.5");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("SCANS is required"), std::string::npos) << r.err;
}

// report.json's "options" is the configuration in effect (configuration().json), with the preset, the
// front end kAuto chose and the written map's voxel beside it; --print-config with SCANS prints
// the configuration and runs.
TEST(Slam3dCli, ReportOptionsHoldTheSettings) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const fs::path scans = linked_scans("settings", 3);
  const fs::path out = scratch() / "o_settings";
  fs::remove_all(out);
  const Result r = run(q(scans) + " --set keyframes.distance_m=2.5 --set registration.metric=point-to-point "
                       "--set health.min_scan_points=50 --no-loop-closure --print-config -q --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.rfind("# cairn slam3d configuration", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("\n  distance_m: 2.5  #"), std::string::npos) << r.out;
  nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  nlohmann::json& options = report["options"];
  EXPECT_EQ(options["keyframes"]["distance_m"].get<double>(), 2.5);
  EXPECT_EQ(options["registration"]["metric"], "point-to-point");
  EXPECT_EQ(options["health"]["min_scan_points"], 50);
  EXPECT_EQ(options["loop_closure"]["enabled"], false);
  EXPECT_EQ(options["odometry"]["voxel_size_m"].get<double>(), 1.0);
  EXPECT_EQ(options["scan_context"]["lateral_offsets_m"], "-4 -2 2 4");
  EXPECT_EQ(options["preset"], "default");
  EXPECT_EQ(options["map_voxel_m"].get<double>(), 0.25);
  EXPECT_TRUE(options["front_end_used"] == "dense" || options["front_end_used"] == "loam") << options;
  EXPECT_EQ(report["input"]["scans_processed"], 3);
}

}  // namespace
