#include "cairn/sim/simulated_graph.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

using core::SE2;

Matrix3 information(double sigma_xy, double sigma_theta) {
  Matrix3 info = Matrix3::Zero();
  info(0, 0) = 1.0 / (sigma_xy * sigma_xy);
  info(1, 1) = 1.0 / (sigma_xy * sigma_xy);
  info(2, 2) = 1.0 / (sigma_theta * sigma_theta);
  return info;
}

SE2 perturb(const SE2& T, double sigma_xy, double sigma_theta, Random& random) {
  Vector3 xi;
  xi.x() = random.gaussian(sigma_xy);
  xi.y() = random.gaussian(sigma_xy);
  xi.z() = random.gaussian(sigma_theta);
  return T * SE2::exp(xi);
}

}  // namespace

bool GraphOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  auto positive = [&](double value, const char* name) {
    if (!(value > 0.0) || !std::isfinite(value)) problems << name << " must be > 0 (found " << value << "); ";
  };
  positive(node_spacing_m, "node_spacing_m");
  positive(node_spacing_rad, "node_spacing_rad");
  positive(odometry_sigma_xy_m, "odometry_sigma_xy_m");
  positive(odometry_sigma_theta_rad, "odometry_sigma_theta_rad");
  positive(loop_sigma_xy_m, "loop_sigma_xy_m");
  positive(loop_sigma_theta_rad, "loop_sigma_theta_rad");
  positive(loop_radius_m, "loop_radius_m");
  positive(loop_max_heading_difference_rad, "loop_max_heading_difference_rad");
  if (!(loop_min_separation_s >= 0.0)) problems << "loop_min_separation_s must be >= 0; ";
  if (loop_every_n_nodes < 1) problems << "loop_every_n_nodes must be >= 1; ";
  if (false_loops < 0) problems << "false_loops must be >= 0; ";
  if (!(false_loop_min_distance_m >= 0.0)) problems << "false_loop_min_distance_m must be >= 0; ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

SimulatedGraph build_graph(const std::vector<TrajectorySample>& truth, const std::vector<std::size_t>& candidates,
                           const GraphOptions& options, std::uint64_t seed) {
  CAIRN_ASSERT(options.is_valid(nullptr), "build_graph: invalid options (check is_valid first)");
  CAIRN_ASSERT(!candidates.empty(), "build_graph: no candidate samples");
  SimulatedGraph result;
  Random random(seed);

  std::vector<double> times;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const SE2& T = truth[candidates[k]].T_world_body;
    if (!result.truth.empty()) {
      const SE2 delta = result.truth.back().inverse() * T;
      if (delta.translation().norm() < options.node_spacing_m && std::abs(delta.angle()) < options.node_spacing_rad) {
        continue;
      }
    }
    result.truth.push_back(T);
    result.node_scans.push_back(k);
    times.push_back(truth[candidates[k]].stamp.seconds());
  }
  const std::size_t n = result.truth.size();
  const Matrix3 odometry_information = information(options.odometry_sigma_xy_m, options.odometry_sigma_theta_rad);
  const Matrix3 loop_information = information(options.loop_sigma_xy_m, options.loop_sigma_theta_rad);

  // Odometry chain and the initial guess composed from it.
  SE2 guess = result.truth.front();
  result.graph.vertices.push_back({0, guess});
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const SE2 T_i_j = result.truth[i].inverse() * result.truth[i + 1];
    const SE2 z = perturb(T_i_j, options.odometry_sigma_xy_m, options.odometry_sigma_theta_rad, random);
    io::GraphEdge<SE2> edge;
    edge.from = static_cast<std::int64_t>(i);
    edge.to = static_cast<std::int64_t>(i + 1);
    edge.T_from_to = z;
    edge.information = odometry_information;
    result.graph.edges.push_back(edge);
    guess = guess * z;
    result.graph.vertices.push_back({static_cast<std::int64_t>(i + 1), guess});
  }
  result.graph.fixed.push_back(0);

  // True loop closures.
  const auto step = static_cast<std::size_t>(options.loop_every_n_nodes);
  std::vector<std::size_t> searched;
  for (std::size_t j = 0; j < n; j += step) searched.push_back(j);
  if ((n - 1) % step != 0) searched.push_back(n - 1);  // the end of a run often closes its loop
  for (std::size_t j : searched) {
    std::size_t best = n;
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < j; ++i) {
      if (times[j] - times[i] < options.loop_min_separation_s) break;  // times increase with i
      const SE2 delta = result.truth[i].inverse() * result.truth[j];
      const double distance = delta.translation().norm();
      if (distance <= options.loop_radius_m && std::abs(delta.angle()) <= options.loop_max_heading_difference_rad &&
          distance < best_distance) {
        best = i;
        best_distance = distance;
      }
    }
    if (best == n) continue;
    io::GraphEdge<SE2> edge;
    edge.from = static_cast<std::int64_t>(best);
    edge.to = static_cast<std::int64_t>(j);
    edge.T_from_to = perturb(result.truth[best].inverse() * result.truth[j], options.loop_sigma_xy_m,
                             options.loop_sigma_theta_rad, random);
    edge.information = loop_information;
    result.graph.edges.push_back(edge);
    result.loops.push_back({edge.from, edge.to, false});
  }

  // False loop closures: bounded attempts so a small world cannot loop forever.
  Random outliers(Random::derive_seed(seed, 99));
  int made = 0;
  for (int attempt = 0; made < options.false_loops && attempt < 1000 * (options.false_loops + 1) && n >= 2; ++attempt) {
    std::size_t i = static_cast<std::size_t>(outliers.index(n));
    std::size_t j = static_cast<std::size_t>(outliers.index(n));
    if (i == j) continue;
    if (i > j) std::swap(i, j);
    if ((result.truth[i].translation() - result.truth[j].translation()).norm() < options.false_loop_min_distance_m) {
      continue;
    }
    io::GraphEdge<SE2> edge;
    edge.from = static_cast<std::int64_t>(i);
    edge.to = static_cast<std::int64_t>(j);
    edge.T_from_to = SE2(outliers.uniform(-1.0, 1.0), outliers.uniform(-1.0, 1.0),
                         outliers.uniform(-std::numbers::pi, std::numbers::pi));
    edge.information = loop_information;
    result.graph.edges.push_back(edge);
    result.loops.push_back({edge.from, edge.to, true});
    ++made;
  }
  return result;
}

}  // namespace cairn::sim
