// The `cairn` binary end to end: exit codes, messages naming file and line, JSON facts, and
// conversions that read back the same.

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

using Result = cairn::test::CliResult;
using cairn::test::slurp;

std::filesystem::path scratch() { return cairn::test::scratch_folder("cli_test"); }

Result run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

std::string write_file(const std::string& name, const std::string& content) {
  const auto path = scratch() / name;
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

TEST(Cli, HelpEverywhere) {
  const Result top = run("--help");
  EXPECT_EQ(top.status, 0);
  EXPECT_NE(top.out.find("info"), std::string::npos);
  EXPECT_NE(top.out.find("convert"), std::string::npos);
  for (const char* command : {"info", "convert"}) {
    const Result sub = run(std::string(command) + " --help");
    EXPECT_EQ(sub.status, 0) << command;
    EXPECT_NE(sub.out.find("--strict"), std::string::npos) << command << sub.out;
  }
}

// `cairn` runs info, convert, corrupt, optimize and ba itself and hands the other commands to the
// cairn-suite beside it (src/cairn/cli/main.cpp): every command is listed and helps, the front
// loads neither cairo nor OpenCV, and a front without its suite says so.
TEST(Cli, TheFrontHandsTheOtherCommandsToCairnSuite) {
  const Result top = run("--help");
  for (const char* command : {"info", "convert", "corrupt", "optimize", "ba", "slam2d", "localize2d", "slam3d", "vslam",
                              "vocabulary", "eval", "landmarks", "simulate"}) {
    EXPECT_NE(top.out.find(std::string("\n  ") + command + " "), std::string::npos) << command << top.out;
  }
  for (const char* command : {"slam2d", "vslam", "simulate"}) {
    const Result help = run(std::string(command) + " --help");
    EXPECT_EQ(help.status, 0) << command << help.err;
    EXPECT_NE(help.out.find(std::string("Usage: cairn ") + command), std::string::npos) << command << help.out;
    EXPECT_NE(help.out.find("--"), std::string::npos) << command << ": its own options" << help.out;
  }
  EXPECT_EQ(run("slam2d --no-such-flag x.clf").status, 2);  // the suite's usage error, passed on

  // The libraries the dynamic loader maps for the front (what ldd prints, without ldd).
  const Result libraries = cairn::test::run_command("LD_TRACE_LOADED_OBJECTS=1 " + std::string(CAIRN_BINARY), "",
                                                    scratch() / "stderr.txt");
  EXPECT_NE(libraries.out.find("libcholmod"), std::string::npos) << libraries.out;
  EXPECT_EQ(libraries.out.find("libcairo"), std::string::npos) << libraries.out;
  EXPECT_EQ(libraries.out.find("libopencv"), std::string::npos) << libraries.out;

  // Alone in a folder, the front still runs its own commands and names what is missing.
  const auto lone = scratch() / "lone";
  std::filesystem::create_directories(lone);
  std::filesystem::copy_file(CAIRN_BINARY, lone / "cairn", std::filesystem::copy_options::overwrite_existing);
  const std::string graph = write_file("lone.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n"
                                                   "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n");
  const Result own = cairn::test::run_command((lone / "cairn").string(), "info " + graph, scratch() / "stderr.txt");
  EXPECT_EQ(own.status, 0) << own.err;
  const Result handed = cairn::test::run_command((lone / "cairn").string(), "slam2d x.clf", scratch() / "stderr.txt");
  EXPECT_EQ(handed.status, 1);
  EXPECT_NE(handed.err.find((lone / "cairn-suite").string() + ", which cannot be started"), std::string::npos) << handed.err;
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run("").status, 2);
  EXPECT_EQ(run("info").status, 2);
  EXPECT_EQ(run("frobnicate x").status, 2);
  EXPECT_EQ(run("info x.g2o --info-policy maybe").status, 2);
}

TEST(Cli, BadInputNamesFileAndLineAndExitsWithOne) {
  const std::string truncated = write_file("truncated.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0\n");
  const Result r = run("info " + truncated);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(truncated + ":3: EDGE_SE2 expects 11 values after the tag"), std::string::npos) << r.err;

  const Result missing = run("info /nonexistent/graph.g2o");
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("/nonexistent/graph.g2o: cannot open file"), std::string::npos) << missing.err;

  std::string garbage(4096, '\0');
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<char>((i * 7919u) % 256u);
  const Result binary = run("info " + write_file("garbage.g2o", garbage));
  EXPECT_EQ(binary.status, 1);
  EXPECT_NE(binary.err.find("binary data"), std::string::npos) << binary.err;

  const Result empty = run("info " + write_file("empty.g2o", ""));
  EXPECT_EQ(empty.status, 1);
  EXPECT_NE(empty.err.find("empty file"), std::string::npos) << empty.err;

  const Result huge = run("info " + write_file("huge.g2o", std::string(3 << 20, '1')));
  EXPECT_EQ(huge.status, 1);
  EXPECT_NE(huge.err.find("longer than"), std::string::npos) << huge.err;

  const Result unknown_format = run("info " + write_file("what.txt", "1 2 3\n"));
  EXPECT_EQ(unknown_format.status, 1);
  EXPECT_NE(unknown_format.err.find("cannot tell the format"), std::string::npos) << unknown_format.err;
}

