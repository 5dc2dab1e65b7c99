#pragma once
/// \file
/// A relative-pose edge of a 3D pose graph as a factor of the general engine (`RelativePoseFactor`):
/// GeodesicFactor<SE3>'s residual r = S log(Z^-1 T_i^-1 T_j) and its analytic Jacobians
/// (factors.hpp), on two se3_manifold() variables. For graphs that mix pose edges with other
/// factors (GNSS positions, priors), which the pose-graph solver (optimizer.hpp) does not take.

#include "cairn/backend/least_squares.hpp"
#include "cairn/backend/problem.hpp"

namespace cairn::backend {

class RelativePoseFactor final : public Factor {
 public:
  /// `edge.T_i_j` and `edge.sqrt_information` are used (its pose indices are not: the variables
  /// are given to add_factor as (T_world_i, T_world_j)).
  explicit RelativePoseFactor(const PoseEdge<core::SE3>& edge) : edge_(edge) {}
  int residual_size() const override { return 6; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  PoseEdge<core::SE3> edge_;
};

}  // namespace cairn::backend
