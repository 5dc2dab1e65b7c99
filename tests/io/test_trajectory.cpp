#include "cairn/io/trajectory.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"
#include "test_data.hpp"

namespace cairn::io {
namespace {

namespace fs = std::filesystem;
using core::SE3;
using core::Timestamp;

constexpr const char* kEvo = "trajectories/trajectories-evo-testdata/";

// One folder per test process: ctest runs the discovered tests in parallel processes. Created
// on every call because the environment below may remove it between --gtest_repeat rounds.
fs::path scratch_dir() {
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_trajectory_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

class RemoveScratchDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(scratch_dir(), ignored);
  }
};
[[maybe_unused]] const auto* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new RemoveScratchDir);

std::string scratch(const std::string& name) { return (scratch_dir() / name).string(); }

std::string write_temp(const std::string& name, const std::string& content) {
  const std::string path = scratch(name);
  std::ofstream(path, std::ios::binary) << content;
  return path;
}

std::string evo(const std::string& name) { return cairn::test::data_path(kEvo + name).string(); }

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs `read`, which must throw ParseError at `line` with `phrase` in its message.
void expect_parse_error(const std::function<void()>& read, std::size_t line,
                        const std::string& phrase, const std::string& file = "") {
  try {
    read();
    ADD_FAILURE() << "expected a ParseError containing '" << phrase << "'";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(e.detail().find(phrase), std::string::npos) << "missing '" << phrase << "' in: " << e.what();
    if (!file.empty()) {
      EXPECT_EQ(e.file(), file) << e.what();
    }
  }
}

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

// Stamps equal and every translation and quaternion coefficient bit for bit the same; reports
// only the first differing pose so a systematic error does not print 16,702 failures.
void expect_identical(const Trajectory& expected, const Trajectory& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  ASSERT_EQ(expected.stamps.size(), actual.stamps.size());
  for (std::size_t i = 0; i < expected.stamps.size(); ++i) {
    ASSERT_EQ(expected.stamps[i], actual.stamps[i]) << "stamp " << i;
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const SE3& a = expected.poses[i];
    const SE3& b = actual.poses[i];
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(same_bits(a.translation()[k], b.translation()[k]))
          << "pose " << i << " t[" << k << "]: " << a.translation()[k] << " vs " << b.translation()[k];
    }
    for (int k = 0; k < 4; ++k) {
      ASSERT_TRUE(same_bits(a.unit_quaternion().coeffs()[k], b.unit_quaternion().coeffs()[k]))
          << "pose " << i << " q[" << k << "]: " << a.unit_quaternion().coeffs()[k] << " vs "
          << b.unit_quaternion().coeffs()[k];
    }
  }
}

// Stamps equal; poses' 3x4 matrices within `tolerance` (max abs entry).
void expect_close(const Trajectory& expected, const Trajectory& actual, double tolerance) {
  ASSERT_EQ(expected.size(), actual.size());
  ASSERT_EQ(expected.stamps, actual.stamps);
  double worst = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    worst = std::max(worst, (expected.poses[i].matrix3x4() - actual.poses[i].matrix3x4()).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, tolerance);
}

std::size_t count_data_lines(const std::string& path) {
  std::ifstream in(path);
  std::size_t count = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') ++count;
  }
  return count;
}

