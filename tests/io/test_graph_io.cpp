// g2o and TORO readers and writers on small hand-written graphs: values, round trips, and every
// kind of malformed input, each checked for the line and the words of its error.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "cairn/io/parse_error.hpp"
#include "graph_test_utils.hpp"

namespace cairn::io {
namespace {

using test::temp_file;

GraphFile read_text(const std::string& name, const std::string& content, GraphReadOptions options = {}) {
  return read_graph(temp_file(name, content), options);
}

// Expects a ParseError at `line` whose message contains `phrase`.
void expect_error(const std::string& name, const std::string& content, std::size_t line, const std::string& phrase,
                  GraphReadOptions options = {}) {
  const std::string path = temp_file(name, content);
  try {
    read_graph(path, options);
    ADD_FAILURE() << name << ": expected ParseError containing '" << phrase << "'";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), path) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
  }
}

const char* kG2o2D =
    "# a comment\n"
    "VERTEX_SE2 0 0 0 0\n"
    "VERTEX_SE2 1 1.5 -0.25 3.0\n"
    "VERTEX_SE2 2 2 0 -3.141592653589793\n"
    "EDGE_SE2 0 1 1.5 -0.25 3.0 500 0 0 500 0 2000\n"
    "EDGE_SE2 1 2 0.5 0.25 0.1 400 10 0 400 0 1000\n"
    "EDGE_SE2 0 2 2 0 3.141592653589793 100 0 0 100 0 100\n"
    "FIX 0\n";

TEST(G2oReader, Reads2DValuesExactly) {
  const GraphFile file = read_text("a.g2o", kG2o2D);
  ASSERT_EQ(dimension(file.graph), 2);
  const auto& g = std::get<PoseGraph2D>(file.graph);
  ASSERT_EQ(g.vertices.size(), 3u);
  ASSERT_EQ(g.edges.size(), 3u);
  EXPECT_EQ(g.vertices[1].T_world_pose.x(), 1.5);
  EXPECT_EQ(g.vertices[1].T_world_pose.angle(), 3.0);
  // -pi is wrapped to +pi: the same rotation, angle in (-pi, pi].
  EXPECT_EQ(g.vertices[2].T_world_pose.angle(), 3.141592653589793);
  EXPECT_EQ(g.edges[1].information(0, 1), 10.0);
  EXPECT_EQ(g.edges[1].information(1, 0), 10.0);
  EXPECT_EQ(g.edges[1].information(2, 2), 1000.0);
  EXPECT_EQ(g.edges[1].line, 6u);
  EXPECT_EQ(g.fixed, std::vector<std::int64_t>{0});
  EXPECT_EQ(file.report.records.at("EDGE_SE2").count, 3u);
  EXPECT_EQ(file.report.records.at("VERTEX_SE2").first_line, 2u);
  EXPECT_TRUE(file.report.warnings.empty());
}

TEST(G2oReader, Reads3DAndNormalisesQuaternions) {
  std::string info;
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) info += r == c ? " 100" : " 0";
  }
  const std::string text = "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n"
                           "VERTEX_SE3:QUAT 1 1 2 3 0 0 0 2\n"  // norm 2: normalised, counted
                           "EDGE_SE3:QUAT 0 1 1 2 3 0 0 0.7071067811865476 0.7071067811865476" + info + "\n";
  const GraphFile file = read_text("b.g2o", text);
  ASSERT_EQ(dimension(file.graph), 3);
  const auto& g = std::get<PoseGraph3D>(file.graph);
  EXPECT_EQ(g.vertices[1].T_world_pose.unit_quaternion().w(), 1.0);
  EXPECT_EQ(file.report.quaternions_not_unit, 1u);
  EXPECT_NEAR(g.edges[0].T_from_to.so3().angle(), M_PI / 2, 1e-15);
}

