// `cairn slam3d --gnss` end to end on the simulator's tunnel (`cairn simulate tunnel-3d`: scans,
// times, poses, the IMU, and gnss/fixes.csv with gnss/truth.csv: no fix inside the tunnel, 5 % of
// the fixes jumps of 10-50 m). Expected values come from the simulator's files (the true antenna
// positions, which fixes are jumps, the ground truth), never from the run. Loop closure is off: the
// verification of the tunnel's look-alike places costs seconds per run and is not tested here.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/gnss/local_frame.hpp"
#include "cli_runner.hpp"

namespace {

namespace fs = std::filesystem;

using Result = cairn::test::CliResult;
using cairn::test::csv_rows;
using cairn::test::slurp;

fs::path scratch() { return cairn::test::scratch_folder("slam3d_gnss_test"); }

Result cairn_run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string q(const fs::path& p) { return cairn::test::quoted(p); }

// The simulated tunnel (seed 4: the seed whose IMU drifts most inside, docs/lidar3d.md) with 5 %
// GNSS jumps, written once per test program.
const fs::path& tunnel() {
  static const fs::path dir = [] {
    const fs::path d = scratch() / "tunnel";
    fs::remove_all(d);
    const Result r = cairn_run("simulate tunnel-3d --seed 4 -q --set gnss.outlier_fraction=0.05 --out " + q(d));
    EXPECT_EQ(r.status, 0) << r.err;
    return d;
  }();
  return dir;
}

std::string scans_args(const fs::path& d) {
  return q(d / "scans") + " --times " + q(d / "times.txt") + " --ground-truth " + q(d / "poses.txt") +
         " --ground-truth-format kitti --no-loop-closure -q";
}

TEST(Slam3dGnssCli, TunnelWithImuAndGnssEndsWithinAMetreAndFlagsEveryJump) {
  const fs::path out = scratch() / "o_gnss";
  fs::remove_all(out);
  const fs::path d = tunnel();
  const Result r = cairn_run("slam3d " + scans_args(d) + " --imu " + q(d / "imu0") + " --gnss " + q(d / "gnss" / "fixes.csv") +
                             " --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* file : {"gnss_fixes.csv", "trajectory_enu.tum", "report.json"}) EXPECT_TRUE(fs::exists(out / file)) << file;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  const nlohmann::json& g = report["gnss"];
  const auto truth = csv_rows(d / "gnss" / "truth.csv", false);  // header, then time_s, east_m, north_m, up_m, outlier
  const auto fixes = csv_rows(out / "gnss_fixes.csv", false);     // header, then one row per fix
  ASSERT_GT(truth.size(), 20u);
  ASSERT_EQ(fixes.size(), truth.size());
  EXPECT_EQ(g["fixes"].get<std::size_t>(), truth.size() - 1);
  EXPECT_TRUE(g["aligned"].get<bool>());
  EXPECT_TRUE(report["options"]["gnss"].contains("max_fix_gap_s"));

  // Every jump the simulator made is flagged.
  std::size_t jumps = 0, flagged = 0;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    ASSERT_EQ(fixes[i].size(), 12u) << i;
    EXPECT_NEAR(std::stod(fixes[i][0]), std::stod(truth[i][0]), 1e-6) << i;
    if (truth[i][4] == "1") {
      ++jumps;
      flagged += fixes[i][7] == "1" ? 1 : 0;
    }
  }
  EXPECT_GT(jumps, 0u);
  EXPECT_EQ(flagged, jumps);

  // The estimated antenna (the fix plus its error, in the SLAM's ENU frame at the first fix) at
  // every fix after the tunnel, against the simulator's true antenna (its ENU frame at its origin).
  const nlohmann::json manifest = nlohmann::json::parse(slurp(d / "manifest.json"));
  const nlohmann::json& origin = manifest["gnss"]["origin"];
  const cairn::gnss::LocalFrame receiver({origin["latitude_deg"].get<double>(), origin["longitude_deg"].get<double>(),
                                          origin["altitude_m"].get<double>()});
  const nlohmann::json& o = g["enu_origin"];
  const cairn::gnss::LocalFrame slam({o["latitude_deg"].get<double>(), o["longitude_deg"].get<double>(), o["altitude_m"].get<double>()});
  double worst_after_m = 0.0;
  const double last_fix_s = std::stod(truth.back()[0]);
  for (std::size_t i = 1; i < truth.size(); ++i) {
    if (std::stod(truth[i][0]) < last_fix_s - 5.0) continue;  // the last 5 s: after the tunnel
    const cairn::Vector3 estimate(std::stod(fixes[i][1]) + std::stod(fixes[i][9]), std::stod(fixes[i][2]) + std::stod(fixes[i][10]),
                                  std::stod(fixes[i][3]) + std::stod(fixes[i][11]));
    const cairn::Vector3 in_receiver = receiver.forward(slam.reverse(estimate));
    const cairn::Vector3 true_antenna(std::stod(truth[i][1]), std::stod(truth[i][2]), std::stod(truth[i][3]));
    worst_after_m = std::max(worst_after_m, (in_receiver - true_antenna).norm());
  }
  const double end_m = report["ground_truth"]["end_point_error_m"].get<double>();
  const double path_m = report["ground_truth"]["path_length_m"].get<double>();
  std::printf("tunnel-3d seed 4, LiDAR-inertial with GNSS outside the tunnel: end-point error %.2f m of %.0f m, worst antenna "
              "error over the last 5 s of fixes %.2f m; %zu of %zu jumps flagged\n",
              end_m, path_m, worst_after_m, flagged, jumps);
  EXPECT_LT(worst_after_m, 1.0);
  EXPECT_LT(end_m, 0.01 * path_m);
}

TEST(Slam3dGnssCli, FlagsThatDoNotGoTogetherAreUsageErrors) {
  const fs::path out = scratch() / "o_usage";
  fs::remove_all(out);
  const fs::path d = tunnel();
  const std::string base = "slam3d " + scans_args(d) + " --max-scans 3 --out " + q(out);
  for (const std::string& extra : {std::string(" --gnss-lever-arm 0,0,1"), std::string(" --gnss-topic /fix"),
                                   " --gnss " + q(d / "gnss" / "fixes.csv") + " --gnss-topic /fix",
                                   " --gnss " + q(d / "gnss" / "fixes.csv") + " --gnss-lever-arm 1,2"}) {
    const Result r = cairn_run(base + extra);
    EXPECT_EQ(r.status, 2) << extra << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << extra;
  }
}

TEST(Slam3dGnssCli, ABadFixFileStopsWithFileAndLineAndWritesNothing) {
  const fs::path bad = scratch() / "bad_fixes.csv";
  {
    std::istringstream lines(slurp(tunnel() / "gnss" / "fixes.csv"));
    std::ofstream csv(bad);
    std::string line;
    for (int k = 1; k <= 12 && std::getline(lines, line); ++k) csv << (k == 6 ? line.substr(0, line.find(',')) + ",91,8.5,400,0.5,0.5,1,0" : line) << '\n';
  }
  const fs::path out = scratch() / "o_bad";
  fs::remove_all(out);
  const Result r = cairn_run("slam3d " + scans_args(tunnel()) + " --max-scans 3 --gnss " + q(bad) + " --out " + q(out));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("bad_fixes.csv:6"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// Fixes on another clock (here a million seconds later, as UNIX times against scans from zero)
// fall among no scan: the run goes on without them and says why.
TEST(Slam3dGnssCli, FixesOnAnotherClockAreNotUsedAndTheRunSaysSo) {
  const fs::path shifted = scratch() / "shifted_fixes.csv";
  {
    std::istringstream lines(slurp(tunnel() / "gnss" / "fixes.csv"));
    std::ofstream csv(shifted);
    std::string line;
    bool header = false;
    while (std::getline(lines, line)) {
      if (line.empty() || line[0] == '#' || !header) {
        header = header || (!line.empty() && line[0] != '#');
        csv << line << '\n';
        continue;
      }
      const std::size_t comma = line.find(',');
      csv << std::to_string(std::stod(line.substr(0, comma)) + 1e6) << line.substr(comma) << '\n';
    }
  }
  const fs::path out = scratch() / "o_clock";
  fs::remove_all(out);
  const Result r = cairn_run("slam3d " + q(tunnel() / "scans") + " --times " + q(tunnel() / "times.txt") +
                             " --no-loop-closure --max-scans 20 --gnss " + q(shifted) + " --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("on the scans' clock"), std::string::npos) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["gnss"]["placed"].get<std::size_t>(), 0u);
  EXPECT_EQ(report["gnss"]["used"].get<std::size_t>(), 0u);
  EXPECT_FALSE(report["gnss"]["aligned"].get<bool>());
  EXPECT_EQ(report["gnss"]["warnings"].size(), 1u);
  EXPECT_FALSE(fs::exists(out / "trajectory_enu.tum"));
}

}  // namespace
