#include "cairn/backend/outliers.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>


namespace cairn::backend {
namespace {

// Uniform in [0, 1) from the top 53 bits of mt19937_64: identical on every platform, unlike
// std::uniform_real_distribution whose algorithm the standard leaves open.
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// The distinct pose ids of the graph, sorted: its vertices, or the ids its edges name.
template <class Group>
std::vector<std::int64_t> pose_ids(const io::PoseGraphT<Group>& graph) {
  std::vector<std::int64_t> ids;
  if (!graph.vertices.empty()) {
    for (const auto& v : graph.vertices) ids.push_back(v.id);
  } else {
    for (const auto& e : graph.edges) {
      ids.push_back(e.from);
      ids.push_back(e.to);
    }
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

}  // namespace

template <class Group>
std::string outlier_request_problems(const io::PoseGraphT<Group>& graph, const OutlierOptions& options) {
  std::string problems;
  auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "\n") + p; };
  if (options.count < 0) add("the number of false loop closures must be >= 0, got " + std::to_string(options.count));
  if (!std::isfinite(options.translation_extent_m) || options.translation_extent_m <= 0.0) {
    add("the translation extent must be a finite number > 0");
  }
  if (options.count <= 0) return problems;
  const std::vector<std::int64_t> ids = pose_ids(graph);
  if (ids.size() < 3) add("false loop closures need at least 3 poses, and the graph has " + std::to_string(ids.size()));
  if (graph.edges.empty()) add("false loop closures copy the information matrix of an existing edge, and the graph has none");
  if (ids.size() >= 3) {
    // Ordered pairs (from, to) of distinct poses whose ids are not consecutive.
    std::size_t consecutive = 0;
    for (std::size_t k = 1; k < ids.size(); ++k) consecutive += ids[k] - ids[k - 1] == 1;
    const double pairs = static_cast<double>(ids.size()) * static_cast<double>(ids.size() - 1) - 2.0 * static_cast<double>(consecutive);
    if (static_cast<double>(options.count) > pairs) {
      add("asked for " + std::to_string(options.count) + " false loop closures, but the graph has only " +
          std::to_string(static_cast<long long>(pairs)) + " distinct ordered pairs of non-consecutive poses");
    }
  }
  return problems;
}

template <class Group>
void add_false_loop_closures(io::PoseGraphT<Group>& graph, const OutlierOptions& options) {
  if (const std::string problems = outlier_request_problems(graph, options); !problems.empty()) {
    throw std::invalid_argument(problems);
  }
  if (options.count == 0) return;
  const std::vector<std::int64_t> ids = pose_ids(graph);
  std::mt19937_64 rng(options.seed);
  auto pick = [&](std::size_t n) { return std::min(n - 1, static_cast<std::size_t>(uniform01(rng) * static_cast<double>(n))); };
  const std::size_t original_edges = graph.edges.size();
  const double extent = options.translation_extent_m;
  for (int k = 0; k < options.count; ++k) {
    io::GraphEdge<Group> edge;
    do {
      edge.from = ids[pick(ids.size())];
      edge.to = ids[pick(ids.size())];
    } while (edge.from == edge.to || edge.from - edge.to == 1 || edge.to - edge.from == 1);
    if constexpr (Group::kDoF == 3) {
      edge.T_from_to = Group(extent * (2.0 * uniform01(rng) - 1.0), extent * (2.0 * uniform01(rng) - 1.0),
                             std::numbers::pi * (2.0 * uniform01(rng) - 1.0));
    } else {
      // Shoemake, "Uniform random rotations", Graphics Gems III, 1992.
      const double u1 = uniform01(rng);
      const double u2 = 2.0 * std::numbers::pi * uniform01(rng);
      const double u3 = 2.0 * std::numbers::pi * uniform01(rng);
      const double a = std::sqrt(1.0 - u1);
      const double b = std::sqrt(u1);
      const Eigen::Quaterniond q(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3));
      const Eigen::Vector3d t(extent * (2.0 * uniform01(rng) - 1.0), extent * (2.0 * uniform01(rng) - 1.0),
                              extent * (2.0 * uniform01(rng) - 1.0));
      edge.T_from_to = Group(q, t);
    }
    edge.information = graph.edges[pick(original_edges)].information;
    graph.edges.push_back(edge);
  }
}

template std::string outlier_request_problems(const io::PoseGraph2D&, const OutlierOptions&);
template std::string outlier_request_problems(const io::PoseGraph3D&, const OutlierOptions&);
template void add_false_loop_closures(io::PoseGraph2D&, const OutlierOptions&);
template void add_false_loop_closures(io::PoseGraph3D&, const OutlierOptions&);

}  // namespace cairn::backend
