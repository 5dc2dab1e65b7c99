// `cairn eval` end to end: exit codes, the printed numbers against evo's stored results and the
// KITTI devkit's output, JSON content, plots written as PNG and SVG, and bad input named by file
// and line.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <regex>
#include <sstream>
#include <string>

#include "eval/evo_result.hpp"
#include "cli_runner.hpp"
#include "test_data.hpp"

namespace {

constexpr const char* kEvo = "trajectories/trajectories-evo-testdata/";
constexpr const char* kDevkit = "trajectories/kitti-devkit-reference/KITTI_00_ORB/";

using Result = cairn::test::CliResult;
using cairn::test::slurp;

std::filesystem::path scratch() { return cairn::test::scratch_folder("eval_cli_test"); }

Result run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string write_file(const std::string& name, const std::string& content) {
  const auto path = scratch() / name;
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

std::string data(const std::string& relative) { return "'" + cairn::test::data_path(relative).string() + "'"; }

/// The number after `name` at the start of a table row ("  rmse        1.30344971 m").
double printed(const std::string& out, const std::string& name) {
  std::smatch m;
  const std::regex row("\\n  " + name + " +([-+0-9.eE]+)");
  if (!std::regex_search(out, m, row)) {
    ADD_FAILURE() << "no row '" << name << "' in:\n" << out;
    return std::nan("");
  }
  return std::stod(m[1].str());
}

void expect_relative(double actual, double expected, double rel, const std::string& what) {
  EXPECT_LE(std::abs(actual - expected), rel * std::abs(expected))
      << what << ": " << actual << " vs " << expected;
}

TEST(EvalCli, HelpListsTheMetrics) {
  const Result r = run("eval --help");
  EXPECT_EQ(r.status, 0);
  for (const char* metric : {"ape", "rpe", "kitti", "relations"}) EXPECT_NE(r.out.find(metric), std::string::npos);
  EXPECT_EQ(run("eval").status, 2);
  EXPECT_EQ(run("eval ape a.txt b.txt --align rigid").status, 2);
  EXPECT_EQ(run("eval rpe a.txt b.txt --unit km").status, 2);
  EXPECT_EQ(run("eval rpe a.txt b.txt --delta 0").status, 2);
}

// evo_ape kitti KITTI_00_gt.txt KITTI_00_ORB.txt -a (res_files/orb_ape.zip).
TEST(EvalCli, ApeKitti00MatchesEvoStoredResult) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "res_files/orb_ape.zip");
  const std::string json = (scratch() / "ape.json").string();
  const Result r = run("eval ape " + data(std::string(kEvo) + "KITTI_00_gt.txt") + " " +
                       data(std::string(kEvo) + "KITTI_00_ORB.txt") + " --align se3 --json '" + json + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json evo = cairn::test::evo_stats(cairn::test::data_path(std::string(kEvo) + "res_files/orb_ape.zip").string());
  ASSERT_TRUE(evo.is_object());
  // The table prints 9 significant digits.
  expect_relative(printed(r.out, "rmse"), evo["rmse"].get<double>(), 1e-6, "printed rmse");
  EXPECT_NE(r.out.find("1.30344971 m"), std::string::npos) << r.out;
  expect_relative(printed(r.out, "max"), evo["max"].get<double>(), 1e-6, "printed max");

  const nlohmann::json j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["metric"], "ape");
  EXPECT_EQ(j["relation"], "trans_part");
  EXPECT_EQ(j["unit"], "m");
  EXPECT_EQ(j["association"]["pairs"], 4541);
  EXPECT_EQ(j["association"]["by_time"], false);
  EXPECT_EQ(j["alignment"]["method"], "se3");
  EXPECT_EQ(j["alignment"]["scale"], 1.0);
  for (const char* stat : {"rmse", "mean", "median", "std", "min", "max", "sse"}) {
    expect_relative(j["statistics"][stat].get<double>(), evo[stat].get<double>(), 1e-6, stat);
  }
  EXPECT_EQ(j["errors"].size(), 4541u);
}

// evo_rpe kitti KITTI_00_gt.txt KITTI_00_ORB.txt -d 10 -u m (res_files/orb_rpe.zip).
TEST(EvalCli, RpeKitti00TenMetresMatchesEvoStoredResult) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "res_files/orb_rpe.zip");
  const std::string json = (scratch() / "rpe.json").string();
  const Result r = run("eval rpe " + data(std::string(kEvo) + "KITTI_00_gt.txt") + " " +
                       data(std::string(kEvo) + "KITTI_00_ORB.txt") + " --delta 10 --unit m --json '" + json + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json evo = cairn::test::evo_stats(cairn::test::data_path(std::string(kEvo) + "res_files/orb_rpe.zip").string());
  expect_relative(printed(r.out, "rmse"), evo["rmse"].get<double>(), 1e-6, "printed rmse");
  const nlohmann::json j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["delta_unit"], "m");
  EXPECT_EQ(j["all_pairs"], false);
  EXPECT_EQ(j["pairs"].size(), 353u);
  for (const char* stat : {"rmse", "mean", "median", "std", "min", "max", "sse"}) {
    expect_relative(j["statistics"][stat].get<double>(), evo[stat].get<double>(), 1e-6, stat);
  }
}

