#include "cairn/eval/relations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "cairn/core/se2.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/statistics.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::eval {
namespace {

constexpr const char* kLayout = "t_i t_j x y z roll pitch yaw";

// Wraps into (-pi, pi], as the evaluator's normalize_theta.
double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

MeanStd mean_std(const std::vector<double>& values) {
  const Statistics s = compute_statistics(values);
  return {s.mean, s.std, s.min, s.max};
}

// Yaw of a rotation: the planar heading the evaluator reads from a CARMEN pose.
double yaw_of(const Matrix4& pose) { return std::atan2(pose(1, 0), pose(0, 0)); }

}  // namespace

std::vector<Relation> read_relations(const std::string& path) {
  io::TextReader reader(path);
  std::vector<Relation> relations;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    const auto tokens = io::split_whitespace(reader.line());
    if (tokens.size() != 8) {
      reader.fail("a relation has 8 numbers '" + std::string(kLayout) + "', found " + std::to_string(tokens.size()) +
                  " fields");
    }
    Relation r;
    r.line = reader.line_number();
    const char* names[2] = {"t_i", "t_j"};
    core::Timestamp* stamps[2] = {&r.from, &r.to};
    for (int k = 0; k < 2; ++k) {
      const auto t = core::Timestamp::parse_seconds(tokens[static_cast<std::size_t>(k)]);
      if (!t) {
        reader.fail(std::string("expected a time in seconds for ") + names[k] + ", found " +
                    io::quote_token(tokens[static_cast<std::size_t>(k)]));
      }
      *stamps[k] = *t;
    }
    for (int k = 0; k < 3; ++k) {
      r.translation_m[k] = io::parse_double(reader, tokens[static_cast<std::size_t>(2 + k)], "x y z");
      r.roll_pitch_yaw_rad[k] = io::parse_double(reader, tokens[static_cast<std::size_t>(5 + k)], "roll pitch yaw");
    }
    relations.push_back(r);
  }
  if (relations.empty()) throw io::ParseError(path, 0, "no relations: expected lines '" + std::string(kLayout) + "'");
  return relations;
}

MatrixTrajectory relations_estimate_from_carmen(const io::CarmenLog& log, const std::string& path) {
  MatrixTrajectory estimate;
  for (const io::LaserScan& scan : log.scans) {
    Matrix4 T = Matrix4::Identity();
    const core::SE2& p = scan.T_odom_laser;
    T(0, 0) = std::cos(p.angle());
    T(0, 1) = -std::sin(p.angle());
    T(1, 0) = std::sin(p.angle());
    T(1, 1) = std::cos(p.angle());
    T(0, 3) = p.x();
    T(1, 3) = p.y();
    if (!estimate.stamps.empty() && scan.time <= estimate.stamps.back()) {
      throw io::ParseError(path, scan.line,
                           "laser record time " + scan.time.to_seconds_string() + " s does not follow the previous one (" +
                               estimate.stamps.back().to_seconds_string() + " s); the estimate needs increasing times");
    }
    estimate.stamps.push_back(scan.time);
    estimate.poses.push_back(T);
  }
  if (estimate.poses.empty()) throw io::ParseError(path, 0, "no laser records (FLASER, RLASER, ROBOTLASER1)");
  return estimate;
}

