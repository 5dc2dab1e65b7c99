#pragma once
/// \file
/// The optimisation a keyframe pose-graph SLAM runs whenever loop closures arrive and once at the
/// end, written once for slam2d (SE(2)) and lidar3d (SE(3)): Levenberg-Marquardt over the graph,
/// or, at the end, graduated non-convexity over its loop closures (Yang et al., "Graduated
/// Non-Convexity for Robust Spatial Perception", RA-L 2020; backend/gnc.hpp), after which the loop
/// closures GNC rejected (weight <= 0.5) leave the graph for good. Odometry edges are never
/// rejected. The caller owns the graph (its edges, which of them are loops) and copies
/// problem.T_world_pose back into its keyframes when the solve was applied.

#include <cstddef>
#include <functional>
#include <vector>

#include "cairn/backend/problem.hpp"

namespace cairn::backend {

struct KeyframeGraphSolveOptions {
  /// Levenberg-Marquardt (and GNC's inner solves): iterations at most, relative cost decrease
  /// that ends it. One thread: the graphs are small and the front end runs beside it.
  int max_iterations = 30;
  double function_tolerance = 1e-9;
  /// Polled between iterations; a stopped GNC is not applied (its weights are no classification).
  std::function<bool()> should_stop;
};

struct KeyframeGraphSolve {
  /// False when GNC was cut short: the caller keeps its graph and poses as they were.
  bool applied = false;
  /// GNC only: per edge, whether it stays in the graph (false for the rejected loop closures).
  std::vector<bool> keep;
  /// GNC only: the rejected loop closures' edge indices, ascending.
  std::vector<std::size_t> rejected_loops;
};

/// Solves `problem` in place (LM, or GNC when `gnc`). `is_loop[e]` says whether edge e is a loop
/// closure (GNC may reject only those); used only with `gnc`.
template <class Group>
KeyframeGraphSolve solve_keyframe_graph(PoseGraphProblem<Group>& problem, bool gnc, const std::vector<bool>& is_loop,
                                        const KeyframeGraphSolveOptions& options);

}  // namespace cairn::backend