TEST(Cli, InfoReportsCountsAsJson) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  const Result r = run("info " + quoted(cairn::test::data_path("posegraph/se-sync/intel.g2o")) + " --json -");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["dimension"], 2);
  EXPECT_EQ(j["poses"], 1728);
  EXPECT_EQ(j["edges"], 2512);
  EXPECT_EQ(j["connected_components"], 1);
  EXPECT_EQ(j["has_initial_guess"], true);
  EXPECT_EQ(j["records"]["EDGE_SE2"], 2512);

  const Result csail = run("info " + quoted(cairn::test::data_path("posegraph/se-sync/CSAIL.g2o")));
  ASSERT_EQ(csail.status, 0) << csail.err;
  EXPECT_NE(csail.out.find("initial guess     no"), std::string::npos) << csail.out;
}

TEST(Cli, InfoAndStrictModeOnCubicle) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/cubicle.g2o");
  const std::string cubicle = quoted(cairn::test::data_path("posegraph/se-sync/cubicle.g2o"));
  const Result r = run("info " + cubicle + " --json -");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["information_indefinite"], 5021);
  EXPECT_EQ(j["first_indefinite_line"], 5753);
  EXPECT_EQ(j["information_policy"], "project");
  const Result text = run("info " + cubicle);
  EXPECT_NE(text.err.find("5021 of 16869 information matrices are indefinite (first at line 5753)"),
            std::string::npos)
      << text.err;
  const Result strict = run("info --strict " + cubicle);
  EXPECT_EQ(strict.status, 1);
  EXPECT_NE(strict.err.find("cubicle.g2o:5753: information matrix is indefinite"), std::string::npos) << strict.err;
}

TEST(Cli, ConvertToroToG2oKeepsTheGraph) {
  CAIRN_REQUIRE_DATA("posegraph/toro/w100.graph");
  const auto out = scratch() / "w100.g2o";
  const Result c = run("convert " + quoted(cairn::test::data_path("posegraph/toro/w100.graph")) + " " + quoted(out));
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_NE(c.out.find("wrote"), std::string::npos);
  EXPECT_NE(c.err.find("skipped 40 unknown EQUIV record(s)"), std::string::npos) << c.err;
  const Result info = run("info " + quoted(out) + " --json -");
  ASSERT_EQ(info.status, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_EQ(j["vertices"], 100);
  EXPECT_EQ(j["edges"], 300);
  EXPECT_EQ(j["format"], "g2o");
}

TEST(Cli, ConvertTrajectoryKittiToTumAndBack) {
  CAIRN_REQUIRE_DATA("trajectories/trajectories-evo-testdata/KITTI_00_gt.txt");
  const auto dir = cairn::test::data_path("trajectories/trajectories-evo-testdata");
  const auto tum = scratch() / "kitti00.tum";
  const Result c = run("convert " + quoted(dir / "KITTI_00_gt.txt") + " " + quoted(tum) + " --from kitti --times " +
                       quoted(dir / "KITTI_00_gt_times.txt"));
  ASSERT_EQ(c.status, 0) << c.err;
  const Result info = run("info " + quoted(tum) + " --json -");
  ASSERT_EQ(info.status, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_EQ(j["poses"], 4541);
  EXPECT_EQ(j["has_timestamps"], true);
  // Without times a KITTI trajectory cannot become TUM: the command says what to pass.
  const Result no_times = run("convert " + quoted(dir / "KITTI_00_gt.txt") + " " + quoted(scratch() / "x.tum"));
  EXPECT_EQ(no_times.status, 1);
  EXPECT_NE(no_times.err.find("--times"), std::string::npos) << no_times.err;
  EXPECT_FALSE(std::filesystem::exists(scratch() / "x.tum"));
}

TEST(Cli, ConvertRefusesGraphToTrajectory) {
  const std::string graph = write_file("g.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n");
  const Result r = run("convert " + graph + " " + (scratch() / "out.tum").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cannot convert a pose graph"), std::string::npos) << r.err;
}

TEST(Cli, InfoReadsCompressedCarmenLogs) {
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.clf.bz2");
  const Result r = run("info " + quoted(cairn::test::data_path("laser2d/aces/aces.clf.bz2")) + " --json -");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["format"], "carmen");
  EXPECT_EQ(j["scans"], 7374);
  EXPECT_EQ(j["records"]["ODOM"], 7375);
  EXPECT_EQ(j["beams_per_scan"]["180"], 7374);
  EXPECT_EQ(j["first_scan_time_s"], "70.289900000");
  // laser2d/aces/SOURCE.txt: odometry path 325.2 m.
  EXPECT_NEAR(j["odometry_path_length_m"].get<double>(), 325.2, 0.05);
}

TEST(Cli, OptimizeReachesTheCertifiedOptimumAndWritesItsReport) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  const auto out = scratch() / "intel_opt.g2o";
  const auto report = scratch() / "intel_report.json";
  const Result r = run("optimize " + quoted(cairn::test::data_path("posegraph/se-sync/intel.g2o")) + " -o " + quoted(out) +
                       " --objective chordal --init chordal --covariance 0,100 --report " + quoted(report));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("iter"), std::string::npos) << "progress per iteration expected on stderr";
  std::ifstream in(report);
  const auto j = nlohmann::json::parse(in);
  // SE-Sync's certified optimum for intel.g2o: 52.348227285553435 (../shared/data/README.md).
  EXPECT_NEAR(j["final_f_chordal"].get<double>(), 52.348227285553435, 1e-5);
  EXPECT_EQ(j["summary"]["termination"], "convergence");
  EXPECT_EQ(j["marginal_covariances"]["poses"].size(), 2u);
  const Result info = run("info " + quoted(out) + " --json -");
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["vertices"], 1728);
}

