#include "cairn/backend/bundle_adjustment.hpp"

#include "cairn/backend/reprojection_factors.hpp"

namespace cairn::backend {

LeastSquaresProblem make_bundle_adjustment_problem(io::BalProblem& problem, const BundleAdjustmentOptions& options) {
  LeastSquaresProblem ls;
  const Manifold& camera_manifold = euclidean_manifold(kBalCameraSize);
  const Manifold& point_manifold = euclidean_manifold(3);
  for (int c = 0; c < problem.num_cameras; ++c) ls.add_variable(problem.camera(c), camera_manifold);
  const int first_point = problem.num_cameras;
  for (int p = 0; p < problem.num_points; ++p) {
    ls.add_variable(problem.point(p), point_manifold, VariableGroup::kEliminate);
  }
  const FactorLoss loss{options.kernel, options.kernel_scale_px};
  for (const io::BalObservation& o : problem.observations) {
    ls.add_factor(std::make_unique<BalReprojectionFactor>(o.x, o.y), {o.camera, first_point + o.point}, loss);
  }
  return ls;
}

LeastSquaresSummary bundle_adjust(io::BalProblem& problem, const BundleAdjustmentOptions& options) {
  LeastSquaresProblem ls = make_bundle_adjustment_problem(problem, options);
  return solve(ls, options.solver);
}

}  // namespace cairn::backend
