#include "cairn/eval/rpe.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/eval/paired_poses.hpp"

namespace cairn::eval {

std::string_view to_string(DeltaUnit unit) { return unit == DeltaUnit::kFrames ? "f" : "m"; }

std::optional<DeltaUnit> delta_unit_from_name(std::string_view name) {
  if (name == "f" || name == "frames") return DeltaUnit::kFrames;
  if (name == "m" || name == "meters" || name == "metres") return DeltaUnit::kMeters;
  return std::nullopt;
}

bool RpeOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(delta > 0.0) || !std::isfinite(delta)) problems.add("delta must be a finite number > 0");
  if (delta_unit == DeltaUnit::kFrames && std::isfinite(delta) &&
      (delta != std::floor(delta) || delta > 1e15)) {
    problems.add("delta in frames must be a whole number");
  }
  if (!(relative_delta_tolerance >= 0.0) || !std::isfinite(relative_delta_tolerance)) {
    problems.add("relative delta tolerance must be a finite number >= 0");
  }
  return problems.report(why);
}

std::vector<IndexPair> rpe_pairs(const std::vector<Matrix4>& poses, const RpeOptions& options) {
  std::vector<IndexPair> pairs;
  const std::size_t n = poses.size();
  if (options.delta_unit == DeltaUnit::kFrames) {
    // evo filters.py, filter_pairs_by_index.
    const auto d = static_cast<std::size_t>(options.delta);
    if (options.all_pairs) {
      for (std::size_t i = 0; i + d < n; ++i) pairs.emplace_back(i, i + d);
    } else {
      for (std::size_t i = 0; i + d < n; i += d) pairs.emplace_back(i, i + d);
    }
    return pairs;
  }
  if (options.all_pairs) {
    // evo filters.py, filter_pairs_by_path (all_pairs): geometry.accumulated_distances, then
    // per start i the argmin over j > i of |(D_j - D_i) - delta|, kept within tol.
    const double tol = options.delta * options.relative_delta_tolerance;
    std::vector<double> distance(n, 0.0);
    for (std::size_t k = 1; k < n; ++k) {
      distance[k] = distance[k - 1] + (poses[k].topRightCorner<3, 1>() - poses[k - 1].topRightCorner<3, 1>()).norm();
    }
    for (std::size_t i = 0; i + 1 < n; ++i) {
      std::size_t best = i + 1;
      double best_gap = std::numeric_limits<double>::infinity();
      for (std::size_t j = i + 1; j < n; ++j) {
        const double gap = std::abs((distance[j] - distance[i]) - options.delta);
        if (gap < best_gap) {
          best_gap = gap;
          best = j;
        }
      }
      if (best_gap <= tol) pairs.emplace_back(i, best);
    }
    return pairs;
  }
  // evo filters.py, filter_pairs_by_path (consecutive).
  std::vector<std::size_t> ids;
  double path = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0) path += (poses[k].topRightCorner<3, 1>() - poses[k - 1].topRightCorner<3, 1>()).norm();
    if (path >= options.delta) {
      ids.push_back(k);
      path = 0.0;
    }
  }
  for (std::size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  return pairs;
}

RpeResult evaluate_rpe(const MatrixTrajectory& reference, const MatrixTrajectory& estimate, const RpeOptions& options) {
  RpeResult result;
  result.relation = options.relation;
  if (std::string problems; !options.is_valid(&problems)) {
    result.outcome = {Status::kInvalidOptions, problems};
    return result;
  }
  PairedPoses p = pair_and_align(reference, estimate, options.association, options.alignment);
  result.outcome = p.outcome;
  result.association = std::move(p.association);
  result.alignment = p.alignment;
  if (!result.outcome.ok()) return result;
  result.reference = std::move(p.reference);
  result.estimate = std::move(p.estimate);
  result.time_s = std::move(p.time_s);
  result.pairs = rpe_pairs(options.pairs_from_reference ? result.reference : result.estimate, options);
  if (result.pairs.empty()) {
    result.outcome = {Status::kNoPairs, "delta = " + std::to_string(options.delta) + " (" +
                                            std::string(to_string(options.delta_unit)) + ") selects no pose pair among " +
                                            std::to_string(result.reference.size()) +
                                            " paired poses: use a smaller delta or a looser tolerance"};
    return result;
  }
  result.errors.reserve(result.pairs.size());
  for (const auto& [i, j] : result.pairs) {
    // evo rpe_base: Q_rel = Q_i^-1 Q_j, P_rel = P_i^-1 P_j, E = Q_rel^-1 P_rel.
    const Matrix4 Q_rel = se3_inverse(result.reference[i]) * result.reference[j];
    const Matrix4 P_rel = se3_inverse(result.estimate[i]) * result.estimate[j];
    result.errors.push_back(pose_error(se3_inverse(Q_rel) * P_rel, options.relation));
  }
  result.statistics = compute_statistics(result.errors);
  return result;
}

}  // namespace cairn::eval
