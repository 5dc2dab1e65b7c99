#pragma once
/// \file
/// Bundle adjustment of a BAL problem (io/bal.hpp) on the least-squares engine: one 9-parameter
/// camera variable per camera, one eliminated R^3 variable per point, one
/// BalReprojectionFactor per observation (reprojection_factors.hpp), optionally robust.

#include "cairn/backend/least_squares.hpp"
#include "cairn/io/bal.hpp"

namespace cairn::backend {

struct BundleAdjustmentOptions {
  LeastSquaresOptions solver;
  /// Robust kernel on each observation's reprojection error (pixels); none = least squares.
  RobustKernel kernel = RobustKernel::kNone;
  /// Kernel scale c in pixels; > 0.
  double kernel_scale_px = 1.0;
};

/// Refines problem.cameras and problem.points in place.
LeastSquaresSummary bundle_adjust(io::BalProblem& problem, const BundleAdjustmentOptions& options);

/// The engine's problem for `problem` (variables point into it: keep it alive and unmoved).
LeastSquaresProblem make_bundle_adjustment_problem(io::BalProblem& problem, const BundleAdjustmentOptions& options);

}  // namespace cairn::backend
