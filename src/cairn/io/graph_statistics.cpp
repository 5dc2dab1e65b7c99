#include "cairn/io/graph_statistics.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

namespace cairn::io {
namespace {

// Union-find with path halving and union by size.
class DisjointSets {
 public:
  std::size_t add() {
    parent_.push_back(parent_.size());
    size_.push_back(1);
    return parent_.size() - 1;
  }
  std::size_t find(std::size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }
  std::size_t size_of(std::size_t root) const { return size_[root]; }

 private:
  std::vector<std::size_t> parent_;
  std::vector<std::size_t> size_;
};

template <class Graph>
GraphStatistics compute(const Graph& graph, int dimension) {
  GraphStatistics s;
  s.dimension = dimension;
  s.vertices = graph.vertices.size();
  s.edges = graph.edges.size();
  s.fixed = graph.fixed.size();
  s.has_initial_guess = !graph.vertices.empty();

  std::unordered_map<std::int64_t, std::size_t> index;
  DisjointSets sets;
  auto node = [&](std::int64_t id) {
    const auto [it, inserted] = index.emplace(id, 0);
    if (inserted) it->second = sets.add();
    return it->second;
  };
  for (const auto& v : graph.vertices) node(v.id);
  for (const auto& e : graph.edges) {
    node(e.from);
    node(e.to);
  }
  std::vector<bool> touched(index.size(), false);
  std::set<std::pair<std::int64_t, std::int64_t>> pairs;
  for (const auto& e : graph.edges) {
    const std::size_t a = index.at(e.from);
    const std::size_t b = index.at(e.to);
    sets.unite(a, b);
    touched[a] = true;
    touched[b] = true;
    const std::int64_t gap = e.to > e.from ? e.to - e.from : e.from - e.to;
    if (gap == 1) {
      ++s.odometry_edges;
    } else {
      ++s.loop_closure_edges;
    }
    if (!pairs.emplace(std::min(e.from, e.to), std::max(e.from, e.to)).second) ++s.duplicate_edges;
  }
  s.poses = index.size();
  for (const auto& v : graph.vertices) {
    if (!touched[index.at(v.id)]) ++s.isolated_vertices;
  }
  std::unordered_map<std::size_t, std::size_t> components;
  for (const auto& [id, i] : index) ++components[sets.find(i)];
  s.connected_components = components.size();
  for (const auto& [root, count] : components) s.largest_component = std::max(s.largest_component, count);
  if (!index.empty()) {
    s.min_id = std::numeric_limits<std::int64_t>::max();
    s.max_id = std::numeric_limits<std::int64_t>::min();
    for (const auto& [id, i] : index) {
      s.min_id = std::min(s.min_id, id);
      s.max_id = std::max(s.max_id, id);
    }
    s.contiguous_ids = static_cast<std::size_t>(s.max_id - s.min_id) + 1 == index.size();
  }
  return s;
}

}  // namespace

GraphStatistics compute_statistics(const PoseGraph& graph) {
  if (const auto* g2 = std::get_if<PoseGraph2D>(&graph)) return compute(*g2, 2);
  return compute(std::get<PoseGraph3D>(graph), 3);
}

nlohmann::json graph_info_json(const std::string& path, const GraphStatistics& statistics, const GraphReadReport& report) {
  nlohmann::json j;
  j["file"] = path;
  j["kind"] = "pose_graph";
  j["format"] = to_string(report.format);
  j["dimension"] = statistics.dimension;
  j["poses"] = statistics.poses;
  j["vertices"] = statistics.vertices;
  j["edges"] = statistics.edges;
  j["odometry_edges"] = statistics.odometry_edges;
  j["loop_closure_edges"] = statistics.loop_closure_edges;
  j["duplicate_edges"] = statistics.duplicate_edges;
  j["connected_components"] = statistics.connected_components;
  j["largest_component"] = statistics.largest_component;
  j["isolated_vertices"] = statistics.isolated_vertices;
  j["fixed"] = statistics.fixed;
  j["min_id"] = statistics.min_id;
  j["max_id"] = statistics.max_id;
  j["contiguous_ids"] = statistics.contiguous_ids;
  j["has_initial_guess"] = statistics.has_initial_guess;
  nlohmann::json records = nlohmann::json::object();
  for (const auto& [tag, count] : report.records) records[tag] = count.count;
  j["records"] = records;
  nlohmann::json unknown = nlohmann::json::object();
  for (const auto& [tag, count] : report.unknown_records) {
    unknown[tag] = {{"count", count.count}, {"first_line", count.first_line}};
  }
  j["unknown_records"] = unknown;
  j["information_not_positive_definite"] = report.information_not_positive_definite;
  if (report.information_not_positive_definite > 0) {
    j["first_not_positive_definite_line"] = report.first_not_positive_definite_line;
  }
  j["information_indefinite"] = report.information_indefinite;
  j["information_singular"] = report.information_singular;
  if (report.information_indefinite > 0) j["first_indefinite_line"] = report.first_indefinite_line;
  if (report.information_singular > 0) j["first_singular_line"] = report.first_singular_line;
  j["information_policy"] = to_string(report.information_policy);
  j["edges_without_information"] = report.edges_without_information;
  if (!report.toro_information_order.empty()) j["toro_information_order"] = report.toro_information_order;
  j["warnings"] = report.warnings;
  return j;
}

}  // namespace cairn::io
