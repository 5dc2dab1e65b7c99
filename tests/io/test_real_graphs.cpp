// Every pose graph under <data>/posegraph/ parses, its record counts match the census in the
// folder's SOURCE.txt (computed by the data's curator with an independent script), and a g2o
// round trip is bit-exact.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include "cairn/io/graph_statistics.hpp"
#include "cairn/io/parse_error.hpp"
#include "graph_test_utils.hpp"
#include "test_data.hpp"

namespace cairn::io {
namespace {

// Census of one file as SOURCE.txt states it.
struct Census {
  std::map<std::string, std::size_t> records;  // VERTEX*/EDGE* and other line types
  std::size_t fix_lines = 0;
  std::size_t distinct_pose_ids = 0;
};

// Parses the "== name" sections of a SOURCE.txt: "vertex lines by type: VERTEX_SE2=808",
// "edge lines by type: EDGE_SE2=827", "other line types: EQUIV=40", "FIX lines: 0",
// "distinct pose ids referenced by edges: 808 (...)".
std::map<std::string, Census> read_census(const std::filesystem::path& source) {
  std::map<std::string, Census> census;
  std::ifstream in(source);
  std::string line;
  Census* current = nullptr;
  const std::regex pair_re(R"(([A-Z0-9_:]+)=(\d+))");
  while (std::getline(in, line)) {
    if (line.rfind("== ", 0) == 0) {
      current = &census[line.substr(3)];
      continue;
    }
    if (current == nullptr) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon);
    key.erase(0, key.find_first_not_of(' '));
    const std::string value = line.substr(colon + 1);
    if (key == "vertex lines by type" || key == "edge lines by type" || key == "other line types") {
      for (std::sregex_iterator it(value.begin(), value.end(), pair_re), end; it != end; ++it) {
        current->records[(*it)[1]] = std::stoul((*it)[2]);
      }
    } else if (key == "FIX lines") {
      current->fix_lines = std::stoul(value);
    } else if (key == "distinct pose ids referenced by edges") {
      current->distinct_pose_ids = std::stoul(value);
    }
  }
  return census;
}

class RealGraphs : public ::testing::TestWithParam<std::string> {};

TEST_P(RealGraphs, ParsesWithTheCountsOfSourceTxt) {
  const std::string folder = "posegraph/" + GetParam();
  CAIRN_REQUIRE_DATA(folder + "/SOURCE.txt");
  const auto census = read_census(test::data_path(folder + "/SOURCE.txt"));
  ASSERT_FALSE(census.empty());
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::data_path(folder))) {
    const std::string name = entry.path().filename().string();
    if (name == "SOURCE.txt") continue;
    SCOPED_TRACE(name);
    ASSERT_TRUE(census.contains(name)) << "no census for " << name;
    const Census& expected = census.at(name);
    const GraphFile file = read_graph(entry.path().string());
    std::map<std::string, std::size_t> seen;
    for (const auto& [tag, count] : file.report.records) {
      if (tag != "FIX") seen[tag] = count.count;
    }
    for (const auto& [tag, count] : file.report.unknown_records) seen[tag] = count.count;
    EXPECT_EQ(seen, expected.records);
    const std::size_t fix = file.report.records.contains("FIX") ? file.report.records.at("FIX").count : 0;
    EXPECT_EQ(fix, expected.fix_lines);
    const GraphStatistics stats = compute_statistics(file.graph);
    EXPECT_EQ(stats.poses, expected.distinct_pose_ids);
    ++files;
  }
  EXPECT_EQ(files, census.size());
}

INSTANTIATE_TEST_SUITE_P(PoseGraphFolders, RealGraphs, ::testing::Values("se-sync", "other", "toro"));

TEST(RealGraphs, G2oRoundTripIsBitExact) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync");
  std::size_t files = 0;
  for (const std::string folder : {"posegraph/se-sync", "posegraph/other", "posegraph/toro"}) {
    for (const auto& entry : std::filesystem::directory_iterator(test::data_path(folder))) {
      if (entry.path().filename() == "SOURCE.txt") continue;
      SCOPED_TRACE(entry.path().string());
      const GraphFile original = read_graph(entry.path().string());
      const GraphFile back = test::write_and_read(original.graph, GraphFormat::kG2o, "real_rt.g2o");
      EXPECT_TRUE(test::graphs_identical(original.graph, back.graph));
      ++files;
    }
  }
  EXPECT_GE(files, 20u);
}

TEST(RealGraphs, CubicleHasTheDocumentedIndefiniteMatrices) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/cubicle.g2o");
  const GraphFile file = read_graph(test::data_path("posegraph/se-sync/cubicle.g2o").string());
  // data/README.md: 5,021 of 16,869 EDGE_SE3:QUAT matrices not positive definite, first at line 5753.
  EXPECT_EQ(file.report.information_not_positive_definite, 5021u);
  EXPECT_EQ(file.report.first_not_positive_definite_line, 5753u);
  EXPECT_EQ(file.report.information_indefinite, 5021u);
  GraphReadOptions strict;
  strict.information_policy = InformationPolicy::kReject;
  try {
    read_graph(test::data_path("posegraph/se-sync/cubicle.g2o").string(), strict);
    FAIL() << "strict mode must refuse cubicle.g2o";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 5753u);
  }
}

TEST(RealGraphs, W20000InformationIsReadInG2oOrder) {
  CAIRN_REQUIRE_DATA("posegraph/toro/w20000.txt");
  const GraphFile file = read_graph(test::data_path("posegraph/toro/w20000.txt").string());
  EXPECT_EQ(file.report.format, GraphFormat::kToro);
  EXPECT_EQ(file.report.toro_information_order, "g2o");
  EXPECT_EQ(file.report.information_not_positive_definite, 0u);
  const auto stats = compute_statistics(file.graph);
  EXPECT_FALSE(stats.has_initial_guess);
  // The other TORO 2D files are positive definite only in TORO order.
  const GraphFile w100 = read_graph(test::data_path("posegraph/toro/w100.graph").string());
  EXPECT_EQ(w100.report.toro_information_order, "toro");
  EXPECT_EQ(w100.report.information_not_positive_definite, 0u);
}

TEST(RealGraphs, StatisticsOfKnownGraphs) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  const auto stats = compute_statistics(read_graph(test::data_path("posegraph/se-sync/intel.g2o").string()).graph);
  EXPECT_EQ(stats.dimension, 2);
  EXPECT_EQ(stats.poses, 1728u);
  EXPECT_EQ(stats.edges, 2512u);
  EXPECT_EQ(stats.odometry_edges + stats.loop_closure_edges, 2512u);
  EXPECT_EQ(stats.connected_components, 1u);
  EXPECT_TRUE(stats.contiguous_ids);
  EXPECT_TRUE(stats.has_initial_guess);
}

}  // namespace
}  // namespace cairn::io