TEST(G2oWriter, RoundTripIsBitExact2DAnd3D) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  PoseGraph2D g2;
  PoseGraph3D g3;
  for (int i = 0; i < 200; ++i) {
    g2.vertices.push_back({i, core::SE2(u(rng), u(rng), u(rng) / 30.0)});
    g3.vertices.push_back({i, core::SE3(Quaternion(u(rng), u(rng), u(rng), u(rng)), Vector3(u(rng), u(rng), u(rng)))});
    if (i > 0) {
      GraphEdge<core::SE2> e2;
      e2.from = i - 1;
      e2.to = i;
      e2.T_from_to = core::SE2(u(rng), u(rng), u(rng) / 30.0);
      const Matrix3 A = Matrix3::Random();
      const Matrix3 S = A * A.transpose() + Matrix3::Identity();
      e2.information = 0.5 * (S + S.transpose());  // information is symmetric by contract
      g2.edges.push_back(e2);
      GraphEdge<core::SE3> e3;
      e3.from = i;
      e3.to = i - 1;
      e3.T_from_to = core::SE3(Quaternion(u(rng), u(rng), u(rng), u(rng)), Vector3(u(rng), u(rng), u(rng)));
      const Matrix6 B = Matrix6::Random();
      const Matrix6 S3 = B * B.transpose() + Matrix6::Identity();
      e3.information = 0.5 * (S3 + S3.transpose());
      g3.edges.push_back(e3);
    }
  }
  g2.fixed = {0, 5};
  g3.fixed = {3};
  // The in-memory graph was not read from a file, so compare read-back copies: read(write(read(write(g))))
  // must equal read(write(g)), and the first read must match g to the last bit for exactly representable
  // inputs (every double is written in its shortest round-trip form).
  for (const PoseGraph& graph : {PoseGraph(g2), PoseGraph(g3)}) {
    const GraphFile once = test::write_and_read(graph, GraphFormat::kG2o, "rt1.g2o");
    EXPECT_TRUE(test::graphs_identical(graph, once.graph));
    const GraphFile twice = test::write_and_read(once.graph, GraphFormat::kG2o, "rt2.g2o");
    EXPECT_TRUE(test::graphs_identical(once.graph, twice.graph));
  }
}

TEST(ToroReader, ReadsTwoDInToroOrderAndRoundTrips) {
  // I_xx I_xy I_yy I_tt I_xt I_yt = 1 0.1 2 3 0.2 0.3
  const std::string text = "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0.5\nEDGE2 0 1 1 0 0.5 1 0.1 2 3 0.2 0.3\n";
  const GraphFile file = read_text("t.graph", text);
  const auto& g = std::get<PoseGraph2D>(file.graph);
  const Matrix3& I = g.edges[0].information;
  EXPECT_EQ(I(0, 0), 1.0);
  EXPECT_EQ(I(0, 1), 0.1);
  EXPECT_EQ(I(1, 1), 2.0);
  EXPECT_EQ(I(2, 2), 3.0);
  EXPECT_EQ(I(0, 2), 0.2);
  EXPECT_EQ(I(2, 1), 0.3);
  EXPECT_EQ(file.report.toro_information_order, "toro");
  const GraphFile back = test::write_and_read(file.graph, GraphFormat::kToro, "t2.graph");
  EXPECT_TRUE(test::graphs_identical(file.graph, back.graph));
  const GraphFile as_g2o = test::write_and_read(file.graph, GraphFormat::kG2o, "t3.g2o");
  EXPECT_TRUE(test::graphs_identical(file.graph, as_g2o.graph));
}

TEST(ToroReader, AutoOrderSwitchesToG2oOnlyWhenToroOrderIsInvalidEverywhere) {
  // g2o order: diag(3.16, 3.16, 5). In TORO order I_yy = 0: invalid.
  const std::string text = "EDGE2 0 1 1 0 0 3.16 0 0 3.16 0 5\nEDGE2 1 2 1 0 0 3.16 0 0 3.16 0 5\n";
  const GraphFile file = read_text("w.txt", text);
  EXPECT_EQ(file.report.toro_information_order, "g2o");
  const auto& g = std::get<PoseGraph2D>(file.graph);
  EXPECT_EQ(g.edges[0].information(1, 1), 3.16);
  EXPECT_EQ(g.edges[0].information(2, 2), 5.0);
  ASSERT_EQ(file.report.warnings.size(), 1u);
  EXPECT_TRUE(g.vertices.empty());
  // Forcing TORO order makes the zero diagonal an error at the first edge.
  GraphReadOptions toro;
  toro.toro_information_order = ToroInformationOrder::kToro;
  expect_error("w2.txt", text, 1, "I(2,2) is 0: expected > 0", toro);
}

