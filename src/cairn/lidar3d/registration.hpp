#pragma once
/// \file
/// Scan-to-map registration: point-to-point ICP with a Geman-McClure kernel, as KISS-ICP
/// (Vizzo et al., RA-L 2023, Sec. III-D, eq. 5-6; kiss_icp/core/Registration.cpp), with the
/// degeneracy analysis of Zhang, Kaess & Singh, "On degeneracy of optimization-based state
/// estimation problems", ICRA 2016.
///
/// Each iteration pairs every source point, moved by the current T_map_sensor, with its nearest
/// map point (voxel_hash_map.hpp) if that lies within `max_correspondence_m`, and takes one
/// Gauss-Newton step on
///   sum_i rho(||T p_i - q_i||^2),  rho's weight w(r^2) = kappa^2 / (kappa + r^2)^2
/// (KISS-ICP's weight, kappa = `kernel_scale_m`), with the left perturbation
/// T <- exp(delta) T, delta = (rho, phi) translation first, Jacobian J_i = [I, -[T p_i]x].
///
/// Degeneracy (Zhang et al. 2016, Sec. IV-V) is a property of the surfaces, so it is judged on
/// the correspondences with a planar voxel, whatever the metric (a point-to-point H has a
/// translation block sum w I, never degenerate, even in a featureless tunnel, where matching the
/// scan's own ring pattern holds the pose back). Two measures are reported:
///  - `translation_degeneracy`, which decides: the smallest eigenvalue of the weighted mean
///    N = sum w n n^T / sum w of the normals, the share of the surfaces that constrains the worst
///    translation direction (in [0, 1/3]; a tunnel's axis gets only the normals' noise). Measured:
///    >= 0.078 on every real KITTI 00 key frame, about 0.0065 inside the simulated tunnel.
///    Directions below `degenerate_min_eigenvalue` are degenerate and reported. With
///    `remap_degenerate_directions` the step is solved in the span of the others and every
///    rotation (their "solution remapping"), so along a degenerate direction the pose stays at
///    the initial guess, i.e. the motion prior carries it. Off by default, by measurement: the
///    planes miss what poles, trees and cars say along a street (point-to-point terms), and a
///    prior that comes from the same LiDAR lags whenever the vehicle accelerates; on the simulated
///    street with loops remapping made the end-point error 17.9 m instead of 1.2 m, and in the
///    simulated tunnel, entered from rest, it kept the estimate near the start either way;
///  - `degeneracy`, the smallest eigenvalue of the 6-DoF point-to-plane normal matrix normalised
///    to the share of correspondences, H_s = S H S / sum w, S = diag(1, 1, 1, 1/L, 1/L, 1/L), L the
///    weighted RMS range (a rotation phi moves such a point by L phi). It also sees rotations,
///    but the normals' noise puts real streets and the tunnel at the same values (median 0.007
///    on both), so it is reported only.

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {

/// Residual per correspondence (p the moved source point, q its map neighbour, n the normal of
/// q's voxel).
enum class IcpMetric {
  /// ||p - q||^2: KISS-ICP's choice (Vizzo et al. 2023, Sec. III-D).
  kPointToPoint,
  /// (n . (p - q))^2 where q's voxel is planar, ||p - q||^2 elsewhere (Chen & Medioni 1992;
  /// LOAM's planar residual, Zhang & Singh 2014, eq. 3, with a per-voxel plane fit).
  kPointToPlane,
};

struct RegistrationOptions {
  IcpMetric metric = IcpMetric::kPointToPlane;
  /// Gauss-Newton iterations at most (KISS-ICP: 500).
  int max_iterations = 500;
  /// Stop when the step's norm (m and rad mixed, as KISS-ICP) is below this (KISS-ICP: 1e-4).
  double convergence_step = 1e-4;
  /// Eigenvalue of the mean normal moment N below which a translation direction is degenerate
  /// and left to the prior, in [0, 1/3). 0 turns the remapping off.
  double degenerate_min_eigenvalue = 0.02;
  /// Solve degenerate directions from the initial guess only (Zhang et al.'s remapping); see
  /// above for why it is off by default.
  bool remap_degenerate_directions = false;
};

struct RegistrationResult {
  core::SE3 T_map_sensor;
  int iterations = 0;
  /// The last step was below convergence_step, or undid the step before it to within that (a
  /// two-cycle, ended half-way); false: the iteration limit was reached.
  bool converged = false;
  /// Source points with a map point within max_correspondence_m, at the last iteration.
  std::size_t correspondences = 0;
  std::size_t source_points = 0;
  /// Root mean square distance of those correspondences, metres.
  double rms_m = 0.0;
  /// Correspondences whose map voxel is planar, at the last iteration.
  std::size_t planar_correspondences = 0;
  /// Eigenvalues of the scaled point-to-plane normal matrix H_s at the last iteration, ascending;
  /// and the weakest translation direction (eigenvector of N's smallest eigenvalue; rotation part
  /// zero), in the map frame.
  Eigen::Matrix<double, 6, 1> eigenvalues = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> weakest_direction = Eigen::Matrix<double, 6, 1>::Zero();
  /// lambda_min of H_s (0 when there were too few planar correspondences).
  double degeneracy = 0.0;
  /// Smallest eigenvalue of the weighted mean n n^T of the planar correspondences' normals, in
  /// [0, 1/3]: how much the surfaces constrain the worst translation direction.
  double translation_degeneracy = 0.0;
  /// L of the normalisation, metres.
  double characteristic_length_m = 0.0;
  /// Directions solved from the prior instead of the scan (0 normally).
  int degenerate_directions = 0;
  /// The Gauss-Newton matrix J^T W J of the last iteration (tangent translation first, the left
  /// perturbation T_map_sensor <- exp(delta) T_map_sensor of the residuals' Jacobians [I, -[p]x]);
  /// with the residuals' variance, the estimate's covariance (pairwise_registration.hpp).
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
};

/// Registers `source_sensor` (points in the sensor frame) to `map`, starting at
/// `T_map_sensor_guess`. Preconditions: max_correspondence_m > 0, kernel_scale_m > 0. Uses the
/// calling thread's TBB arena; the sums are reduced in a fixed order, so the result does not
/// depend on the number of threads.
RegistrationResult register_scan(const VoxelHashMap& map, const std::vector<Eigen::Vector3d>& source_sensor,
                                 const core::SE3& T_map_sensor_guess, double max_correspondence_m,
                                 double kernel_scale_m, const RegistrationOptions& options = {});

/// LOAM's scan-to-map step (Zhang & Singh 2014, Sec. VI, eq. 2-3): edge points (sensor frame)
/// against the lines of `edge_map` (point-to-line), planar points against the planes of
/// `plane_map` (point-to-plane); points whose nearest voxel has no line or plane are skipped.
/// Same Gauss-Newton, kernel, convergence and degeneracy analysis as register_scan (a line
/// contributes (I - d d^T) / 2 to the translation information).
RegistrationResult register_features(const VoxelHashMap& edge_map, const VoxelHashMap& plane_map,
                                     const std::vector<Eigen::Vector3d>& edges_sensor,
                                     const std::vector<Eigen::Vector3d>& planes_sensor,
                                     const core::SE3& T_map_sensor_guess, double max_correspondence_m,
                                     double kernel_scale_m, const RegistrationOptions& options = {});

/// "x (forward)", "y (left)", "z (up)", "roll", "pitch" or "yaw": the sensor axis along (or
/// about) which `direction_map` (translation, rotation) mostly points, after rotating it into the
/// sensor frame with R_map_sensor and scaling the rotation by `length_m`.
std::string name_direction(const Eigen::Matrix<double, 6, 1>& direction_map, const core::SO3& R_map_sensor,
                           double length_m);

}  // namespace cairn::lidar3d
