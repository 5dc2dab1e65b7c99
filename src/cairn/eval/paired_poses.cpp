#include "cairn/eval/paired_poses.hpp"

namespace cairn::eval {

PairedPoses pair_and_align(const MatrixTrajectory& reference, const MatrixTrajectory& estimate,
                           const AssociationOptions& association, const AlignmentOptions& alignment) {
  PairedPoses p;
  p.association = associate(reference, estimate, association);
  if (!p.association.outcome.ok()) {
    p.outcome = p.association.outcome;
    return p;
  }
  const std::size_t n = p.association.size();
  p.reference.reserve(n);
  p.estimate.reserve(n);
  p.time_s.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t r = p.association.reference_indices[k];
    p.reference.push_back(reference.poses[r]);
    p.estimate.push_back(estimate.poses[p.association.estimate_indices[k]]);
    if (reference.has_stamps()) {
      const std::size_t r0 = p.association.reference_indices.front();
      p.time_s.push_back(static_cast<double>(reference.stamps[r].nanoseconds() - reference.stamps[r0].nanoseconds()) * 1e-9);
    } else {
      p.time_s.push_back(static_cast<double>(k));
    }
  }
  p.alignment = align(p.reference, p.estimate, alignment);
  if (!p.alignment.outcome.ok()) {
    p.outcome = p.alignment.outcome;
    return p;
  }
  if (alignment.method != AlignmentMethod::kNone) p.estimate = apply_alignment(p.alignment, p.estimate);
  return p;
}

}  // namespace cairn::eval
