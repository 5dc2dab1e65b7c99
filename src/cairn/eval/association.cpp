#include "cairn/eval/association.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace cairn::eval {
namespace {

Association fail(Status status, std::string message) {
  Association a;
  a.outcome = {status, std::move(message)};
  return a;
}

std::string seconds_text(double s) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.9g", s);
  return buffer;
}

}  // namespace

double evo_seconds(core::Timestamp stamp) {
  // Nine decimals hold the stamp exactly; strtod rounds that decimal correctly, as Python's
  // float() does with the file's shorter text of the same value.
  return std::strtod(stamp.to_seconds_string().c_str(), nullptr);
}

Association associate(const MatrixTrajectory& reference, const MatrixTrajectory& estimate,
                      const AssociationOptions& options) {
  if (!(options.max_time_difference_s >= 0.0) || !std::isfinite(options.max_time_difference_s) ||
      !std::isfinite(options.offset_s)) {
    return fail(Status::kInvalidOptions, "association needs a finite max time difference >= 0 s and a finite offset");
  }
  if (Outcome o = validate_trajectory(reference, "reference"); !o.ok()) return fail(o.status, o.message);
  if (Outcome o = validate_trajectory(estimate, "estimate"); !o.ok()) return fail(o.status, o.message);

  Association a;
  a.max_pairs = std::min(reference.size(), estimate.size());
  const bool both_stamped = reference.has_stamps() && estimate.has_stamps();
  if (options.by_index || !both_stamped) {
    if (reference.size() != estimate.size()) {
      const bool one_stamped = reference.has_stamps() != estimate.has_stamps();
      std::string why = options.by_index ? "pairing by index was asked for"
                        : one_stamped    ? std::string("only the ") +
                                            (reference.has_stamps() ? "reference" : "estimate") +
                                            " has timestamps, so poses pair by index"
                                         : "neither trajectory has timestamps, so poses pair by index";
      return fail(one_stamped && !options.by_index ? Status::kMissingStamps : Status::kSizeMismatch,
                  why + ", which needs equal lengths: the reference has " + std::to_string(reference.size()) +
                      " poses, the estimate " + std::to_string(estimate.size()) +
                      (both_stamped ? "" : " (give timestamps, e.g. a KITTI times file, to pair by time)"));
    }
    a.reference_indices.reserve(reference.size());
    for (std::size_t i = 0; i < reference.size(); ++i) a.reference_indices.push_back(i);
    a.estimate_indices = a.reference_indices;
    return a;
  }

  a.by_time = true;
  // evo associate_trajectories: traj_2 (the estimate) is the "long" one only when strictly
  // longer; the short one is walked; the long one's stamps get +offset_2 when it is the
  // estimate and -offset_2 when it is the reference.
  const bool estimate_longer = estimate.size() > reference.size();
  const auto& shorter = estimate_longer ? reference.stamps : estimate.stamps;
  const auto& longer = estimate_longer ? estimate.stamps : reference.stamps;
  const double shift = estimate_longer ? options.offset_s : -options.offset_s;
  std::vector<double> longer_s(longer.size());
  for (std::size_t k = 0; k < longer.size(); ++k) longer_s[k] = evo_seconds(longer[k]) + shift;
  for (std::size_t i = 0; i < shorter.size(); ++i) {
    const double t = evo_seconds(shorter[i]);
    // matching_time_indices: index_2 = argmin |stamps_2 - stamp_1| (first on ties); the
    // nearest is the first stamp >= t or the one before it.
    std::size_t best = static_cast<std::size_t>(std::lower_bound(longer_s.begin(), longer_s.end(), t) - longer_s.begin());
    double best_diff = best < longer_s.size() ? std::abs(longer_s[best] - t) : HUGE_VAL;
    if (best > 0 && std::abs(longer_s[best - 1] - t) <= best_diff) {
      best -= 1;
      best_diff = std::abs(longer_s[best] - t);
    }
    while (best > 0 && longer_s[best - 1] == longer_s[best]) --best;  // equal doubles: argmin takes the first
    if (best_diff <= options.max_time_difference_s) {
      a.reference_indices.push_back(estimate_longer ? i : best);
      a.estimate_indices.push_back(estimate_longer ? best : i);
    }
  }
  if (a.reference_indices.empty()) {
    return fail(Status::kNoOverlap,
                "no timestamps match between the reference (" + reference.stamps.front().to_seconds_string() + " .. " +
                    reference.stamps.back().to_seconds_string() + " s) and the estimate (" +
                    estimate.stamps.front().to_seconds_string() + " .. " + estimate.stamps.back().to_seconds_string() +
                    " s) with max time difference " + seconds_text(options.max_time_difference_s) + " s and offset " +
                    seconds_text(options.offset_s) + " s");
  }
  return a;
}

}  // namespace cairn::eval