RelationsResult evaluate_relations(const std::vector<Relation>& relations, const MatrixTrajectory& estimate,
                                   const RelationsOptions& options) {
  RelationsResult result;
  if (!(options.max_time_difference_s >= 0.0) || !(options.max_time_difference_s <= 1e9)) {
    result.outcome = {Status::kInvalidOptions, "max time difference must be in [0, 1e9] s"};
    return result;
  }
  if (relations.empty()) {
    result.outcome = {Status::kEmpty, "no relations to evaluate"};
    return result;
  }
  if (Outcome o = validate_trajectory(estimate, "estimate"); !o.ok()) {
    result.outcome = o;
    return result;
  }
  if (!estimate.has_stamps()) {
    result.outcome = {Status::kMissingStamps,
                      "the relations metric pairs poses by time, but the estimate has no timestamps"};
    return result;
  }
  const auto& stamps = estimate.stamps;
  const std::int64_t max_diff_ns = std::llround(options.max_time_difference_s * 1e9);
  std::size_t missing = 0;
  std::string first_missing;
  // Nearest stamp (the earlier one on a tie: the evaluator keeps the first strictly nearer).
  auto nearest = [&](core::Timestamp t, std::size_t& index) {
    const auto it = std::lower_bound(stamps.begin(), stamps.end(), t);
    std::size_t best = static_cast<std::size_t>(it - stamps.begin());
    double best_diff = best < stamps.size() ? static_cast<double>(stamps[best].nanoseconds()) -
                                                  static_cast<double>(t.nanoseconds())
                                            : std::numeric_limits<double>::infinity();
    if (best > 0) {
      const double before =
          static_cast<double>(t.nanoseconds()) - static_cast<double>(stamps[best - 1].nanoseconds());
      if (before <= best_diff) {
        best_diff = before;
        best -= 1;
      }
    }
    index = best;
    return best_diff <= static_cast<double>(max_diff_ns);
  };
  for (const Relation& r : relations) {
    std::size_t i = 0;
    std::size_t j = 0;
    const bool found_i = nearest(r.from, i);
    const bool found_j = nearest(r.to, j);
    if (!found_i || !found_j) {
      if (missing++ == 0) {
        first_missing = "line " + std::to_string(r.line) + ", t = " +
                        (found_i ? r.to : r.from).to_seconds_string() + " s";
      }
      continue;
    }
    result.from_indices.push_back(i);
    result.to_indices.push_back(j);
    const Matrix4& pi = estimate.poses[i];
    const Matrix4& pj = estimate.poses[j];
    const core::SE2 xi(pi(0, 3), pi(1, 3), yaw_of(pi));
    const core::SE2 xj(pj(0, 3), pj(1, 3), yaw_of(pj));
    const core::SE2 delta = xi.inverse() * xj;
    const Vector3 dt = Vector3(delta.x(), delta.y(), 0.0) - r.translation_m;
    const double droll = wrap_angle(0.0 - r.roll_pitch_yaw_rad[0]);
    const double dpitch = wrap_angle(0.0 - r.roll_pitch_yaw_rad[1]);
    const double dyaw = wrap_angle(delta.angle() - r.roll_pitch_yaw_rad[2]);
    result.translation_errors_m.push_back(dt.norm());
    result.rotation_errors_rad.push_back(std::sqrt(droll * droll + dpitch * dpitch + dyaw * dyaw));
  }
  if (missing > 0) {
    result.outcome = {Status::kMissingPoses,
                      std::to_string(missing) + " of " + std::to_string(relations.size()) +
                          " relations have an end without an estimated pose within " +
                          std::to_string(options.max_time_difference_s) + " s (first: " + first_missing +
                          "); the estimate must hold a pose for every relation time"};
    result.translation_errors_m.clear();
    result.rotation_errors_rad.clear();
    return result;
  }
  const double to_deg = 180.0 / std::numbers::pi;
  std::vector<double> t_sq;
  std::vector<double> r_deg;
  std::vector<double> r_sq;
  for (std::size_t k = 0; k < result.translation_errors_m.size(); ++k) {
    const double t = result.translation_errors_m[k];
    const double a = result.rotation_errors_rad[k] * to_deg;
    t_sq.push_back(t * t);
    r_deg.push_back(a);
    r_sq.push_back(a * a);
  }
  result.translation_absolute_m = mean_std(result.translation_errors_m);
  result.translation_squared_m2 = mean_std(t_sq);
  result.rotation_absolute_deg = mean_std(r_deg);
  result.rotation_squared_deg2 = mean_std(r_sq);
  return result;
}

}  // namespace cairn::eval
