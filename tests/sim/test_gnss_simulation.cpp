// The 3D scenarios' simulated GNSS receiver (Scenario::gnss, gnss/fixes.csv, gnss/truth.csv):
// no fix inside tunnel-3d's tunnel, fixes before and after it; the written CSV read back by
// gnss::read_gnss_csv and put into metres by gnss::LocalFrame (GeographicLib) lands on the
// simulated measurement; the ENU truth is R_z(world yaw) times the LiDAR's true position, built
// here from the ground-truth body pose and the mount height; the GNSS's own random stream leaves
// every other file byte for byte as it was.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "cairn/gnss/gnss_reader.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/sim/manifest.hpp"
#include "cairn/sim/scenario.hpp"
#include "scratch_directory.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;

using test::bytes_of;
using test::ScratchDirectory;

/// Sets the named parameter of `scenario` (as `--set NAME=VALUE` does).
void set(Scenario& scenario, const std::string& name, const std::string& value) {
  for (auto& p : parameters(scenario)) {
    if (p.name != name) continue;
    std::string why;
    if (!p.set(value, &why)) throw std::runtime_error(why);
    return;
  }
  throw std::runtime_error("no parameter " + name);
}

/// tunnel-3d (150 m tunnel, 40 m approaches, 6 m/s) with a 4-column LiDAR: the GNSS is about the
/// trajectory, not the scans.
Scenario fast_tunnel() {
  Scenario s = *make_scenario("tunnel-3d");
  s.lidar3d.columns = 4;
  return s;
}

/// R_z(yaw_deg), written out.
Matrix3 rotation_z(double yaw_deg) {
  const double a = yaw_deg * std::numbers::pi / 180.0;
  Matrix3 R;
  R << std::cos(a), -std::sin(a), 0.0, std::sin(a), std::cos(a), 0.0, 0.0, 0.0, 1.0;
  return R;
}

/// The ground-truth sample stamped `stamp` (GNSS epochs fall on samples: 0.2 s = 20 x 10 ms).
const TrajectorySample& sample_at(const SimulationResult& result, core::Timestamp stamp) {
  const auto it = std::lower_bound(result.truth.begin(), result.truth.end(), stamp,
                                   [](const TrajectorySample& s, core::Timestamp t) { return s.stamp < t; });
  if (it == result.truth.end() || it->stamp != stamp) throw std::runtime_error("no ground-truth sample at a fix's stamp");
  return *it;
}

/// The LiDAR's true world position: mount_height_m straight above the planar body pose.
Vector3 lidar_position(const TrajectorySample& sample, const Scenario& scenario) {
  return {sample.T_world_body.x(), sample.T_world_body.y(), scenario.lidar3d.mount_height_m};
}

TEST(SimulatedGnss, NoFixInsideTheTunnelAndFixesBeforeAndAfterIt) {
  const Scenario scenario = fast_tunnel();
  std::string why;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const SimulationResult result = simulate(scenario, 1);
  const SimulatedGnss& gnss = result.gnss;
  const double length_m = scenario.tunnel.length_m;  // the tunnel spans world x in [0, length_m]
  const Matrix3 R_world_enu = rotation_z(30.0).transpose();
  std::size_t before = 0, after = 0;
  for (std::size_t i = 0; i < gnss.fixes.size(); ++i) {
    const double x_m = (R_world_enu * gnss.p_enu_true_m[i]).x();
    EXPECT_FALSE(x_m >= 0.0 && x_m <= length_m) << "fix " << i << " at x = " << x_m;
    before += x_m < 0.0 ? 1 : 0;
    after += x_m > length_m ? 1 : 0;
  }
  EXPECT_GT(before, 20u);
  EXPECT_GT(after, 20u);
  // Every epoch (every 0.2 s from the first sample) counted once: a fix outside, blocked inside.
  std::size_t epochs = 0, inside = 0;
  for (std::size_t k = 0; k < result.truth.size(); k += 20) {
    ++epochs;
    const double x_m = result.truth[k].T_world_body.x();
    inside += (x_m >= 0.0 && x_m <= length_m) ? 1 : 0;
  }
  EXPECT_EQ(gnss.blocked_without_sky, inside);
  EXPECT_EQ(gnss.fixes.size(), epochs - inside);
  EXPECT_EQ(gnss.dropped_in_dropouts, 0u);
  // 150 m at a constant 6 m/s: 25 s, 125 epochs at 5 Hz.
  EXPECT_NEAR(static_cast<double>(inside), 125.0, 1.0);
  std::printf("tunnel-3d: %zu epochs, %zu fixes (%zu before the tunnel, %zu after), %zu blocked by the tunnel\n", epochs,
              gnss.fixes.size(), before, after, gnss.blocked_without_sky);
}

