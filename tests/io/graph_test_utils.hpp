#pragma once
// Helpers shared by the graph io tests: temp files and bit-exact graph comparison.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "cairn/io/graph_io.hpp"

namespace cairn::test {

inline std::string temp_file(const std::string& name, const std::string& content) {
  const auto dir = std::filesystem::temp_directory_path() / ("cairn_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

inline bool same_pose(const core::SE2& a, const core::SE2& b) {
  return a.x() == b.x() && a.y() == b.y() && a.angle() == b.angle();
}
inline bool same_pose(const core::SE3& a, const core::SE3& b) {
  return a.translation() == b.translation() && a.unit_quaternion().coeffs() == b.unit_quaternion().coeffs();
}

/// Bit-exact equality of two graphs (ids, poses, measurements, information, fixed ids).
template <class Graph>
::testing::AssertionResult graphs_identical(const Graph& a, const Graph& b) {
  if (a.vertices.size() != b.vertices.size()) return ::testing::AssertionFailure() << "vertex counts differ";
  if (a.edges.size() != b.edges.size()) return ::testing::AssertionFailure() << "edge counts differ";
  if (a.fixed != b.fixed) return ::testing::AssertionFailure() << "fixed ids differ";
  for (std::size_t i = 0; i < a.vertices.size(); ++i) {
    if (a.vertices[i].id != b.vertices[i].id || !same_pose(a.vertices[i].T_world_pose, b.vertices[i].T_world_pose)) {
      return ::testing::AssertionFailure() << "vertex " << i << " differs";
    }
  }
  for (std::size_t i = 0; i < a.edges.size(); ++i) {
    const auto& x = a.edges[i];
    const auto& y = b.edges[i];
    if (x.from != y.from || x.to != y.to || !same_pose(x.T_from_to, y.T_from_to) || x.information != y.information) {
      return ::testing::AssertionFailure() << "edge " << i << " (" << x.from << "->" << x.to << ") differs";
    }
  }
  return ::testing::AssertionSuccess();
}

inline ::testing::AssertionResult graphs_identical(const io::PoseGraph& a, const io::PoseGraph& b) {
  if (a.index() != b.index()) return ::testing::AssertionFailure() << "dimensions differ";
  if (a.index() == 0) return graphs_identical(std::get<0>(a), std::get<0>(b));
  return graphs_identical(std::get<1>(a), std::get<1>(b));
}

/// Writes `graph` in `format` to a temp file and reads it back.
inline io::GraphFile write_and_read(const io::PoseGraph& graph, io::GraphFormat format, const std::string& name) {
  const std::string path = temp_file(name, "");
  io::write_graph(path, graph, format);
  io::GraphReadOptions options;
  options.format = format;
  return io::read_graph(path, options);
}

}  // namespace cairn::test
