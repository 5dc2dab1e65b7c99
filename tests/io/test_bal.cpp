// The BAL reader and writer (io/bal.hpp): the real files of ../shared/data/bal with the counts
// and costs their SOURCE.txt states, and every kind of bad input with file:line errors.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

#include "cairn/io/bal.hpp"
#include "cairn/io/parse_error.hpp"
#include "../test_data.hpp"

namespace cairn::io {
namespace {

/// 1/2 sum of squared residuals of BAL's model, written out independently of the backend.
double initial_cost(const BalProblem& problem) {
  double cost = 0.0;
  for (const BalObservation& o : problem.observations) {
    const double* c = problem.camera(o.camera);
    const Eigen::Vector3d w(c[0], c[1], c[2]);
    const double angle = w.norm();
    const Eigen::Matrix3d R =
        angle > 0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
    const Eigen::Vector3d P = R * Eigen::Vector3d(problem.point(o.point)) + Eigen::Vector3d(c + 3);
    const Eigen::Vector2d p = -P.head<2>() / P.z();
    const double r2 = p.squaredNorm();
    const Eigen::Vector2d predicted = c[6] * (1.0 + c[7] * r2 + c[8] * r2 * r2) * p;
    cost += 0.5 * (predicted - Eigen::Vector2d(o.x, o.y)).squaredNorm();
  }
  return cost;
}

std::string message_of(const std::string& text) {
  try {
    parse_bal("test.txt", text);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Bal, ReadsTheRealProblemsWithTheCountsAndCostsOfTheirSourceFile) {
  CAIRN_REQUIRE_DATA("bal/problem-49-7776-pre.txt.bz2");
  struct Expected {
    const char* file;
    int cameras, points;
    std::size_t observations;
    double cost;
    std::size_t behind;
  };
  // SOURCE.txt: counts, "Initial cost 0.5*sum r^2" and the points behind their camera.
  for (const Expected& e : {Expected{"bal/problem-49-7776-pre.txt.bz2", 49, 7776, 31843, 8.5091246068e+05, 31},
                            Expected{"bal/problem-21-11315-pre.txt.bz2", 21, 11315, 36455, 4.4132393144e+06, 0},
                            Expected{"bal/dubrovnik-3-7-pre.txt", 3, 7, 19, 2.764220e+03, 0}}) {
    const BalProblem problem = read_bal(cairn::test::data_path(e.file).string());
    EXPECT_EQ(problem.num_cameras, e.cameras) << e.file;
    EXPECT_EQ(problem.num_points, e.points) << e.file;
    EXPECT_EQ(problem.observations.size(), e.observations) << e.file;
    EXPECT_NEAR(initial_cost(problem), e.cost, 1e-6 * e.cost) << e.file;
    EXPECT_EQ(count_points_behind_camera(problem), e.behind) << e.file;
  }
}

TEST(Bal, WriteThenReadRoundTripsExactly) {
  CAIRN_REQUIRE_DATA("bal/dubrovnik-3-7-pre.txt");
  const BalProblem problem = read_bal(cairn::test::data_path("bal/dubrovnik-3-7-pre.txt").string());
  std::ostringstream out;
  write_bal(out, problem);
  const BalProblem again = parse_bal("round trip", out.str());
  EXPECT_EQ(again.cameras, problem.cameras);
  EXPECT_EQ(again.points, problem.points);
  ASSERT_EQ(again.observations.size(), problem.observations.size());
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    EXPECT_EQ(again.observations[i].camera, problem.observations[i].camera);
    EXPECT_EQ(again.observations[i].x, problem.observations[i].x);
  }
}

// A valid 1-camera, 1-point, 1-observation problem, one number per line after the observation.
const std::string kTiny =
    "1 1 1\n"
    "0 0 1.5 -2.5\n"
    "0.1\n0.2\n0.3\n1\n2\n-5\n500\n0\n0\n"
    "1\n2\n3\n";

TEST(Bal, ParsesTokensAcrossBlankLinesAndCarriageReturns) {
  const BalProblem problem = parse_bal("tiny", "1 1 1\r\n\r\n0 0 1.5 -2.5\n\n0.1 0.2 0.3 1 2 -5 500 0 0\n\n1 2 3");
  EXPECT_EQ(problem.cameras[6], 500.0);
  EXPECT_EQ(problem.points[2], 3.0);
  EXPECT_EQ(problem.observations[0].y, -2.5);
  EXPECT_NO_THROW(parse_bal("tiny", kTiny));
}

TEST(Bal, BadInputGetsTheFileTheLineAndWhatWasExpected) {
  EXPECT_EQ(message_of(""), "test.txt: file is empty: expected a BAL header '<cameras> <points> <observations>'");
  // Truncated: the last point coordinate is missing.
  EXPECT_EQ(message_of(kTiny.substr(0, kTiny.size() - 2)),
            "test.txt:14: file ends early: expected point 0 coordinate z (3 numbers per point) (truncated file?)");
  // Camera index out of range, on line 2.
  std::string text = kTiny;
  text.replace(text.find("0 0 1.5"), 1, "3");
  EXPECT_EQ(message_of(text),
            "test.txt:2: the camera index of observation 1 of 1 3 is out of range: expected less than 1");
  // NaN among the camera parameters (line 9 holds f).
  text = kTiny;
  text.replace(text.find("500"), 3, "nan");
  EXPECT_EQ(message_of(text), "test.txt:9: expected a finite number for camera 0 parameter f (9 numbers per camera), found 'nan'");
  // Extra data after the points.
  EXPECT_EQ(message_of(kTiny + "4\n"),
            "test.txt:15: unexpected data after the last point: '4' (the header announces 1 cameras, 1 points, 1 observations)");
  // Binary bytes.
  text = kTiny;
  text.replace(text.find("1.5"), 1, std::string(1, '\x01'));
  EXPECT_EQ(message_of(text), "test.txt:2: binary data (byte 0x01): expected BAL text (numbers separated by white space)");
  // A header announcing more than the file can hold is refused before any allocation.
  EXPECT_NE(message_of("1000000 1000000 2000000000\n0 0 1 1\n").find("more than a file of"), std::string::npos);
  EXPECT_NE(message_of("-1 1 1\n").find("expected a non-negative integer for the number of cameras"), std::string::npos);
  EXPECT_NE(message_of("0 1 1\n").find("at least one camera"), std::string::npos);
  EXPECT_NE(message_of("1 1 x\n").find("test.txt:1: expected a non-negative integer for the number of observations"),
            std::string::npos);
}

TEST(Bal, MissingFileIsAnError) {
  EXPECT_THROW(read_bal("/nonexistent/problem.txt"), ParseError);
}

}  // namespace
}  // namespace cairn::io
