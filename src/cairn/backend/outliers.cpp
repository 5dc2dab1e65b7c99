#include "cairn/backend/outliers.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "cairn/core/assert.hpp"

namespace cairn::backend {
namespace {

// Uniform in [0, 1) from the top 53 bits of mt19937_64: identical on every platform, unlike
// std::uniform_real_distribution whose algorithm the standard leaves open.
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

template <class Group>
void add_false_loop_closures(io::PoseGraphT<Group>& graph, const OutlierOptions& options) {
  CAIRN_ASSERT(options.count >= 0 && options.translation_extent_m > 0.0, "invalid OutlierOptions");
  if (options.count == 0) return;
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
  CAIRN_ASSERT(ids.size() >= 3 && !graph.edges.empty(), "need at least 3 poses and one edge");
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

template void add_false_loop_closures(io::PoseGraph2D&, const OutlierOptions&);
template void add_false_loop_closures(io::PoseGraph3D&, const OutlierOptions&);

}  // namespace cairn::backend