TEST(ToroReader, ThreeDWithAndWithoutInformation) {
  std::string info;
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) info += r == c ? " 4" : " 0";
  }
  const std::string text = "VERTEX3 0 0 0 0 0 0 0\nVERTEX3 1 1 2 3 0.1 0.2 0.3\nVERTEX3 2 1 2 3 0.1 0.2 0.3\n"
                           "EDGE3 0 1 1 2 3 0.1 0.2 0.3" + info + "\nEDGE3 1 2 0 0 0 0 0 0\n";
  const GraphFile file = read_text("s.graph", text);
  const auto& g = std::get<PoseGraph3D>(file.graph);
  EXPECT_EQ(file.report.edges_without_information, 1u);
  EXPECT_EQ(g.edges[1].information, Matrix6::Identity());
  EXPECT_EQ(g.edges[0].information(3, 3), 4.0);
  const Vector3 rpy = g.vertices[1].T_world_pose.so3().to_rpy();
  EXPECT_NEAR(rpy.x(), 0.1, 1e-15);
  EXPECT_NEAR(rpy.y(), 0.2, 1e-15);
  EXPECT_NEAR(rpy.z(), 0.3, 1e-15);
  // R = Rz(yaw) Ry(pitch) Rx(roll).
  const Matrix3 expected = (Eigen::AngleAxisd(0.3, Vector3::UnitZ()) * Eigen::AngleAxisd(0.2, Vector3::UnitY()) *
                            Eigen::AngleAxisd(0.1, Vector3::UnitX())).toRotationMatrix();
  EXPECT_TRUE(g.vertices[1].T_world_pose.rotation_matrix().isApprox(expected, 1e-15));
  // TORO 3D stores roll-pitch-yaw, so a round trip through TORO matches to rounding, not bits.
  const GraphFile back = test::write_and_read(file.graph, GraphFormat::kToro, "s2.graph");
  const auto& h = std::get<PoseGraph3D>(back.graph);
  for (std::size_t i = 0; i < g.vertices.size(); ++i) {
    EXPECT_LT((g.vertices[i].T_world_pose.inverse() * h.vertices[i].T_world_pose).log().norm(), 1e-15);
  }
}

TEST(GraphReader, CountsUnknownRecordsAndRefusesThemWhenStrict) {
  const std::string text = "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEQUIV 0 1\nBR 0 1 0.5 2.0\nEQUIV 1 0\n"
                           "EDGE2 0 1 1 0 0 1 0 1 1 0 0\n";
  const GraphFile file = read_text("u.graph", text);
  EXPECT_EQ(file.report.unknown_records.at("EQUIV").count, 2u);
  EXPECT_EQ(file.report.unknown_records.at("EQUIV").first_line, 3u);
  EXPECT_EQ(file.report.unknown_records.at("BR").count, 1u);
  GraphReadOptions strict;
  strict.reject_unknown_records = true;
  expect_error("u2.graph", text, 3, "unknown record type 'EQUIV'", strict);
}

TEST(GraphReader, IndefiniteInformationFollowsThePolicy) {
  // Positive diagonal, strong coupling: eigenvalues of [[10, 84], [84, 10]] are 94 and -74.
  std::string info;
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) info += r == c ? " 10" : (r == 2 && c == 3 ? " 84" : " 0");
  }
  const std::string text = "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 1\n"
                           "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1" + info + "\n";
  const GraphFile projected = read_text("i.g2o", text);
  EXPECT_EQ(projected.report.information_indefinite, 1u);
  EXPECT_EQ(projected.report.first_indefinite_line, 3u);
  const Matrix6& P = std::get<PoseGraph3D>(projected.graph).edges[0].information;
  const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(P);
  EXPECT_GE(eigen.eigenvalues().minCoeff(), -1e-12);
  // Higham's projection of [[10, 84], [84, 10]] keeps the eigenvalue 94 along (1, 1)/sqrt(2).
  EXPECT_NEAR(P(2, 2), 47.0, 1e-12);
  EXPECT_NEAR(P(2, 3), 47.0, 1e-12);
  EXPECT_EQ(P(0, 0), 10.0);
  // Reading the projected file back classifies it as singular, keeps it, and is exact.
  const GraphFile again = test::write_and_read(projected.graph, GraphFormat::kG2o, "i2.g2o");
  EXPECT_EQ(again.report.information_indefinite, 0u);
  EXPECT_EQ(again.report.information_singular, 1u);
  EXPECT_TRUE(test::graphs_identical(projected.graph, again.graph));

  GraphReadOptions keep;
  keep.information_policy = InformationPolicy::kKeep;
  EXPECT_EQ(std::get<PoseGraph3D>(read_text("i3.g2o", text, keep).graph).edges[0].information(2, 3), 84.0);
  GraphReadOptions reject;
  reject.information_policy = InformationPolicy::kReject;
  expect_error("i4.g2o", text, 3, "indefinite", reject);
}