// --exact-steps and --initial-radius 1e4 give Ceres' choices (a factorisation every iteration,
// damped start); both roads end at the same minimum, the default one in fewer iterations.
TEST(Cli, OptimizeExactStepsAndCeresRadiusReachTheSameMinimum) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/sphere2500.g2o");
  const std::string graph = quoted(cairn::test::data_path("posegraph/se-sync/sphere2500.g2o"));
  auto solve = [&](const std::string& name, const std::string& flags) {
    const auto report = scratch() / (name + ".json");
    const Result r = run("optimize " + graph + " -o " + quoted(scratch() / (name + ".g2o")) + " --init chordal " + flags +
                         " --report " + quoted(report));
    EXPECT_EQ(r.status, 0) << r.err;
    std::ifstream in(report);
    return std::make_pair(nlohmann::json::parse(in)["summary"], r.err);
  };
  const auto [fast, fast_progress] = solve("default_steps", "");
  const auto [ceres_like, ceres_progress] = solve("exact_steps", "--exact-steps --initial-radius 1e4");
  EXPECT_NEAR(fast["final_cost"].get<double>(), ceres_like["final_cost"].get<double>(),
              1e-8 * ceres_like["final_cost"].get<double>());
  EXPECT_LT(fast["iterations"].get<int>(), ceres_like["iterations"].get<int>());
  int pcg_steps = 0;
  for (const auto& it : fast["iteration_log"]) pcg_steps += it["cg_iterations"].get<int>() > 0 && it["factorize_s"].get<double>() == 0.0;
  EXPECT_GE(pcg_steps, 1);
  for (const auto& it : ceres_like["iteration_log"]) {
    EXPECT_EQ(it["cg_iterations"].get<int>(), 0);
    EXPECT_GT(it["factorize_s"].get<double>(), 0.0);
  }
  EXPECT_NE(fast_progress.find(" cg "), std::string::npos) << fast_progress;
  EXPECT_EQ(ceres_progress.find(" cg "), std::string::npos) << ceres_progress;
  const Result bad = run("optimize " + graph + " -o " + quoted(scratch() / "bad.g2o") + " --initial-radius 0");
  EXPECT_EQ(bad.status, 2) << bad.err;
}

