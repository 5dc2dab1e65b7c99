#include "cairn/slam2d/icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>

#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::slam2d {
namespace {
double huber_weight(double r, double k) { return std::abs(r) <= k ? 1.0 : k / std::abs(r); }
}  // namespace

IcpResult match_icp(const PointMap& map, const std::vector<Eigen::Vector2d>& points_sensor, const core::SE2& initial,
                    const core::SE2* prior, const IcpOptions& options) {
  CAIRN_ASSERT(options.max_iterations >= 1 && options.point_sigma_m > 0.0 && options.huber_threshold_m > 0.0,
               "invalid IcpOptions");
  IcpResult result;
  result.points = static_cast<int>(points_sensor.size());
  double x = initial.x(), y = initial.y(), theta = initial.angle();
  const double inv_sigma2 = 1.0 / (options.point_sigma_m * options.point_sigma_m);
  const bool use_prior = prior != nullptr && options.prior_translation_sigma_m > 0.0 && options.prior_rotation_sigma_rad > 0.0;
  double radius = options.max_correspondence_m;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    result.iterations = iteration + 1;
    const double c = std::cos(theta), s = std::sin(theta);
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    Eigen::Matrix2d normal_outer = Eigen::Matrix2d::Zero();
    int normal_count = 0;
    std::optional<Eigen::Vector2d> degenerate_direction;
    for (const auto& p : points_sensor) {
      const Eigen::Vector2d Rp(c * p.x() - s * p.y(), s * p.x() + c * p.y());
      const Eigen::Vector2d world(Rp.x() + x, Rp.y() + y);
      const MapPoint* q = map.nearest(world, radius);
      if (q == nullptr) continue;
      const Eigen::Vector2d e = world - q->position;
      const Eigen::Vector2d dtheta(-Rp.y(), Rp.x());
      if (q->has_normal) {
        const double r = q->normal.dot(e);
        const Eigen::Vector3d J(q->normal.x(), q->normal.y(), q->normal.dot(dtheta));
        const double w = huber_weight(r, options.huber_threshold_m) * inv_sigma2;
        H += w * J * J.transpose();
        g += w * J * r;
        normal_outer += q->normal * q->normal.transpose();
        ++normal_count;
      } else if (options.point_to_point_weight > 0.0) {
        const double w = options.point_to_point_weight * huber_weight(e.norm(), options.huber_threshold_m) * inv_sigma2;
        Eigen::Matrix<double, 2, 3> J;
        J << 1.0, 0.0, dtheta.x(), 0.0, 1.0, dtheta.y();
        H += w * J.transpose() * J;
        g += w * J.transpose() * e;
      }
    }
    if (use_prior && normal_count > 0) {
      // Degeneracy-aware update (Zhang, Kaess & Singh, "On degeneracy of optimization-based
      // state estimation problems", ICRA 2016, solution remapping): along a translation direction
      // the normals do not constrain (a corridor's axis), noisy normals still carry a little
      // information that pins the pose to where the map was sampled; there the prior decides.
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> spread(normal_outer / normal_count);
      if (spread.eigenvalues()(0) < options.degenerate_threshold) degenerate_direction = spread.eigenvectors().col(0);
    }
    if (use_prior) {
      const double wt = 1.0 / (options.prior_translation_sigma_m * options.prior_translation_sigma_m);
      const double wr = 1.0 / (options.prior_rotation_sigma_rad * options.prior_rotation_sigma_rad);
      H(0, 0) += wt;
      H(1, 1) += wt;
      H(2, 2) += wr;
      g(0) += wt * (x - prior->x());
      g(1) += wt * (y - prior->y());
      g(2) += wr * core::wrap_angle(theta - prior->angle());
    }
    if (H.trace() <= 0.0) break;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) break;
    Eigen::Vector3d step = -ldlt.solve(g);
    if (!step.allFinite()) break;
    x += step(0);
    y += step(1);
    if (degenerate_direction) {
      const Eigen::Vector2d v = *degenerate_direction;
      const double along = v.dot(Eigen::Vector2d(x - prior->x(), y - prior->y()));
      x -= along * v.x();
      y -= along * v.y();
      step(0) -= along * v.x();
      step(1) -= along * v.y();
      result.remapped = true;
    }
    theta = core::wrap_angle(theta + step(2));
    const bool small = step.head<2>().norm() < options.convergence_translation_m &&
                       std::abs(step(2)) < options.convergence_rotation_rad;
    const double next_radius = std::max(options.final_correspondence_m, radius * 0.5);
    if (iteration % 3 == 2) radius = next_radius;
    if (small && radius <= options.final_correspondence_m) {
      result.converged = true;
      break;
    }
  }
  // Final statistics at the solution, with the final radius.
  result.T_map_sensor = core::SE2(x, y, theta);
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix2d normals = Eigen::Matrix2d::Zero();
  double sum_squared = 0.0;
  for (const auto& p : points_sensor) {
    const Eigen::Vector2d Rp(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    const Eigen::Vector2d world(Rp.x() + x, Rp.y() + y);
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
  }
  return result;
}

}  // namespace cairn::slam2d