// Random poses (Gaussian quaternions, translations across many magnitudes, including -0 and
// 1e-300) with strictly increasing stamps that start before zero.
Trajectory random_trajectory(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  std::uniform_int_distribution<int> exponent(-300, 300);
  std::uniform_int_distribution<std::int64_t> step_ns(1, 2'000'000'000);
  Trajectory trajectory;
  std::int64_t ns = -5'123'456'789;
  for (std::size_t i = 0; i < n; ++i) {
    const Quaternion q(gaussian(rng), gaussian(rng), gaussian(rng), gaussian(rng));
    Vector3 t(gaussian(rng), gaussian(rng) * std::pow(10.0, exponent(rng)), gaussian(rng) * 1e3);
    if (i == 1) t = Vector3(-0.0, 1e-300, -1e300);
    trajectory.poses.emplace_back(q, t);
    trajectory.stamps.push_back(Timestamp::from_nanoseconds(ns));
    ns += step_ns(rng);
  }
  return trajectory;
}

// ---------------------------------------------------------------------------------------------
// Names

TEST(TrajectoryFormat, NamesRoundTrip) {
  for (const auto format : {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc}) {
    EXPECT_EQ(trajectory_format_from_name(to_string(format)), format);
  }
  EXPECT_EQ(to_string(TrajectoryFormat::kEuroc), "euroc");
  EXPECT_FALSE(trajectory_format_from_name("TUM").has_value());
  EXPECT_FALSE(trajectory_format_from_name("g2o").has_value());
  EXPECT_FALSE(trajectory_format_from_name("").has_value());
}

// ---------------------------------------------------------------------------------------------
// Real files

TEST(TrajectoryRealData, KittiGroundTruthWithTimes) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "KITTI_00_gt.txt");
  TrajectoryReadReport report;
  const Trajectory t = read_kitti(evo("KITTI_00_gt.txt"), evo("KITTI_00_gt_times.txt"), &report);
  EXPECT_EQ(t.size(), 4541u);
  ASSERT_TRUE(t.has_stamps());
  EXPECT_EQ(t.stamps.size(), 4541u);
  EXPECT_EQ(t.stamps[0].nanoseconds(), 0);
  EXPECT_EQ(t.stamps[1].nanoseconds(), 103'735'900);  // "1.037359e-01"
  EXPECT_EQ(report.poses, 4541u);
  EXPECT_EQ(report.comment_lines, 0u);
  EXPECT_TRUE(report.warnings.empty());
  // 7 significant digits leave the rotation blocks orthonormal to a few 1e-7, never 1e-5.
  EXPECT_GT(report.max_rotation_orthonormality_error, 0.0);
  EXPECT_LT(report.max_rotation_orthonormality_error, 1e-5);
  // Line 2: "... -4.690294e-02 ... -2.839928e-02 ... 8.586941e-01" is the translation column.
  EXPECT_EQ(t.poses[1].translation(), Vector3(-4.690294e-02, -2.839928e-02, 8.586941e-01));
  EXPECT_NEAR(t.poses[1].rotation_matrix()(0, 1), 5.272628e-04, 1e-6);
}

TEST(TrajectoryRealData, KittiOrbWithoutTimes) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "KITTI_00_ORB.txt");
  const Trajectory t = read_kitti(evo("KITTI_00_ORB.txt"));
  EXPECT_EQ(t.size(), 4541u);
  EXPECT_FALSE(t.has_stamps());
}

TEST(TrajectoryRealData, TumGroundTruthWithComments) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "freiburg1_xyz-groundtruth.txt");
  const std::string path = evo("freiburg1_xyz-groundtruth.txt");
  TrajectoryReadReport report;
  const Trajectory t = read_tum(path, &report);
  EXPECT_EQ(t.size(), count_data_lines(path));
  EXPECT_EQ(t.size(), 3000u);
  EXPECT_EQ(report.comment_lines, 3u);
  EXPECT_EQ(report.quaternions_normalised, 0u);  // 4 decimals: |norm - 1| ~ 1e-4 at most
  EXPECT_TRUE(report.warnings.empty());
  EXPECT_EQ(report.max_rotation_orthonormality_error, 0.0);
  // "1305031098.6659 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986"
  EXPECT_EQ(t.stamps[0].nanoseconds(), 1'305'031'098'665'900'000);
  EXPECT_EQ(t.poses[0].translation(), Vector3(1.3563, 0.6305, 1.6380));
  const Quaternion q = Quaternion(-0.3986, 0.6132, 0.5962, -0.3311).normalized();
  EXPECT_NEAR(t.poses[0].unit_quaternion().angularDistance(q), 0.0, 1e-12);
}

TEST(TrajectoryRealData, TumOrbEstimate) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "fr2_desk_ORB.txt");
  const std::string path = evo("fr2_desk_ORB.txt");
  const Trajectory t = read_tum(path);
  EXPECT_EQ(t.size(), count_data_lines(path));
  EXPECT_EQ(t.stamps[1].nanoseconds(), 1'311'868'164'399'026'000);
}

// The published fr2/desk ground truth repeats 1311868229.5760 on lines 10862-10863 with two
// different poses. cairn keeps the first, drops the second and says so.
TEST(TrajectoryRealData, TumGroundTruthWithRepeatedStampDropsTheRepeat) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "fr2_desk_groundtruth.txt");
  const std::string path = evo("fr2_desk_groundtruth.txt");
  TrajectoryReadReport report;
  const Trajectory t = read_tum(path, &report);
  EXPECT_EQ(report.repeated_stamps_dropped, 1u);
  EXPECT_EQ(t.size(), count_data_lines(path) - 1);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find(":10863: 1 pose(s) with a repeated timestamp dropped"), std::string::npos)
      << report.warnings[0];
  EXPECT_NE(report.warnings[0].find("1311868229.5760 repeats line 10862"), std::string::npos) << report.warnings[0];
  for (std::size_t i = 1; i < t.size(); ++i) ASSERT_LT(t.stamps[i - 1], t.stamps[i]);
}