TEST(Cli, OptimizeRefusesAnUnanchoredComponent) {
  const std::string graph = write_file("two.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 0 0 0\n"
                                                  "VERTEX_SE2 3 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n"
                                                  "EDGE_SE2 2 3 1 0 0 1 0 0 1 0 1\n");
  const Result r = run("optimize " + graph + " -o " + (scratch() / "two_out.g2o").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("2 connected components"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(scratch() / "two_out.g2o"));
}

// The report names each rejected edge by ids and file line, and those lines are the edges named.
// (How many false edges GNC rejects on this graph is a measurement, in docs/backend.md, not an
// assertion: on input_INTEL_g2o with 20 false loop closures it rejects 18 and no true one.)
TEST(Cli, CorruptThenGncReportsRejectedEdgesByIdAndLine) {
  CAIRN_REQUIRE_DATA("posegraph/other/input_INTEL_g2o.g2o");
  const auto bad = scratch() / "intel_bad.g2o";
  const Result c = run("corrupt " + quoted(cairn::test::data_path("posegraph/other/input_INTEL_g2o.g2o")) +
                       " --outliers 20 --seed 3 -o " + quoted(bad));
  ASSERT_EQ(c.status, 0) << c.err;
  const auto report = scratch() / "gnc.json";
  const Result r = run("optimize " + quoted(bad) + " -o " + quoted(scratch() / "gnc.g2o") + " --robust gnc -q --report " +
                       quoted(report));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("GNC:"), std::string::npos) << r.out;
  std::vector<std::string> lines;
  {
    std::ifstream in(bad);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  std::ifstream in(report);
  const auto j = nlohmann::json::parse(in);
  ASSERT_FALSE(j["gnc"]["rejected"].empty());
  for (const auto& e : j["gnc"]["rejected"]) {
    const std::size_t line = e["line"].get<std::size_t>();
    ASSERT_GE(line, 1u);
    ASSERT_LE(line, lines.size());
    std::istringstream tokens(lines[line - 1]);
    std::string tag;
    std::int64_t from = -1;
    std::int64_t to = -1;
    tokens >> tag >> from >> to;
    EXPECT_EQ(tag, "EDGE_SE2");
    EXPECT_EQ(from, e["from"].get<std::int64_t>());
    EXPECT_EQ(to, e["to"].get<std::int64_t>());
    EXPECT_NE(to - from, 1) << "odometry edges are trusted, never rejected";
  }
}

TEST(Cli, BundleAdjustmentRefinesABalProblemAndWritesItBack) {
  CAIRN_REQUIRE_DATA("bal/dubrovnik-3-7-pre.txt");
  const std::string input = cairn::test::data_path("bal/dubrovnik-3-7-pre.txt").string();
  const auto out = scratch() / "ba_out.txt";
  const auto report = scratch() / "ba_report.json";
  const Result result = run("ba " + quoted(std::filesystem::path(input)) + " -o " + quoted(out) + " --report " + quoted(report) + " -q");
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_NE(result.out.find("3 cameras, 7 points, 19 observations"), std::string::npos) << result.out;
  const nlohmann::json j = nlohmann::json::parse(slurp(report));
  // SOURCE.txt: initial cost 2.764220e+03 for this file.
  EXPECT_NEAR(j["initial_cost"].get<double>(), 2.764220e+03, 0.01);
  EXPECT_LT(j["final_cost"].get<double>(), 1e-2 * j["initial_cost"].get<double>());
  EXPECT_EQ(j["cameras"], 3);
  // The written problem reads back with the same counts, and starting from it the solve has
  // nothing left to gain.
  const auto again = scratch() / "ba_report_again.json";
  ASSERT_EQ(run("ba " + quoted(out) + " --report " + quoted(again) + " -q").status, 0);
  const nlohmann::json k = nlohmann::json::parse(slurp(again));
  EXPECT_NEAR(k["initial_cost"].get<double>(), j["final_cost"].get<double>(), 1e-9 * (1.0 + j["final_cost"].get<double>()));
}

TEST(Cli, BundleAdjustmentRejectsBadInputWithFileAndLine) {
  const std::string bad = write_file("bad.bal", "1 1 1\n0 3 1.5 -2.5\n0.1\n0.2\n0.3\n1\n2\n-5\n500\n0\n0\n1\n2\n3\n");
  const Result result = run("ba " + quoted(std::filesystem::path(bad)));
  EXPECT_EQ(result.status, 1);
  EXPECT_NE(result.err.find("bad.bal:2: the point index of observation 1 of 1 3 is out of range"), std::string::npos)
      << result.err;
  EXPECT_EQ(run("ba " + quoted(std::filesystem::path(bad)) + " --linear-solver qr").status, 2);
  // A point in its camera's plane (P_z = 0: t = 0, X = 0) has no BAL projection.
  const std::string plane = write_file("plane.bal", "1 1 1\n0 0 1 1\n0 0 0 0 0 0 500 0 0\n0 0 0\n");
  const Result in_plane = run("ba " + quoted(std::filesystem::path(plane)));
  EXPECT_EQ(in_plane.status, 1);
  EXPECT_NE(in_plane.err.find("plane.bal: observation 1 (camera 0, point 0): the point lies in the camera's plane"),
            std::string::npos)
      << in_plane.err;
}

}  // namespace