TEST(SimulatedGnss, FixesCsvReadsBackOntoTheMeasurementsAndTruthCsvHoldsTheTruth) {
  Scenario scenario = fast_tunnel();
  set(scenario, "gnss.outlier_fraction", "0.1");
  set(scenario, "gnss.dropout_start_s", "2");
  set(scenario, "gnss.dropout_end_s", "4");
  std::string why;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const SimulationResult result = simulate(scenario, 5);
  const SimulatedGnss& gnss = result.gnss;
  EXPECT_EQ(gnss.dropped_in_dropouts, 10u);  // epochs at 2.0, 2.2, ..., 3.8 s
  ScratchDirectory dir("sim_gnss_files");
  const std::vector<std::string> files = write_outputs(result, scenario, 5, dir.path.string());
  ASSERT_NE(std::find(files.begin(), files.end(), "gnss/fixes.csv"), files.end());
  ASSERT_NE(std::find(files.begin(), files.end(), "gnss/truth.csv"), files.end());

  gnss::GnssReadReport report;
  const std::vector<gnss::GnssFix> fixes = gnss::read_gnss_csv((dir.path / "gnss" / "fixes.csv").string(), &report);
  ASSERT_EQ(fixes.size(), gnss.fixes.size());
  EXPECT_EQ(report.dropped_no_fix + report.dropped_not_finite, 0u);
  const gnss::LocalFrame frame(scenario.gnss.origin);
  const std::int64_t first_ns = result.truth.front().stamp.nanoseconds();
  double worst_m = 0.0;
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    EXPECT_EQ(fixes[i].stamp, gnss.fixes[i].stamp);
    const double since_start_s = static_cast<double>(fixes[i].stamp.nanoseconds() - first_ns) * 1e-9;
    EXPECT_FALSE(since_start_s >= 2.0 - 1e-9 && since_start_s < 4.0 - 1e-9) << since_start_s;
    worst_m = std::max(worst_m, (frame.forward(fixes[i]) - gnss.p_enu_measured_m[i]).norm());
    ASSERT_TRUE(fixes[i].covariance_known);
    EXPECT_EQ(fixes[i].covariance_enu_m2.diagonal(), Vector3(0.25, 0.25, 1.0));
    EXPECT_EQ(fixes[i].status, gnss::kStatusFix);
  }
  EXPECT_LT(worst_m, 1e-3);
  std::printf("fixes.csv read back: %zu fixes, LocalFrame.forward off the measurement by at most %.3g m\n", fixes.size(),
              worst_m);

  // truth.csv: one line per fix, the same stamps, the truth to the last bit, the outlier flags.
  std::ifstream in(dir.path / "gnss" / "truth.csv");
  std::string line;
  while (std::getline(in, line) && line.starts_with("#")) {
  }
  ASSERT_EQ(line, "time_s,east_m,north_m,up_m,outlier");
  std::size_t rows = 0, outliers = 0;
  while (std::getline(in, line)) {
    ASSERT_LT(rows, gnss.fixes.size());
    std::istringstream fields(line);
    std::string time, east, north, up, flag;
    ASSERT_TRUE(std::getline(fields, time, ',') && std::getline(fields, east, ',') && std::getline(fields, north, ',') &&
                std::getline(fields, up, ',') && std::getline(fields, flag))
        << line;
    EXPECT_EQ(core::Timestamp::parse_seconds(time), gnss.fixes[rows].stamp);
    EXPECT_EQ(Vector3(std::strtod(east.c_str(), nullptr), std::strtod(north.c_str(), nullptr),
                      std::strtod(up.c_str(), nullptr)),
              gnss.p_enu_true_m[rows]);
    EXPECT_EQ(flag, gnss.outlier[rows] ? "1" : "0");
    outliers += flag == "1" ? 1 : 0;
    ++rows;
  }
  EXPECT_EQ(rows, gnss.fixes.size());
  EXPECT_GT(outliers, 0u);  // 10 % of 77 fixes

  nlohmann::json manifest = manifest_json(result, scenario, 5, {}, dir.path.string(), files)["gnss"];
  EXPECT_EQ(manifest["fixes"].get<std::size_t>(), gnss.fixes.size());
  EXPECT_EQ(manifest["outliers"].get<std::size_t>(), outliers);
  EXPECT_EQ(manifest["dropped_in_dropouts"].get<std::size_t>(), 10u);
  EXPECT_EQ(manifest["blocked_by_tunnel"].get<std::size_t>(), gnss.blocked_without_sky);
}