TEST(TrajectoryRead, RepeatedStampKeepsTheFirstPoseAndIsReported) {
  const std::string path = write_temp("repeat.txt", "# c\n1.5 1 0 0 0 0 0 1\n1.50 2 0 0 0 0 0 1\n1.6 3 0 0 0 0 0 1\n");
  TrajectoryReadReport report;
  const Trajectory t = read_tum(path, &report);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses[0].translation().x(), 1.0);
  EXPECT_EQ(t.poses[1].translation().x(), 3.0);
  EXPECT_EQ(report.repeated_stamps_dropped, 1u);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find(path + ":3: 1 pose(s) with a repeated timestamp dropped"), std::string::npos)
      << report.warnings[0];
}

TEST(TrajectoryRealData, EurocGroundTruth) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "V102_groundtruth.csv");
  TrajectoryReadReport report;
  const Trajectory t = read_euroc(evo("V102_groundtruth.csv"), &report);
  EXPECT_EQ(t.size(), 16702u);
  EXPECT_EQ(report.comment_lines, 1u);
  EXPECT_EQ(report.quaternions_normalised, 0u);
  // "1403715524907143168,0.515356,1.996773,0.971104,0.161996,0.789985,-0.205376,0.554528,..."
  EXPECT_EQ(t.stamps[0].nanoseconds(), 1'403'715'524'907'143'168);
  EXPECT_EQ(t.poses[0].translation(), Vector3(0.515356, 1.996773, 0.971104));
  const Quaternion q = Quaternion(0.161996, 0.789985, -0.205376, 0.554528).normalized();
  EXPECT_NEAR(t.poses[0].unit_quaternion().angularDistance(q), 0.0, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Round trips

TEST(TrajectoryRoundTrip, TumIsBitExact) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "freiburg1_xyz-groundtruth.txt");
  for (const char* name : {"freiburg1_xyz-groundtruth.txt", "fr2_desk_ORB.txt"}) {
    SCOPED_TRACE(name);
    const Trajectory original = read_tum(evo(name));
    const std::string path = scratch(std::string("roundtrip_") + name);
    write_tum(path, original);
    TrajectoryReadReport report;
    const Trajectory back = read_tum(path, &report);
    EXPECT_EQ(report.comment_lines, 1u);  // the header the writer adds
    expect_identical(original, back);
  }
}

TEST(TrajectoryRoundTrip, EurocIsBitExact) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "V102_groundtruth.csv");
  const Trajectory original = read_euroc(evo("V102_groundtruth.csv"));
  const std::string path = scratch("roundtrip_V102.csv");
  write_euroc(path, original);
  expect_identical(original, read_euroc(path));
}

// KITTI stores a matrix: the writer builds R from the unit quaternion and the reader projects
// it back onto SO(3) through an SVD and converts it to a quaternion, each step rounding at
// ~1e-16, so rotations agree to a few ulp rather than bit for bit. Translations and stamps are
// stored as they are and come back exactly.
TEST(TrajectoryRoundTrip, KittiWithTimesToRounding) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "KITTI_00_gt.txt");
  const Trajectory original = read_kitti(evo("KITTI_00_gt.txt"), evo("KITTI_00_gt_times.txt"));
  const std::string path = scratch("roundtrip_kitti.txt");
  const std::string times = scratch("roundtrip_kitti_times.txt");
  write_kitti(path, original, times);
  TrajectoryReadReport report;
  const Trajectory back = read_kitti(path, times, &report);
  expect_close(original, back, 1e-12);
  EXPECT_LT(report.max_rotation_orthonormality_error, 1e-14);
  for (std::size_t i = 0; i < original.size(); ++i) {
    ASSERT_EQ(original.poses[i].translation(), back.poses[i].translation()) << i;
  }
}

