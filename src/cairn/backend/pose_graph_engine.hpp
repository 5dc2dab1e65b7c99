#pragma once
/// \file
/// A pose graph (problem.hpp) solved on the general least-squares engine (least_squares.hpp)
/// instead of the pose-graph optimiser (optimizer.hpp): poses on se2_manifold() / se3_manifold(),
/// fixed poses constant, one engine factor per edge wrapping GeodesicFactor or ChordalFactor
/// (factors.hpp). The optimiser remains the pose-graph solver; this is the measured step towards
/// one Levenberg-Marquardt in the tree (issue 21): bench/pose_graph_engine.cpp puts the two side
/// by side on the SE-Sync graphs. Robust kernels, GNC's weights, the exact chordal Hessian and
/// factorisation reuse of the optimiser are not carried over here.

#include "cairn/backend/factors.hpp"
#include "cairn/backend/least_squares.hpp"
#include "cairn/backend/problem.hpp"

namespace cairn::backend {

/// Optimises problem.T_world_pose in place on the engine (kSparseNormalCholesky). The summary's
/// costs are the engine's 1/2 sum ||r||^2 (twice them is the optimiser's cost).
template <class Group>
LeastSquaresSummary optimize_on_engine(PoseGraphProblem<Group>& problem, Objective objective,
                                       const LeastSquaresOptions& options);

}  // namespace cairn::backend