TEST(SimulatedGnss, EnuTruthIsTheWorldYawTimesTheLidarsTruePosition) {
  for (const char* yaw : {"30", "-75"}) {
    Scenario scenario = fast_tunnel();
    set(scenario, "gnss.world_yaw_deg", yaw);
    const SimulationResult result = simulate(scenario, 2);
    const Matrix3 R_enu_world = rotation_z(std::strtod(yaw, nullptr));
    ASSERT_GT(result.gnss.fixes.size(), 50u);  // 87: ~212 epochs, 125 of them in the tunnel
    double worst_m = 0.0;
    for (std::size_t i = 0; i < result.gnss.fixes.size(); ++i) {
      const Vector3 expected = R_enu_world * lidar_position(sample_at(result, result.gnss.fixes[i].stamp), scenario);
      worst_m = std::max(worst_m, (result.gnss.p_enu_true_m[i] - expected).norm());
    }
    EXPECT_LT(worst_m, 1e-6) << "world yaw " << yaw;
    std::printf("world yaw %s deg: %zu fixes, ENU truth off R_z(yaw) p_world_lidar by at most %.3g m\n", yaw,
                result.gnss.fixes.size(), worst_m);
  }
}

TEST(SimulatedGnss, OtherFilesAreByteIdenticalWithTheGnssOnOrOff) {
  Scenario on = *make_scenario("tunnel-3d");
  on.tunnel.length_m = 40.0;
  on.tunnel.approach_m = 10.0;
  on.lidar3d.columns = 60;
  Scenario off = on;
  set(off, "gnss.enabled", "false");
  ASSERT_TRUE(on.is_valid(nullptr) && off.is_valid(nullptr));
  ScratchDirectory dir("sim_gnss_streams");
  fs::create_directories(dir.path / "on");
  fs::create_directories(dir.path / "off");
  const auto files_on = write_outputs(simulate(on, 3), on, 3, (dir.path / "on").string());
  const auto files_off = write_outputs(simulate(off, 3), off, 3, (dir.path / "off").string());
  ASSERT_EQ(files_on.size(), files_off.size() + 2);
  EXPECT_FALSE(fs::exists(dir.path / "off" / "gnss"));
  std::size_t scans = 0;
  for (const auto& name : files_off) {
    ASSERT_NE(std::find(files_on.begin(), files_on.end(), name), files_on.end()) << name;
    EXPECT_EQ(bytes_of(dir.path / "on" / name), bytes_of(dir.path / "off" / name)) << name;
    scans += name.starts_with("scans/") ? 1 : 0;
  }
  EXPECT_GT(scans, 50u);
  EXPECT_NE(std::find(files_off.begin(), files_off.end(), "imu0/data.csv"), files_off.end());
}

TEST(SimulatedGnss, ParametersOnlyIn3DWorldsAndBadSettingsNamed) {
  Scenario office = *make_scenario("office");
  for (const auto& p : parameters(office)) EXPECT_FALSE(p.name.starts_with("gnss.")) << p.name;
  Scenario scenario = fast_tunnel();
  set(scenario, "gnss.rate_hz", "0");
  set(scenario, "gnss.dropout_start_s", "5");
  set(scenario, "gnss.dropout_end_s", "3");
  set(scenario, "gnss.world_yaw_deg", "400");
  std::string why;
  EXPECT_FALSE(scenario.is_valid(&why));
  EXPECT_NE(why.find("gnss: rate_hz"), std::string::npos) << why;
  EXPECT_NE(why.find("gnss.dropout_start_s"), std::string::npos) << why;
  EXPECT_NE(why.find("gnss.world_yaw_deg"), std::string::npos) << why;
  set(scenario, "gnss.enabled", "false");  // then its settings are not checked, as imu.*
  EXPECT_TRUE(scenario.is_valid(&why)) << why;
}

}  // namespace
}  // namespace cairn::sim