TEST(TrajectoryRoundTrip, TumToKittiWithTimesToTum) {
  CAIRN_REQUIRE_DATA(std::string(kEvo) + "freiburg1_xyz-groundtruth.txt");
  const Trajectory tum = read_tum(evo("freiburg1_xyz-groundtruth.txt"));
  const std::string kitti_path = scratch("cross_kitti.txt");
  const std::string times_path = scratch("cross_kitti_times.txt");
  write_kitti(kitti_path, tum, times_path);
  const Trajectory kitti = read_kitti(kitti_path, times_path);
  const std::string tum_path = scratch("cross_tum.txt");
  write_tum(tum_path, kitti);
  const Trajectory back = read_tum(tum_path);
  expect_close(tum, back, 1e-12);
}

TEST(TrajectoryRoundTrip, RandomPosesInEveryFormat) {
  const Trajectory original = random_trajectory(500, 7);
  const std::string tum = scratch("random.tum");
  const std::string euroc = scratch("random.csv");
  const std::string kitti = scratch("random.kitti");
  const std::string times = scratch("random.times");
  write_tum(tum, original);
  write_euroc(euroc, original);
  write_kitti(kitti, original, times);
  expect_identical(original, read_tum(tum));
  expect_identical(original, read_euroc(euroc));
  const Trajectory back = read_kitti(kitti, times);
  // Translations up to 1e300: compare rotations and translations separately.
  ASSERT_EQ(back.stamps, original.stamps);
  for (std::size_t i = 0; i < original.size(); ++i) {
    ASSERT_EQ(back.poses[i].translation(), original.poses[i].translation()) << i;
    ASSERT_LE((back.poses[i].rotation_matrix() - original.poses[i].rotation_matrix()).cwiseAbs().maxCoeff(),
              1e-12)
        << i;
  }
}

TEST(TrajectoryWrite, StreamTextIsExact) {
  Trajectory t;
  t.poses.emplace_back(Quaternion::Identity(), Vector3(1.0, 2.0, 0.1));
  t.stamps.push_back(Timestamp::from_nanoseconds(1'500'000'000));
  std::ostringstream tum;
  write_tum(tum, t);
  EXPECT_EQ(tum.str(), "# timestamp tx ty tz qx qy qz qw\n1.500000000 1 2 0.1 0 0 0 1\n");
  std::ostringstream euroc;
  write_euroc(euroc, t);
  EXPECT_EQ(euroc.str(),
            "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
            "q_RS_z []\n1500000000,1,2,0.1,1,0,0,0\n");
  std::ostringstream kitti;
  std::ostringstream kitti_times;
  write_kitti(kitti, t, &kitti_times);
  EXPECT_EQ(kitti.str(), "1 0 0 1 0 1 0 2 0 0 1 0.1\n");
  EXPECT_EQ(kitti_times.str(), "1.500000000\n");
}

TEST(TrajectoryWrite, ReplacesExistingFileAndLeavesNoTemporary) {
  const std::string dir = scratch("replace");
  fs::create_directories(dir);
  const std::string path = dir + "/out.txt";
  std::ofstream(path) << "old content\n";
  Trajectory t = random_trajectory(3, 1);
  write_tum(path, t);
  expect_identical(t, read_tum(path));
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1u);
}

TEST(TrajectoryWrite, UnwritablePathThrowsAndLeavesNoTemporary) {
  const std::string path = scratch("no_such_dir/out.txt");
  const Trajectory t = random_trajectory(3, 2);
  expect_parse_error([&] { write_tum(path, t); }, 0, "cannot write", path);
  expect_parse_error([&] { write_euroc(path, t); }, 0, "cannot write", path);
  // A KITTI pair whose times cannot be written leaves the pose file untouched too.
  const std::string poses = scratch("kitti_pair.txt");
  std::ofstream(poses) << "old\n";
  expect_parse_error([&] { write_kitti(poses, t, path); }, 0, "cannot write", path);
  EXPECT_EQ(read_all(poses), "old\n");
  for (const auto& entry : fs::directory_iterator(scratch_dir())) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
  }
}