// The devkit's stats.txt for the same files: "0.006997 0.000044" (m/m, rad/m, printed %f).
TEST(EvalCli, KittiMatchesDevkitAndWritesPlots) {
  CAIRN_REQUIRE_DATA(std::string(kDevkit) + "stats.txt");
  const std::string json = (scratch() / "kitti.json").string();
  const std::string prefix = (scratch() / "kitti").string();
  const Result r = run("eval kitti " + data(std::string(kEvo) + "KITTI_00_gt.txt") + " " +
                       data(std::string(kEvo) + "KITTI_00_ORB.txt") + " --json '" + json + "' --plot '" + prefix + ".svg'");
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream stats(cairn::test::data_path(std::string(kDevkit) + "stats.txt"));
  double t_err = 0;
  double r_err = 0;
  ASSERT_TRUE(stats >> t_err >> r_err);
  const nlohmann::json j = nlohmann::json::parse(slurp(json));
  EXPECT_NEAR(j["t_err_m_per_m"].get<double>(), t_err, 5e-7 + 1e-12);
  EXPECT_NEAR(j["r_err_rad_per_m"].get<double>(), r_err, 5e-7 + 1e-12);
  EXPECT_EQ(j["segments"], 3283);
  EXPECT_EQ(j["per_length"].size(), 8u);
  EXPECT_NEAR(printed(r.out, "t_err"), 100 * t_err, 100 * (5e-7 + 1e-9));
  for (const char* name : {"_segments.svg", "_top.svg"}) {
    const std::string svg = slurp(prefix + name);
    EXPECT_NE(svg.find("<svg"), std::string::npos) << prefix + name;
  }
}

TEST(EvalCli, ApeTumFr1XyzAssociatesAndPlotsPng) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "freiburg1_xyz-rgbdslam.txt");
  const std::string prefix = (scratch() / "fr1").string();
  const Result r = run("eval ape " + data(std::string(kEvo) + "freiburg1_xyz-groundtruth.txt") + " " +
                       data(std::string(kEvo) + "freiburg1_xyz-rgbdslam.txt") + " --align se3 --plot '" + prefix + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("785 of 788 poses associated by time"), std::string::npos) << r.out;
  // ../shared/data/trajectories/README.md: evo gives rmse 0.013470088849733684 m for this pair.
  expect_relative(printed(r.out, "rmse"), 0.013470088849733684, 1e-6, "rmse");
  for (const char* name : {"_top.png", "_error.png"}) {
    const std::string png = slurp(prefix + name);
    ASSERT_GT(png.size(), 1000u) << prefix + name;
    EXPECT_EQ(png.substr(1, 3), "PNG");
  }
}

// Three poses at 1, 2, 3 s: (0, 0, 0), (1, 0, 0), (2, 0, yaw 0.1). Relations 1->2 says (1, 0, 0):
// error 0; 2->3 says (1.1, 0, 0): translational error 0.1 m, rotational 0.1 rad = 5.7295780 deg.
TEST(EvalCli, RelationsOnATumEstimate) {
  const std::string relations = write_file("small.relations", "# t_i t_j x y z roll pitch yaw\n"
                                                              "1.0 2.0 1.0 0 0 0 0 0\n"
                                                              "2.0 3.0 1.1 0 0 0 0 0\n");
  const double half = 0.05;
  std::ostringstream tum;
  tum.precision(17);
  tum << "1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n3.0 2 0 0 0 0 " << std::sin(half) << " " << std::cos(half) << "\n";
  const std::string estimate = write_file("small.tum", tum.str());
  const std::string json = (scratch() / "relations.json").string();
  const Result r = run("eval relations '" + relations + "' '" + estimate + "' --json '" + json + "' --plot '" +
                       (scratch() / "rel").string() + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["count"], 2);
  EXPECT_NEAR(j["translation_absolute_m"]["mean"].get<double>(), 0.05, 1e-9);
  EXPECT_NEAR(j["translation_absolute_m"]["std"].get<double>(), 0.05, 1e-9);
  EXPECT_NEAR(j["translation_squared_m2"]["mean"].get<double>(), 0.005, 1e-9);
  EXPECT_NEAR(j["rotation_absolute_deg"]["mean"].get<double>(), 0.05 * 180 / std::numbers::pi, 1e-6);
  EXPECT_NEAR(j["per_relation"][1]["translation_error_m"].get<double>(), 0.1, 1e-9);
  EXPECT_EQ(j["per_relation"][1]["line"], 3);
  EXPECT_TRUE(std::filesystem::exists(scratch() / "rel_error.png"));
}

