#pragma once
/// \file
/// Point-to-line ICP in the plane (Censi, ICRA 2008; the point-to-plane error of Chen & Medioni
/// 1992 restricted to 2D), Gauss-Newton with Huber weights over (x, y, theta), optionally pulled
/// towards a prior pose (the odometry prediction), as Cartographer's Ceres scan matcher pulls
/// towards its initial pose (Hess et al. 2016, eq. (CS) with translation/rotation weights).
///
/// Residual of scan point p (laser frame) against its nearest map point q with normal n:
///   r = n^T (R(theta) p + t - q) / sigma_point,
///   dr/d(x, y, theta) = [n_x, n_y, n^T R'(theta) p] / sigma_point,  R' p = (-(Rp)_y, (Rp)_x).
/// Map points without a normal (corners, clutter, walls sampled too sparsely for a normal) give
/// the two point-to-point residuals, weighted by `point_to_point_weight` (default 0: ignored).
/// On a sparsely sampled wall the nearest map point lies at the old sampling position, so
/// point-to-point residuals drag the pose back along the wall (measured: a simulated corridor
/// drive stuck for 6 m with weight 1).
///
/// The Hessian of the scan term, H = sum w J^T J, is returned for the covariance of the match
/// (H^-1, Censi's first-order estimate; optimistic) and for degeneracy: `degeneracy` is the
/// smallest eigenvalue of sum n n^T divided by the number of correspondences, 0 in a featureless
/// corridor (translation along it unobservable), up to 0.5 for normals spread evenly.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/slam2d/point_map.hpp"

namespace cairn::slam2d {

struct IcpOptions {
  int max_iterations = 30;                 ///< >= 1
  double max_correspondence_m = 0.3;       ///< first iterations' search radius (<= map cell size)
  double final_correspondence_m = 0.1;     ///< radius is halved every 3 iterations down to this
  double point_sigma_m = 0.02;             ///< range noise used to scale residuals; > 0
  double huber_threshold_m = 0.03;         ///< Huber kernel width on |n^T e|; > 0
  double inlier_distance_m = 0.05;         ///< a point counts as inlier within this of the map
  double point_to_point_weight = 0.0;      ///< weight of points whose map neighbour has no normal
  /// Prior standard deviations (odometry prediction); <= 0 disables the prior.
  double prior_translation_sigma_m = 0.1;
  double prior_rotation_sigma_rad = 0.05;
  /// With a prior: translation directions whose normal spread (see `degeneracy`) is below this
  /// take the prior's value (Zhang et al. ICRA 2016 solution remapping); 0 disables.
  double degenerate_threshold = 0.03;
  double convergence_translation_m = 1e-5;
  double convergence_rotation_rad = 1e-6;
};

struct IcpResult {
  core::SE2 T_map_sensor;
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();  ///< scan term only, (x, y, theta), 1/sigma^2 units
  int points = 0;            ///< scan points tried
  int correspondences = 0;   ///< with a map point within the final radius
  int inliers = 0;           ///< within inlier_distance_m
  double inlier_fraction = 0.0;  ///< inliers / points
  double rms_m = 0.0;        ///< RMS point-to-line distance over inliers
  double degeneracy = 0.0;   ///< see file comment
  /// The unit direction (map frame) of that smallest eigenvalue: the translation the normals
  /// constrain least (a corridor's axis when `degeneracy` is near 0). Zero without correspondences.
  Eigen::Vector2d degenerate_direction = Eigen::Vector2d::Zero();
  int iterations = 0;
  bool converged = false;
  bool remapped = false;     ///< a degenerate direction was taken from the prior
};

/// Aligns `points_sensor` to `map` from `initial`. `prior` (may equal `initial`) is the pose the
/// prior term pulls towards; pass nullptr for none.
IcpResult match_icp(const PointMap& map, const std::vector<Eigen::Vector2d>& points_sensor,
                    const core::SE2& initial, const core::SE2* prior, const IcpOptions& options = {});

/// A translation direction in the map frame (IcpResult::degenerate_direction) in words, relative to
/// the sensor's forward axis at `T_map_sensor`: "translation along the laser's forward axis" within
/// 15 degrees of it, "... sideways axis" within 15 degrees of that, else the axis's angle from
/// forward (0-180 degrees, counterclockwise; a direction and its opposite are one axis).
std::string name_direction(const Eigen::Vector2d& direction_map, const core::SE2& T_map_sensor);

}  // namespace cairn::slam2d