TEST(TrajectoryWrite, RefusesWhatCouldNotBeReadBack) {
  const std::string path = scratch("refused.txt");
  Trajectory no_stamps;
  no_stamps.poses.resize(2);
  expect_parse_error([&] { write_tum(path, no_stamps); }, 0, "no timestamps", path);
  expect_parse_error([&] { write_euroc(path, no_stamps); }, 0, "no timestamps", path);
  const std::string times = scratch("refused_times.txt");
  expect_parse_error([&] { write_kitti(path, no_stamps, times); }, 0, "no timestamps", times);
  write_kitti(path, no_stamps);  // poses alone are fine
  EXPECT_EQ(read_kitti(path).size(), 2u);

  expect_parse_error([&] { write_tum(path, Trajectory{}); }, 0, "no poses", path);
  Trajectory repeated = random_trajectory(3, 3);
  repeated.stamps[2] = repeated.stamps[1];
  expect_parse_error([&] { write_tum(path, repeated); }, 0, "timestamps must increase", path);
  std::ostringstream stream;
  expect_parse_error([&] { write_euroc(stream, repeated); }, 0, "timestamps must increase", "<stream>");
}

// ---------------------------------------------------------------------------------------------
// Tolerated input

TEST(TrajectoryRead, NormalisesFarFromUnitQuaternionsAndWarnsOnce) {
  const std::string path = write_temp("unnormalised.tum",
                                      "1 0 0 0 0 0 0 2\n"
                                      "2 0 0 0 0 0 0 1.0005\n"  // within tolerance: not counted
                                      "3 0 0 0 0 0 0 0.5\n"
                                      "4 0 0 0 1e200 0 0 0\n"     // squares overflow
                                      "5 0 0 0 0 -1e-200 0 0\n");  // squares underflow
  TrajectoryReadReport report;
  const Trajectory t = read_tum(path, &report);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(report.quaternions_normalised, 4u);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find(path + ":1: 4 quaternion(s)"), std::string::npos) << report.warnings[0];
  EXPECT_EQ(t.poses[0].unit_quaternion().coeffs(), Vector4(0, 0, 0, 1));
  EXPECT_NEAR(t.poses[1].unit_quaternion().w(), 1.0, 1e-15);
  EXPECT_EQ(t.poses[2].unit_quaternion().coeffs(), Vector4(0, 0, 0, 1));
  EXPECT_EQ(t.poses[3].unit_quaternion().coeffs(), Vector4(1, 0, 0, 0));
  EXPECT_EQ(t.poses[4].unit_quaternion().coeffs(), Vector4(0, -1, 0, 0));
}

TEST(TrajectoryRead, TumAcceptsTabsCrLfBlankLinesAndExponents) {
  const std::string path = write_temp("lenient.tum",
                                      "# comment\r\n"
                                      "\r\n"
                                      "1.036614e-01\t1 2 3  0 0 0 1\r\n"
                                      "   # indented comment\n"
                                      "+2.5 -1e-3 0 0 0 0 0 1");  // no final newline
  TrajectoryReadReport report;
  const Trajectory t = read_tum(path, &report);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(report.comment_lines, 3u);
  EXPECT_EQ(t.stamps[0].nanoseconds(), 103'661'400);
  EXPECT_EQ(t.stamps[1].nanoseconds(), 2'500'000'000);
  EXPECT_EQ(t.poses[1].translation().x(), -1e-3);
}

TEST(TrajectoryRead, EurocIgnoresExtraColumnsWithoutParsingThem) {
  const std::string path = write_temp("extra.csv",
                                      "#timestamp,x,y,z,qw,qx,qy,qz,anything\n"
                                      "100,1,2,3,1,0,0,0,not-a-number,nan\n"
                                      "200, 1 , 2 , 3 , 1 , 0 , 0 , 0\n");
  const Trajectory t = read_euroc(path);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.stamps[1].nanoseconds(), 200);
  EXPECT_EQ(t.poses[1].translation(), Vector3(1, 2, 3));
}

