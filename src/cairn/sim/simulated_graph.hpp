#pragma once
/// \file
/// A pose graph made from the ground truth, with statistically consistent measurements: every
/// edge's measurement is the true relative pose perturbed by exactly the Gaussian noise its
/// information matrix states, so a back end can be checked against known truth and a chi^2
/// test is meaningful.
///
/// Nodes: the first scan, then every scan where the robot moved node_spacing_m or turned
/// node_spacing_rad since the last node (ground truth).
/// Odometry edges i -> i+1:  z = T_i_j * exp(n),  n ~ N(0, diag(s_xy^2, s_xy^2, s_theta^2)),
///   information = diag(1/s_xy^2, 1/s_xy^2, 1/s_theta^2) (g2o order x, y, theta), with
///   T_i_j = T_world_i^-1 T_world_j and exp the SE(2) exponential (right perturbation, the
///   g2o / cairn residual convention log(z^-1 T_i^-1 T_j)).
/// Loop closures: for every loop_every_n_nodes-th node j and the last node, the earlier node i
///   nearest to it with t_j - t_i >= loop_min_separation_s, |p_i - p_j| <= loop_radius_m and
///   |theta_i - theta_j| <= loop_max_heading_difference_rad; same noise model with the loop sigmas.
/// False loop closures (false_loops > 0): pairs (i, j) drawn uniformly among node pairs at
///   least false_loop_min_distance_m apart, with a measurement drawn as a plausible loop
///   (x, y ~ U(-1, 1) m, theta ~ U(-pi, pi)) and the loop information: outliers a robust back
///   end must reject.
/// Vertex initial guess: the odometry edges composed from the first node's true pose.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/io/pose_graph.hpp"
#include "cairn/sim/trajectory.hpp"

namespace cairn::sim {

struct GraphOptions {
  /// Node spacing, metres and radians (> 0).
  double node_spacing_m = 0.5;
  double node_spacing_rad = 0.5;
  /// Odometry edge noise, metres and radians (> 0).
  double odometry_sigma_xy_m = 0.02;
  double odometry_sigma_theta_rad = 0.005;
  /// Loop closure noise, metres and radians (> 0).
  double loop_sigma_xy_m = 0.05;
  double loop_sigma_theta_rad = 0.01;
  /// Loop closure selection (see the file comment).
  double loop_radius_m = 2.0;
  double loop_max_heading_difference_rad = 1.0;
  double loop_min_separation_s = 20.0;
  int loop_every_n_nodes = 5;
  /// Number of false loop closures and their smallest true distance, metres.
  int false_loops = 0;
  double false_loop_min_distance_m = 5.0;

  bool is_valid(std::string* why) const;
};

struct LoopClosureRecord {
  std::int64_t from = 0;
  std::int64_t to = 0;
  bool is_false = false;
};

struct SimulatedGraph {
  io::PoseGraph2D graph;
  /// For vertex id k: the index into the candidate list handed to build_graph (a scan index).
  std::vector<std::size_t> node_scans;
  /// Ground truth T_world_node per vertex.
  std::vector<core::SE2> truth;
  /// Every loop closure edge, true or false, in file order.
  std::vector<LoopClosureRecord> loops;
};

/// Builds the graph over the samples truth[candidates[k]] (the scan samples).
/// Precondition: options.is_valid(), candidates not empty and increasing.
SimulatedGraph build_graph(const std::vector<TrajectorySample>& truth, const std::vector<std::size_t>& candidates,
                           const GraphOptions& options, std::uint64_t seed);

}  // namespace cairn::sim
