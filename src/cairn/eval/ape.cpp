#include "cairn/eval/ape.hpp"

#include "cairn/core/assert.hpp"
#include "cairn/eval/paired_poses.hpp"

namespace cairn::eval {

std::vector<double> ape_errors(const std::vector<Matrix4>& reference, const std::vector<Matrix4>& estimate,
                               PoseRelation relation) {
  CAIRN_ASSERT(reference.size() == estimate.size(), "ape_errors needs paired poses");
  std::vector<double> errors(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    if (relation == PoseRelation::kTranslationPart) {
      // evo: E = positions_est - positions_ref, error = |E| (no rotation involved).
      errors[i] = (estimate[i].topRightCorner<3, 1>() - reference[i].topRightCorner<3, 1>()).norm();
    } else {
      // evo ape_base(x_t, x_t_star) = relative_se3(est, ref) = est^-1 * ref.
      errors[i] = pose_error(se3_inverse(estimate[i]) * reference[i], relation);
    }
  }
  return errors;
}

ApeResult evaluate_ape(const MatrixTrajectory& reference, const MatrixTrajectory& estimate, const ApeOptions& options) {
  ApeResult result;
  result.relation = options.relation;
  PairedPoses p = pair_and_align(reference, estimate, options.association, options.alignment);
  result.outcome = p.outcome;
  result.association = std::move(p.association);
  result.alignment = p.alignment;
  if (!result.outcome.ok()) return result;
  result.reference = std::move(p.reference);
  result.estimate = std::move(p.estimate);
  result.time_s = std::move(p.time_s);
  result.errors = ape_errors(result.reference, result.estimate, options.relation);
  result.statistics = compute_statistics(result.errors);
  return result;
}

}  // namespace cairn::eval