TEST(GraphReader, MalformedInputNamesLineAndExpectation) {
  const std::string v = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
  expect_error("e1.g2o", v + "EDGE_SE2 0 1 1 0 0 1 0 0 1\n", 3, "EDGE_SE2 expects 11 values after the tag");
  expect_error("e1b.g2o", v + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1 5\n", 3, "found 12");
  expect_error("e2.g2o", v + "EDGE_SE2 0 1 1 0 nan 1 0 0 1 0 1\n", 3, "expected a finite number for dtheta, found 'nan'");
  expect_error("e3.g2o", v + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 abc\n", 3, "found 'abc'");
  expect_error("e4.g2o", v + "EDGE_SE2 0 7 1 0 0 1 0 0 1 0 1\n", 3, "pose 7, which has no VERTEX line");
  expect_error("e5.g2o", "", 0, "empty file");
  expect_error("e6.g2o", "# only a comment\n\n", 0, "no pose records");
  expect_error("e7.g2o", v + std::string("EDGE_SE2 0 1\0\x01\x02 garbage\n", 24), 3, "binary data");
  expect_error("e8.g2o", v + "EDGE_SE2 0 1 1 0 0 -1 0 0 1 0 1\n", 3, "I(1,1) is -1: expected > 0");
  expect_error("e9.g2o", v + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 0\n", 3, "I(3,3) is 0");
  expect_error("e10.g2o", v + "VERTEX_SE2 1 2 0 0\n", 3, "pose 1 is defined twice (first at line 2)");
  expect_error("e11.g2o", v + "EDGE_SE2 1 1 1 0 0 1 0 0 1 0 1\n", 3, "to itself");
  expect_error("e12.g2o", v + "VERTEX_SE3:QUAT 2 0 0 0 0 0 0 1\n", 3, "is a 3D record, but the graph is 2D");
  expect_error("e13.g2o", v + "FIX 9\n", 3, "FIX refers to pose 9");
  expect_error("e14.g2o", v + "FIX\n", 3, "FIX expects at least one pose id");
  expect_error("e15.g2o", "VERTEX_SE2 -1 0 0 0\n", 1, "expected a non-negative integer for the pose id");
  expect_error("e16.g2o", "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 0\n", 1, "quaternion (qx qy qz qw) has zero norm");
  expect_error("e17.g2o", "VERTEX_SE2 0 1e999 0 0\n", 1, "expected a finite number for x");
  expect_error("e18.graph", "EDGE3 0 1 1 2 3\n", 1, "EDGE3 expects 8 values");
  expect_error("e19.txt", "hello world\n", 0, "cannot tell the graph format");
}

TEST(GraphReader, DetectsFormatFromContentWhenExtensionIsAmbiguous) {
  EXPECT_EQ(detect_graph_format(temp_file("d1.txt", "# c\nVERTEX_SE2 0 0 0 0\n")), GraphFormat::kG2o);
  EXPECT_EQ(detect_graph_format(temp_file("d2.txt", "EDGE3 0 1 0 0 0 0 0 0\n")), GraphFormat::kToro);
  EXPECT_EQ(detect_graph_format(temp_file("d3.txt", "1 2 3\n")), std::nullopt);
}

TEST(GraphWriter, OutputIsWholeOrAbsent) {
  PoseGraph2D g;
  g.vertices.push_back({0, core::SE2()});
  EXPECT_THROW(write_graph("/nonexistent-dir/cairn/out.g2o", PoseGraph(g), GraphFormat::kG2o), ParseError);
  // TORO cannot hold FIX: the writer says so.
  g.fixed = {0};
  std::ostringstream out;
  const auto warnings = write_graph(out, PoseGraph(g), GraphFormat::kToro);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("FIX"), std::string::npos);
}

}  // namespace
}  // namespace cairn::io