// The raw ACES log's odometry (laser poses of its FLASER records) as the estimate. The data's
// curator measured, independently of cairn, the relative motion from these odometry fields
// against all 1279 relations: "mean error 0.549 m / 2.33 deg"
// (../shared/data/laser2d/aces/SOURCE.txt, "Raw vs corrected"); 3 significant digits.
TEST(EvalCli, RelationsAcesOdometryMatchesTheCuratorsNumbers) {
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.clf.bz2");
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.relations");
  const std::string json = (scratch() / "aces.json").string();
  const Result r = run("eval relations " + data("laser2d/aces/aces.relations") + " " + data("laser2d/aces/aces.clf.bz2") +
                       " --json '" + json + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["count"], 1279);
  EXPECT_NEAR(j["translation_absolute_m"]["mean"].get<double>(), 0.549, 0.0005);
  EXPECT_NEAR(j["rotation_absolute_deg"]["mean"].get<double>(), 2.33, 0.005);
}

// ---------------------------------------------------------------------------------------------
// Bad input: exit status 1, a message naming the file (and the line when there is one).

const char* kTumHeader = "# timestamp tx ty tz qx qy qz qw\n";

std::string tum_line(double t, double x, double y) {
  std::ostringstream s;
  s << t << " " << x << " " << y << " 0 0 0 0 1\n";
  return s.str();
}

std::string good_tum(const std::string& name, double t0) {
  std::string text = kTumHeader;
  for (int i = 0; i < 20; ++i) text += tum_line(t0 + 0.1 * i, i, 0.05 * i * i);
  return write_file(name, text);
}

TEST(EvalCli, UnsortedTimesNameFileAndLine) {
  std::string text = kTumHeader;
  text += tum_line(1.0, 0, 0) + tum_line(1.2, 1, 0) + tum_line(1.1, 2, 0);
  const std::string path = write_file("unsorted.tum", text);
  const Result r = run("eval ape '" + good_tum("gt.tum", 1.0) + "' '" + path + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(path + ":4:"), std::string::npos) << r.err;
}

TEST(EvalCli, NaNNamesFileAndLine) {
  std::string text = kTumHeader;
  text += tum_line(1.0, 0, 0) + "1.1 nan 0 0 0 0 0 1\n";
  const std::string path = write_file("nan.tum", text);
  const Result r = run("eval ape '" + good_tum("gt.tum", 1.0) + "' '" + path + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(path + ":3:"), std::string::npos) << r.err;
}

TEST(EvalCli, MismatchedLengthsNameBothFiles) {
  const std::string row = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const std::string gt = write_file("gt.kitti", row + row + row);
  const std::string est = write_file("est.kitti", row + row);
  const Result r = run("eval ape '" + gt + "' '" + est + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(gt), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(est), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("3"), std::string::npos) << r.err;
}

TEST(EvalCli, NoOverlappingTimestamps) {
  const std::string gt = good_tum("early.tum", 1.0);
  const std::string est = good_tum("late.tum", 500.0);
  const Result r = run("eval ape '" + gt + "' '" + est + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no overlapping timestamps"), std::string::npos) << r.err;
  // --offset moves the estimate onto the reference: then it evaluates.
  const Result shifted = run("eval ape '" + gt + "' '" + est + "' --offset -499");
  EXPECT_EQ(shifted.status, 0) << shifted.err;
  EXPECT_NEAR(printed(shifted.out, "rmse"), 0.0, 1e-9) << shifted.out;
}

TEST(EvalCli, UnwritablePlotOrJsonIsAnErrorNamingThePath) {
  const std::string gt = good_tum("gt2.tum", 1.0);
  const std::string missing_dir = (scratch() / "no" / "such" / "dir").string();
  const Result plot = run("eval ape '" + gt + "' '" + gt + "' --plot '" + missing_dir + "/p.png'");
  EXPECT_EQ(plot.status, 1);
  EXPECT_NE(plot.err.find(missing_dir + "/p_top.png"), std::string::npos) << plot.err;
  const Result json = run("eval ape '" + gt + "' '" + gt + "' --json '" + missing_dir + "/r.json'");
  EXPECT_EQ(json.status, 1);
  EXPECT_NE(json.err.find(missing_dir + "/r.json"), std::string::npos) << json.err;
}

TEST(EvalCli, BadRelationsFileAndMissingFile) {
  const std::string relations = write_file("bad.relations", "1.0 2.0 1.0 0 0 0 0 0\n2.0 3.0 1.1 0 0\n");
  const Result r = run("eval relations '" + relations + "' '" + good_tum("est.tum", 1.0) + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(relations + ":2:"), std::string::npos) << r.err;
  const Result missing = run("eval ape '" + (scratch() / "absent.tum").string() + "' '" + good_tum("est.tum", 1.0) + "'");
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("absent.tum"), std::string::npos) << missing.err;
}

}  // namespace
