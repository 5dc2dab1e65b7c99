#include "cairn/eval/kitti_metric.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/LU>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"

namespace cairn::eval {
namespace {

// The devkit stores these in float; every conversion below mirrors one in
// evaluate_odometry.cpp so that the per-segment values are the devkit's to the bit (up to the
// ~1e-16 differences between its general 4x4 inverse and our rigid-motion inverse).

// rotationError: d = 0.5 * (a + b + c - 1.0) with float a, b, c; the sum a + b + c is float,
// "- 1.0" and "0.5 *" are double, d is stored as float; acos of the clamped float.
float devkit_rotation_error(const Matrix3& R) {
  const auto a = static_cast<float>(R(0, 0));
  const auto b = static_cast<float>(R(1, 1));
  const auto c = static_cast<float>(R(2, 2));
  const auto d = static_cast<float>(0.5 * (static_cast<double>(a + b + c) - 1.0));
  return std::acos(std::max(std::min(d, 1.0f), -1.0f));
}

// translationError: float dx, dy, dz; sqrt in float.
float devkit_translation_error(const Vector3& t) {
  const auto dx = static_cast<float>(t.x());
  const auto dy = static_cast<float>(t.y());
  const auto dz = static_cast<float>(t.z());
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

bool KittiOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (lengths_m.empty()) problems.add("at least one segment length is needed");
  for (double l : lengths_m) {
    if (!(l > 0.0) || !std::isfinite(l)) {
      problems.add("segment lengths must be finite and > 0, found " + std::to_string(l));
      break;
    }
  }
  if (step_frames == 0) problems.add("step between start frames must be >= 1");
  if (!(frame_period_s > 0.0) || !std::isfinite(frame_period_s)) problems.add("frame period must be finite and > 0");
  return problems.report(why);
}

double KittiResult::rotation_error_deg_per_m() const { return rotation_error_rad_per_m * 180.0 / std::numbers::pi; }

std::vector<KittiSegment> kitti_segments(const std::vector<Matrix4>& ground_truth,
                                         const std::vector<Matrix4>& result, const KittiOptions& options,
                                         std::vector<double>* path_length_m) {
  CAIRN_ASSERT(ground_truth.size() == result.size(), "kitti_segments needs paired poses");
  const std::size_t n = ground_truth.size();
  // trajectoryDistances: float differences, float sum.
  std::vector<float> dist(n, 0.0f);
  for (std::size_t i = 1; i < n; ++i) {
    const Vector3 p1 = ground_truth[i - 1].topRightCorner<3, 1>();
    const Vector3 p2 = ground_truth[i].topRightCorner<3, 1>();
    const auto dx = static_cast<float>(p1.x() - p2.x());
    const auto dy = static_cast<float>(p1.y() - p2.y());
    const auto dz = static_cast<float>(p1.z() - p2.z());
    dist[i] = dist[i - 1] + std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  if (path_length_m != nullptr) path_length_m->assign(dist.begin(), dist.end());

  std::vector<KittiSegment> segments;
  for (std::size_t first = 0; first < n; first += options.step_frames) {
    for (double length : options.lengths_m) {
      const auto len = static_cast<float>(length);
      // lastFrameFromSegmentLength: first i >= first with dist[i] > dist[first] + len.
      std::size_t last = n;
      for (std::size_t i = first; i < n; ++i) {
        if (dist[i] > dist[first] + len) {
          last = i;
          break;
        }
      }
      if (last == n) continue;
      // General 4x4 inverses, as the devkit's Matrix::inv.
      const Matrix4 delta_gt = ground_truth[first].inverse() * ground_truth[last];
      const Matrix4 delta_result = result[first].inverse() * result[last];
      const Matrix4 error = delta_result.inverse() * delta_gt;
      const float r_err = devkit_rotation_error(error.topLeftCorner<3, 3>());
      const float t_err = devkit_translation_error(error.topRightCorner<3, 1>());
      // speed = len / (0.1 * num_frames): double arithmetic, stored as float.
      const auto num_frames = static_cast<float>(last - first + 1);
      const auto speed =
          static_cast<float>(static_cast<double>(len) / (options.frame_period_s * static_cast<double>(num_frames)));
      KittiSegment s;
      s.first_frame = first;
      s.last_frame = last;
      s.length_m = static_cast<double>(len);
      s.rotation_error_rad_per_m = static_cast<double>(r_err / len);
      s.translation_error_m_per_m = static_cast<double>(t_err / len);
      s.speed_m_per_s = static_cast<double>(speed);
      segments.push_back(s);
    }
  }
  return segments;
}

KittiResult evaluate_kitti(const MatrixTrajectory& ground_truth, const MatrixTrajectory& result,
                           const KittiOptions& options) {
  KittiResult r;
  if (std::string problems; !options.is_valid(&problems)) {
    r.outcome = {Status::kInvalidOptions, problems};
    return r;
  }
  r.association = associate(ground_truth, result, options.association);
  if (!r.association.outcome.ok()) {
    r.outcome = r.association.outcome;
    return r;
  }
  for (std::size_t k = 0; k < r.association.size(); ++k) {
    r.reference.push_back(ground_truth.poses[r.association.reference_indices[k]]);
    r.estimate.push_back(result.poses[r.association.estimate_indices[k]]);
  }
  r.segments = kitti_segments(r.reference, r.estimate, options, &r.path_length_m);
  if (r.segments.empty()) {
    const double shortest = *std::min_element(options.lengths_m.begin(), options.lengths_m.end());
    r.outcome = {Status::kNoPairs, "the ground truth path is " + std::to_string(r.path_length_m.back()) +
                                       " m long, shorter than the shortest segment (" + std::to_string(shortest) +
                                       " m): no KITTI segment to evaluate"};
    return r;
  }
  // saveStats: float sums, float count.
  float t_sum = 0.0f;
  float r_sum = 0.0f;
  for (const KittiSegment& s : r.segments) {
    t_sum += static_cast<float>(s.translation_error_m_per_m);
    r_sum += static_cast<float>(s.rotation_error_rad_per_m);
  }
  const auto num = static_cast<float>(r.segments.size());
  r.translation_error_m_per_m = static_cast<double>(t_sum / num);
  r.rotation_error_rad_per_m = static_cast<double>(r_sum / num);
  // saveErrorPlots: per length, segments with |len - L| < 1.0, float sums.
  for (double length : options.lengths_m) {
    const auto len = static_cast<float>(length);
    float t = 0.0f;
    float rot = 0.0f;
    float count = 0.0f;
    for (const KittiSegment& s : r.segments) {
      if (std::fabs(static_cast<float>(s.length_m) - len) < 1.0f) {
        t += static_cast<float>(s.translation_error_m_per_m);
        rot += static_cast<float>(s.rotation_error_rad_per_m);
        count += 1.0f;
      }
    }
    KittiLengthError e;
    e.length_m = static_cast<double>(len);
    e.segments = static_cast<std::size_t>(count);
    if (count > 0.0f) {
      e.translation_error_m_per_m = static_cast<double>(t / count);
      e.rotation_error_rad_per_m = static_cast<double>(rot / count);
    }
    e.reported_by_devkit = count > 2.5f;
    r.per_length.push_back(e);
  }
  return r;
}

}  // namespace cairn::eval