TEST(TrajectoryRead, KittiProjectsNearlyOrthonormalRotationAndReportsError) {
  const std::string path = write_temp("nearly.kitti",
                                      "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                      "1.001 0 0 5 0 1 0 6 0 0 1 7\n");
  TrajectoryReadReport report;
  const Trajectory t = read_kitti(path, "", &report);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(report.max_rotation_orthonormality_error, 1.001 * 1.001 - 1.0, 1e-15);
  EXPECT_LT((t.poses[1].rotation_matrix() - Matrix3::Identity()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(t.poses[1].translation(), Vector3(5, 6, 7));
}

// ---------------------------------------------------------------------------------------------
// Hostile input, one table for the three single-file readers

struct HostileCase {
  const char* name;
  TrajectoryFormat format;
  std::string content;
  std::size_t line;
  const char* phrase;
};

void PrintTo(const HostileCase& c, std::ostream* os) { *os << c.name; }

std::string case_name(const ::testing::TestParamInfo<HostileCase>& param_info) {
  return param_info.param.name;
}

class TrajectoryHostile : public ::testing::TestWithParam<HostileCase> {};

TEST_P(TrajectoryHostile, ThrowsParseErrorAtLineWithMessage) {
  const HostileCase& c = GetParam();
  const std::string path = write_temp(std::string("hostile_") + c.name, c.content);
  expect_parse_error(
      [&] {
        switch (c.format) {
          case TrajectoryFormat::kTum:
            read_tum(path);
            break;
          case TrajectoryFormat::kKitti:
            read_kitti(path);
            break;
          case TrajectoryFormat::kEuroc:
            read_euroc(path);
            break;
        }
      },
      c.line, c.phrase, path);
}

constexpr auto kTum = TrajectoryFormat::kTum;
constexpr auto kKitti = TrajectoryFormat::kKitti;
constexpr auto kEuroc = TrajectoryFormat::kEuroc;
const std::string kTumOk = "1.0 0 0 0 0 0 0 1\n";
const std::string kKittiOk = "1 0 0 0 0 1 0 0 0 0 1 0\n";
const std::string kEurocHeader = "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n";

INSTANTIATE_TEST_SUITE_P(
    Tum, TrajectoryHostile,
    ::testing::Values(
        HostileCase{"truncated_line", kTum, kTumOk + "2.0 0 0 0 0 0 0\n", 2, "TUM line expects 8 numbers, found 7"},
        HostileCase{"cut_mid_number", kTum, kTumOk + "2.0 0 0 0 0 0 0 1e", 2, "expected a finite number for qw, found '1e'"},
        HostileCase{"nan_translation", kTum, kTumOk + "2.0 nan 0 0 0 0 0 1\n", 2, "expected a finite number for tx, found 'nan'"},
        HostileCase{"nan_timestamp", kTum, "nan 0 0 0 0 0 0 1\n", 1, "expected a timestamp in seconds, found 'nan'"},
        HostileCase{"inf_quaternion", kTum, "1.0 0 0 0 0 0 0 inf\n", 1, "expected a finite number for qw, found 'inf'"},
        HostileCase{"overflow", kTum, "1.0 0 1e999 0 0 0 0 1\n", 1, "expected a finite number for ty, found '1e999'"},
        HostileCase{"huge_timestamp", kTum, "99999999999999999999 0 0 0 0 0 0 1\n", 1, "expected a timestamp in seconds"},
        HostileCase{"timestamp_beyond_2261", kTum, "9210000000.5 0 0 0 0 0 0 1\n", 1,
                    "timestamp out of range: expected at most 9.2e9 s from the epoch, found '9210000000.5'"},
        HostileCase{"text_garbage", kTum, "# header\nhello world\n", 2, "TUM line expects 8 numbers, found 2"},
        HostileCase{"eight_words", kTum, "a b c d e f g h\n", 1, "expected a timestamp in seconds, found 'a'"},
        HostileCase{"euroc_line", kTum, "1403715524907143168,0.5,2.0,0.9,0.1,0.7,-0.2,0.5\n", 1, "TUM line expects 8 numbers, found 1"},
        HostileCase{"empty_file", kTum, "", 0, "no poses found: expected lines 'timestamp tx ty tz qx qy qz qw'"},
        HostileCase{"comment_only", kTum, "# a\n\n# b\n", 0, "no poses found"},
        HostileCase{"binary_bytes", kTum, kTumOk + std::string("\x01\x02\x00\xff", 4), 2, "binary data (byte 0x01 at column 1)"},
        HostileCase{"gzip", kTum, std::string("\x1f\x8b\x08\x00rest", 8), 0, "gzip-compressed"},
        HostileCase{"decreasing_timestamps", kTum, "13.0 0 0 0 0 0 0 1\n12.5 0 0 0 0 0 0 1\n", 2,
                    "timestamps must increase: 12.5 follows 13.0 (line 1)"},
        HostileCase{"repeat_then_decrease", kTum, "# c\n1.5 0 0 0 0 0 0 1\n1.50 0 0 0 0 0 0 1\n1.4 0 0 0 0 0 0 1\n", 4,
                    "timestamps must increase: 1.4 follows 1.5 (line 2)"},
        HostileCase{"zero_quaternion", kTum, kTumOk + "2.0 1 2 3 0 0 0 0\n", 2, "quaternion has zero norm"},
        HostileCase{"negative_zero_quaternion", kTum, "2.0 1 2 3 -0 0 -0.0 0e5\n", 1, "quaternion has zero norm"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Kitti, TrajectoryHostile,
    ::testing::Values(
        HostileCase{"truncated_line", kKitti, kKittiOk + "1 0 0 0 0 1 0 0 0 0 1\n", 2, "KITTI line expects 12 numbers, found 11"},
        HostileCase{"tum_line", kKitti, kTumOk, 1, "KITTI line expects 12 numbers, found 8"},
        HostileCase{"nan", kKitti, kKittiOk + "1 0 0 nan 0 1 0 0 0 0 1 0\n", 2, "expected a finite number for tx, found 'nan'"},
        HostileCase{"inf", kKitti, "1 0 0 0 0 1 0 0 0 0 inf 0\n", 1, "expected a finite number for r33, found 'inf'"},
        HostileCase{"text_garbage", kKitti, "lorem ipsum dolor sit amet consectetur adipiscing elit sed do eiusmod tempor\n", 1,
                    "expected a finite number for r11, found 'lorem'"},
        HostileCase{"scaled_rotation", kKitti, kKittiOk + kKittiOk + "2 0 0 0 0 2 0 0 0 0 2 0\n", 3,
                    "rotation block is not a rotation (|R^T R - I| = 3, limit 0.01)"},
        HostileCase{"huge_entries", kKitti, "1e200 0 0 0 0 1 0 0 0 0 1 0\n", 1, "rotation block is not a rotation (|R^T R - I| = inf"},
        HostileCase{"reflection", kKitti, "1 0 0 0 0 1 0 0 0 0 -1 0\n", 1, "rotation block is a reflection"},
        HostileCase{"zero_matrix", kKitti, "0 0 0 0 0 0 0 0 0 0 0 0\n", 1, "rotation block is not a rotation (|R^T R - I| = 1"},
        HostileCase{"empty_file", kKitti, "", 0, "no poses found: expected lines 'r11 r12 r13 tx"},
        HostileCase{"comment_only", kKitti, "# poses\n", 0, "no poses found"},
        HostileCase{"binary_bytes", kKitti, kKittiOk + "1 0 0 0 0 1 0 0 0 0 1 \x7f\n", 2, "binary data (byte 0x7f at column 23)"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Euroc, TrajectoryHostile,
    ::testing::Values(
        HostileCase{"truncated_line", kEuroc, kEurocHeader + "100,1,2,3,1,0,0\n", 2,
                    "EuRoC line expects at least 8 comma-separated fields, found 7"},
        HostileCase{"tum_line", kEuroc, kTumOk, 1, "EuRoC line expects at least 8 comma-separated fields, found 1"},
        HostileCase{"nan", kEuroc, kEurocHeader + "100,1,2,3,1,nan,0,0\n", 2, "expected a finite number for qx, found 'nan'"},
        HostileCase{"minus_inf", kEuroc, "100,-inf,2,3,1,0,0,0\n", 1, "expected a finite number for tx, found '-inf'"},
        HostileCase{"empty_field", kEuroc, "100,1,,3,1,0,0,0\n", 1, "expected a finite number for ty, found ''"},
        HostileCase{"seconds_timestamp", kEuroc, "1403715524.907143168,1,2,3,1,0,0,0\n", 1,
                    "expected an integer timestamp in nanoseconds, found '1403715524.907143168'"},
        HostileCase{"header_without_hash", kEuroc, "timestamp,x,y,z,qw,qx,qy,qz\n", 1,
                    "expected an integer timestamp in nanoseconds, found 'timestamp'"},
        HostileCase{"timestamp_overflow", kEuroc, "99999999999999999999,1,2,3,1,0,0,0\n", 1,
                    "expected an integer timestamp in nanoseconds"},
        HostileCase{"int64_max_timestamp", kEuroc, "9223372036854775807,1,2,3,1,0,0,0\n", 1, "timestamp out of range"},
        HostileCase{"decreasing_timestamps", kEuroc, kEurocHeader + "2000,0,0,0,1,0,0,0\n1000,0,0,0,1,0,0,0\n", 3,
                    "timestamps must increase: 1000 follows 2000 (line 2)"},
        HostileCase{"zero_quaternion", kEuroc, "100,1,2,3,0,0,0,0\n", 1, "quaternion has zero norm"},
        HostileCase{"empty_file", kEuroc, "", 0, "no poses found: expected lines 'timestamp_ns,px,py,pz,qw,qx,qy,qz'"},
        HostileCase{"header_only", kEuroc, kEurocHeader, 0, "no poses found"},
        HostileCase{"binary_bytes", kEuroc, kEurocHeader + std::string("100,1,2,3,1,0,0,0\0\n", 19), 2, "binary data (byte 0x00"}),
    case_name);

TEST(TrajectoryHostileFiles, MissingFile) {
  const std::string path = scratch("does_not_exist.txt");
  expect_parse_error([&] { read_tum(path); }, 0, "cannot open file", path);
  expect_parse_error([&] { read_kitti(path); }, 0, "cannot open file", path);
  expect_parse_error([&] { read_euroc(path); }, 0, "cannot open file", path);
}

TEST(TrajectoryHostileFiles, HugeLine) {
  const std::string path = write_temp("huge.tum", kTumOk + std::string(kMaxLineBytes + 100, '1') + "\n");
  expect_parse_error([&] { read_tum(path); }, 2, "line is longer than", path);
}

TEST(TrajectoryHostileFiles, HugeTimestampTokenIsShortenedInTheMessage) {
  const std::string long_stamp = "1." + std::string(10'000, '0');
  const std::string path = write_temp("long_stamp.tum", "2 0 0 0 0 0 0 1\n" + long_stamp + " 0 0 0 0 0 0 1\n");
  try {
    read_tum(path);
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 2u);
    EXPECT_LT(e.detail().size(), 200u) << e.detail();
  }
}

// KITTI times file: one time per pose.

class KittiTimes : public ::testing::Test {
 protected:
  const std::string poses_ = write_temp("times_poses.kitti", kKittiOk + kKittiOk + kKittiOk);
};

TEST_F(KittiTimes, ReadsOneTimePerPose) {
  const std::string times = write_temp("times_ok.txt", "0.000000e+00\n# c\n1.037359e-01\n0.25\n");
  TrajectoryReadReport report;
  const Trajectory t = read_kitti(poses_, times, &report);
  ASSERT_EQ(t.stamps.size(), 3u);
  EXPECT_EQ(t.stamps[2].nanoseconds(), 250'000'000);
  EXPECT_EQ(report.comment_lines, 1u);
}

TEST_F(KittiTimes, FewerTimesThanPoses) {
  const std::string times = write_temp("times_short.txt", "0\n1\n");
  expect_parse_error([&] { read_kitti(poses_, times); }, 0,
                     "times file has 2 times but pose file " + poses_ + " has 3 poses", times);
}

TEST_F(KittiTimes, MoreTimesThanPoses) {
  const std::string times = write_temp("times_long.txt", "0\n1\n2\n3\n");
  expect_parse_error([&] { read_kitti(poses_, times); }, 0, "times file has 4 times but pose file", times);
}

TEST_F(KittiTimes, EmptyTimesFile) {
  const std::string times = write_temp("times_empty.txt", "");
  expect_parse_error([&] { read_kitti(poses_, times); }, 0, "times file has 0 times", times);
}

TEST_F(KittiTimes, DecreasingTimes) {
  const std::string times = write_temp("times_decreasing.txt", "0\n13.0\n12.5\n");
  expect_parse_error([&] { read_kitti(poses_, times); }, 3, "timestamps must increase: 12.5 follows 13.0 (line 2)",
                     times);
}

TEST_F(KittiTimes, TwoNumbersOnALine) {
  const std::string times = write_temp("times_two.txt", "0\n1 2\n3\n");
  expect_parse_error([&] { read_kitti(poses_, times); }, 2, "KITTI times line expects 1 number, found 2", times);
}

TEST_F(KittiTimes, NanAndBinary) {
  const std::string nan_times = write_temp("times_nan.txt", "0\nnan\n3\n");
  expect_parse_error([&] { read_kitti(poses_, nan_times); }, 2, "expected a timestamp in seconds, found 'nan'");
  const std::string binary = write_temp("times_binary.txt", std::string("0\n1\n\x00\x01", 6));
  expect_parse_error([&] { read_kitti(poses_, binary); }, 3, "binary data");
}

TEST_F(KittiTimes, MissingTimesFile) {
  const std::string times = scratch("times_missing.txt");
  expect_parse_error([&] { read_kitti(poses_, times); }, 0, "cannot open file", times);
}

}  // namespace
}  // namespace cairn::io
