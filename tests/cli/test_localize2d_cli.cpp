// `cairn slam2d --save-map` and `cairn localize2d` end to end: the files, the report's facts, and
// clear errors for a map file that is missing, corrupt, truncated or not a map at all.

#include <gtest/gtest.h>

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

fs::path scratch() { return cairn::test::scratch_folder("localize2d_cli"); }

Result run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

const char* kIntel = "laser2d/intel/intel.clf.bz2";

// The map of Intel's first 800 scans, written once for the tests below.
const fs::path& intel_map() {
  static const fs::path map = [] {
    const fs::path out = scratch() / "slam";
    const fs::path file = scratch() / "intel-800.cmap";
    fs::remove_all(out);
    const Result r = run("slam2d " + quoted(cairn::test::data_path(kIntel)) + " --max-scans 800 --out " + quoted(out) +
                         " --save-map " + quoted(file) + " -q");
    EXPECT_EQ(r.status, 0) << r.err;
    return file;
  }();
  return map;
}

TEST(Localize2dCli, SaveMapThenLocaliseWritesEveryOutput) {
  CAIRN_REQUIRE_DATA(kIntel);
  const fs::path& map = intel_map();
  ASSERT_TRUE(fs::exists(map));
  const nlohmann::json slam_report = nlohmann::json::parse(slurp(scratch() / "slam" / "report.json"));
  EXPECT_EQ(slam_report["saved_map"]["format_version"], 1);
  EXPECT_EQ(slam_report["saved_map"]["bytes"].get<std::uintmax_t>(), fs::file_size(map));

  // Scans 400..549 of the same log, from no prior; the slam2d trajectory is the ground truth.
  const fs::path out = scratch() / "localised";
  fs::remove_all(out);
  const Result r = run("localize2d " + quoted(cairn::test::data_path(kIntel)) + " --map " + quoted(map) + " --out " +
                       quoted(out) + " --first-scan 400 --max-scans 150 --ground-truth " +
                       quoted(scratch() / "slam" / "trajectory.tum"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("localised at scan"), std::string::npos) << r.out;
  for (const char* name : {"map.png", "trajectory.tum", "scans.csv", "report.json"})
    EXPECT_TRUE(fs::exists(out / name)) << name;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["input"]["scans"], 150);
  EXPECT_EQ(report["input"]["first_scan"], 400);
  EXPECT_FALSE(report["interrupted"].get<bool>());
  ASSERT_FALSE(report["summary"]["first_localised_scan"].is_null());
  EXPECT_LE(report["summary"]["first_localised_scan"].get<int>(), 10);
  ASSERT_GE(report["relocalisations"].size(), 1u);
  EXPECT_GE(report["relocalisations"][0]["evidence"].size(), 2u);  // confirmed by two scans
  EXPECT_EQ(report["ground_truth"]["relocalisations_off_by_more_than_0.3_m_or_3_deg"], 0);
  EXPECT_LT(report["ground_truth"]["translation_error_m"]["mean"].get<double>(), 0.1);
  // scans.csv: a header and one line per scan; no pose for a scan that was not localised.
  std::istringstream csv(slurp(out / "scans.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("time_s,state,health,localised,x_m,y_m,theta_rad,confidence", 0), 0u) << line;
  int lines = 0, without_pose = 0;
  while (std::getline(csv, line)) {
    ++lines;
    if (line.find(",searching,lost,0,,,,") != std::string::npos) ++without_pose;
  }
  EXPECT_EQ(lines, 150);
  EXPECT_EQ(without_pose, report["summary"]["first_localised_scan"].get<int>());

  // The directory now holds files: refused without --overwrite, before any work.
  const Result again = run("localize2d " + quoted(cairn::test::data_path(kIntel)) + " --map " + quoted(map) + " --out " +
                           quoted(out) + " --max-scans 5 -q");
  EXPECT_EQ(again.status, 1);
  EXPECT_NE(again.err.find("--overwrite"), std::string::npos) << again.err;
}

TEST(Localize2dCli, BadMapFilesGiveClearErrors) {
  CAIRN_REQUIRE_DATA(kIntel);
  const std::string log = quoted(cairn::test::data_path(kIntel));
  auto localise = [&](const fs::path& map) {
    const fs::path out = scratch() / "bad-map-out";
    const Result r = run("localize2d " + log + " --map " + quoted(map) + " --out " + quoted(out) + " --max-scans 5 -q");
    EXPECT_FALSE(fs::exists(out)) << "a failed run leaves no output directory";
    return r;
  };
  const fs::path g2o = scratch() / "graph.g2o";
  std::ofstream(g2o) << "VERTEX_SE2 0 0 0 0\n";
  Result r = localise(g2o);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(g2o.string() + ": not a cairn 2D map file"), std::string::npos) << r.err;

  r = localise(scratch() / "missing.cmap");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("missing.cmap: cannot open"), std::string::npos) << r.err;

  const std::string bytes = slurp(intel_map());
  ASSERT_GT(bytes.size(), 1000u);
  const fs::path truncated = scratch() / "truncated.cmap";
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  r = localise(truncated);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("(truncated)"), std::string::npos) << r.err;

  std::string flipped = bytes;
  flipped[bytes.size() / 3] = static_cast<char>(flipped[bytes.size() / 3] ^ 0x04);
  const fs::path corrupt = scratch() / "corrupt.cmap";
  std::ofstream(corrupt, std::ios::binary) << flipped;
  r = localise(corrupt);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("checksum mismatch"), std::string::npos) << r.err;

  r = run("localize2d " + log + " --out " + quoted(scratch() / "no-map"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--map FILE is required"), std::string::npos) << r.err;

  r = run("slam2d " + log + " --max-scans 5 --out " + quoted(scratch() / "map-to-stdout") + " --save-map - -q");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--save-map needs a file"), std::string::npos) << r.err;
}

}  // namespace
