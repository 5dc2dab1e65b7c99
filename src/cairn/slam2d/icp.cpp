#include "cairn/slam2d/icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::slam2d {
namespace {
double huber_weight(double r, double k) { return std::abs(r) <= k ? 1.0 : k / std::abs(r); }

/// The pose being estimated, (x, y, theta) of T_map_sensor.
struct IcpPose {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

/// One Gauss-Newton iteration's normal equations H step = -g, with the spread of the matched
/// normals (sum n n^T over `normal_count` point-to-line correspondences) for the degeneracy test.
struct NormalEquations {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  Eigen::Matrix2d normal_outer = Eigen::Matrix2d::Zero();
  int normal_count = 0;
};

/// The scan term of the normal equations at `pose`: every point matched to its nearest map point
/// within `radius`, point-to-line where the map point has a normal (icp.hpp's residual and
/// Jacobian), point-to-point (weighted) otherwise, each with its Huber weight.
NormalEquations accumulate_scan_term(const PointMap& map, const std::vector<Eigen::Vector2d>& points_sensor,
                                     const IcpPose& pose, double radius, double inv_sigma2, const IcpOptions& options) {
  NormalEquations equations;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  for (const auto& p : points_sensor) {
    const Eigen::Vector2d Rp(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    const Eigen::Vector2d world(Rp.x() + pose.x, Rp.y() + pose.y);
    const MapPoint* q = map.nearest(world, radius);
    if (q == nullptr) continue;
    const Eigen::Vector2d e = world - q->position;
    const Eigen::Vector2d dtheta(-Rp.y(), Rp.x());
    if (q->has_normal) {
      const double r = q->normal.dot(e);
      const Eigen::Vector3d J(q->normal.x(), q->normal.y(), q->normal.dot(dtheta));
      const double w = huber_weight(r, options.huber_threshold_m) * inv_sigma2;
      equations.H += w * J * J.transpose();
      equations.g += w * J * r;
      equations.normal_outer += q->normal * q->normal.transpose();
      ++equations.normal_count;
    } else if (options.point_to_point_weight > 0.0) {
      const double w = options.point_to_point_weight * huber_weight(e.norm(), options.huber_threshold_m) * inv_sigma2;
      Eigen::Matrix<double, 2, 3> J;
      J << 1.0, 0.0, dtheta.x(), 0.0, 1.0, dtheta.y();
      equations.H += w * J.transpose() * J;
      equations.g += w * J.transpose() * e;
    }
  }
  return equations;
}

/// The translation direction the matched normals leave unconstrained, if any (requires
/// normal_count > 0).
std::optional<Eigen::Vector2d> unconstrained_direction(const NormalEquations& equations, const IcpOptions& options) {
  // Degeneracy-aware update (Zhang, Kaess & Singh, "On degeneracy of optimization-based
  // state estimation problems", ICRA 2016, solution remapping): along a translation direction
  // the normals do not constrain (a corridor's axis), noisy normals still carry a little
  // information that pins the pose to where the map was sampled; there the prior decides.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> spread(equations.normal_outer / equations.normal_count);
  if (spread.eigenvalues()(0) < options.degenerate_threshold) return spread.eigenvectors().col(0);
  return std::nullopt;
}

/// Adds the prior term pulling `pose` towards `prior` (translation and rotation sigmas).
void add_prior_term(NormalEquations& equations, const IcpPose& pose, const core::SE2& prior, const IcpOptions& options) {
  const double wt = 1.0 / (options.prior_translation_sigma_m * options.prior_translation_sigma_m);
  const double wr = 1.0 / (options.prior_rotation_sigma_rad * options.prior_rotation_sigma_rad);
  equations.H(0, 0) += wt;
  equations.H(1, 1) += wt;
  equations.H(2, 2) += wr;
  equations.g(0) += wt * (pose.x - prior.x());
  equations.g(1) += wt * (pose.y - prior.y());
  equations.g(2) += wr * core::wrap_angle(pose.theta - prior.angle());
}

/// Solves the normal equations and applies the step to `pose`, the translation along a
/// degenerate direction taken from the prior (`remapped` set). The step taken, or nothing when H
/// cannot be solved (the iterations stop).
std::optional<Eigen::Vector3d> gauss_newton_step(const NormalEquations& equations,
                                                 const std::optional<Eigen::Vector2d>& degenerate_direction,
                                                 const core::SE2* prior, IcpPose& pose, bool& remapped) {
  if (equations.H.trace() <= 0.0) return std::nullopt;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(equations.H);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  Eigen::Vector3d step = -ldlt.solve(equations.g);
  if (!step.allFinite()) return std::nullopt;
  pose.x += step(0);
  pose.y += step(1);
  if (degenerate_direction) {
    const Eigen::Vector2d v = *degenerate_direction;
    const double along = v.dot(Eigen::Vector2d(pose.x - prior->x(), pose.y - prior->y()));
    pose.x -= along * v.x();
    pose.y -= along * v.y();
    step(0) -= along * v.x();
    step(1) -= along * v.y();
    remapped = true;
  }
  pose.theta = core::wrap_angle(pose.theta + step(2));
  return step;
}

/// Halves the search radius every third iteration (down to the final one); true when `step` was
/// small and the radius is final: converged.
bool converged_after(const Eigen::Vector3d& step, int iteration, double& radius, const IcpOptions& options) {
  const bool small = step.head<2>().norm() < options.convergence_translation_m &&
                     std::abs(step(2)) < options.convergence_rotation_rad;
  const double next_radius = std::max(options.final_correspondence_m, radius * 0.5);
  if (iteration % 3 == 2) radius = next_radius;
  return small && radius <= options.final_correspondence_m;
}

/// Final statistics at the solution, with the final radius: correspondences, inliers, RMS, the
/// scan term's Hessian and the degeneracy (icp.hpp's file comment).
void final_statistics(const PointMap& map, const std::vector<Eigen::Vector2d>& points_sensor, const IcpPose& pose,
                      double inv_sigma2, const IcpOptions& options, IcpResult& result) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  Eigen::Matrix2d normals = Eigen::Matrix2d::Zero();
  double sum_squared = 0.0;
  for (const auto& p : points_sensor) {
    const Eigen::Vector2d Rp(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    const Eigen::Vector2d world(Rp.x() + pose.x, Rp.y() + pose.y);
    const MapPoint* q = map.nearest(world, options.final_correspondence_m);
    if (q == nullptr) continue;
    ++result.correspondences;
    const Eigen::Vector2d e = world - q->position;
    const Eigen::Vector2d dtheta(-Rp.y(), Rp.x());
    const double distance = q->has_normal ? std::abs(q->normal.dot(e)) : e.norm();
    if (distance <= options.inlier_distance_m) {
      ++result.inliers;
      sum_squared += distance * distance;
    }
    if (q->has_normal) {
      const Eigen::Vector3d J(q->normal.x(), q->normal.y(), q->normal.dot(dtheta));
      const double w = huber_weight(distance, options.huber_threshold_m) * inv_sigma2;
      result.hessian += w * J * J.transpose();
      normals += q->normal * q->normal.transpose();
    } else if (options.point_to_point_weight > 0.0) {
      Eigen::Matrix<double, 2, 3> J;
      J << 1.0, 0.0, dtheta.x(), 0.0, 1.0, dtheta.y();
      result.hessian += options.point_to_point_weight * huber_weight(distance, options.huber_threshold_m) * inv_sigma2 *
                        J.transpose() * J;
      normals += Eigen::Matrix2d::Identity() * 0.5;
    }
  }
  result.inlier_fraction = result.points > 0 ? static_cast<double>(result.inliers) / result.points : 0.0;
  result.rms_m = result.inliers > 0 ? std::sqrt(sum_squared / result.inliers) : 0.0;
  if (result.correspondences > 0) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(normals / result.correspondences);
    result.degeneracy = eigen.eigenvalues()(0);
    result.degenerate_direction = eigen.eigenvectors().col(0);
  }
}
}  // namespace

IcpResult match_icp(const PointMap& map, const std::vector<Eigen::Vector2d>& points_sensor, const core::SE2& initial,
                    const core::SE2* prior, const IcpOptions& options) {
  CAIRN_ASSERT(options.max_iterations >= 1 && options.point_sigma_m > 0.0 && options.huber_threshold_m > 0.0,
               "invalid IcpOptions");
  IcpResult result;
  result.points = static_cast<int>(points_sensor.size());
  IcpPose pose{initial.x(), initial.y(), initial.angle()};
  const double inv_sigma2 = 1.0 / (options.point_sigma_m * options.point_sigma_m);
  const bool use_prior = prior != nullptr && options.prior_translation_sigma_m > 0.0 && options.prior_rotation_sigma_rad > 0.0;
  double radius = options.max_correspondence_m;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    NormalEquations equations = accumulate_scan_term(map, points_sensor, pose, radius, inv_sigma2, options);
    std::optional<Eigen::Vector2d> degenerate_direction;
    if (use_prior && equations.normal_count > 0) degenerate_direction = unconstrained_direction(equations, options);
    if (use_prior) add_prior_term(equations, pose, *prior, options);
    const std::optional<Eigen::Vector3d> step = gauss_newton_step(equations, degenerate_direction, prior, pose, result.remapped);
    if (!step) break;
    if (converged_after(*step, iteration, radius, options)) {
      result.converged = true;
      break;
    }
  }
  result.T_map_sensor = core::SE2(pose.x, pose.y, pose.theta);
  final_statistics(map, points_sensor, pose, inv_sigma2, options, result);
  return result;
}

std::string name_direction(const Eigen::Vector2d& direction_map, const core::SE2& T_map_sensor) {
  if (!(direction_map.squaredNorm() > 0.0)) return "one translation direction";
  const Eigen::Vector2d d = T_map_sensor.so2().inverse() * direction_map;
  double degrees = std::atan2(d.y(), d.x()) * 180.0 / std::numbers::pi;
  if (degrees < 0.0) degrees += 180.0;
  if (degrees >= 180.0) degrees -= 180.0;
  if (degrees <= 15.0 || degrees >= 165.0) return "translation along the laser's forward axis";
  if (std::abs(degrees - 90.0) <= 15.0) return "translation along the laser's sideways axis";
  return "translation along the axis " + std::to_string(std::lround(degrees)) + " degrees counterclockwise from the laser's forward axis";
}

}  // namespace cairn::slam2d
