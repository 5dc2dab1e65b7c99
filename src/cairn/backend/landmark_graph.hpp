#pragma once
/// \file
/// Graph SLAM with point landmarks in 2D (Grisetti, Kuemmerle, Stachniss & Burgard 2010, "A
/// tutorial on graph-based SLAM"): SE(2) poses and 2D landmark positions as variables,
/// odometry factors between consecutive poses and range-bearing factors from a pose to a
/// landmark, solved by Levenberg-Marquardt on the sparse normal equations.
///
/// Parameterisation: a pose is (x, y, theta) = T_world_body as a vector, updated by
/// x <- (x + dx, y + dy, wrap(theta + dtheta)) (a valid retraction on SE(2); Jacobians below are
/// with respect to these increments); a landmark is p_world, updated additively.
///
/// Factors (residual e, cost e^T Omega e):
///   odometry i -> j, measurement u = (u_x, u_y, u_theta) in body frame i:
///     e = ( R(theta_i)^T (t_j - t_i) - u_t ,  wrap(theta_j - theta_i - u_theta) )
///     J_e_pose_i = [ -R_i^T   dR_i^T/dtheta (t_j - t_i) ; 0  -1 ],  J_e_pose_j = [ R_i^T  0 ; 0  1 ]
///     (Grisetti et al. 2010, the A_ij / B_ij of their 2D example, with R_ij = I because the
///     translation part here is not rotated into the measurement frame).
///   range-bearing pose i -> landmark l, measurement z = (r, b):
///     e = ( |p - t_i| - r ,  wrap(atan2(p - t_i) - theta_i - b) ), Jacobians as in
///     filter/range_bearing.hpp (Thrun et al. 2005 Table 10.1).
///
/// Solver: this file is a front end. It builds the factors (whitened by the Cholesky factor of
/// their information) and the (x, y, theta) retraction above as a manifold, and hands them to the
/// least-squares engine (least_squares.hpp) with its sparse normal Cholesky: the normal equations
/// over all free poses and all landmarks, one block-AMD ordering of the whole system, CHOLMOD.
/// Landmarks are NOT Schur-complemented first: in a range-bearing run each landmark is seen from
/// hundreds of poses, so eliminating landmarks first would connect all those poses to each other
/// (dense cliques); AMD on the joint system keeps the factor sparse (Schur elimination pays off in
/// bundle adjustment, where points outnumber cameras and each point is seen from few).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/types.hpp"

namespace cairn::backend {

using Matrix23 = Eigen::Matrix<double, 2, 3>;

/// e = between(x_i, x_j) - u (angle wrapped) and its Jacobians (see the file comment).
Vector3 odometry_residual_2d(const Vector3& pose_i, const Vector3& pose_j, const Vector3& u,
                             Matrix3* J_e_pose_i = nullptr, Matrix3* J_e_pose_j = nullptr);

/// e = h(x, p) - z (bearing wrapped). Precondition: p differs from the pose position.
Vector2 range_bearing_residual_2d(const Vector3& pose, const Vector2& p_world, const Vector2& z,
                                  Matrix23* J_e_pose = nullptr, Matrix2* J_e_landmark = nullptr);

struct OdometryFactor2D {
  std::size_t from = 0;
  std::size_t to = 0;
  /// T_from_to as (x, y, theta).
  Vector3 u = Vector3::Zero();
  /// Inverse covariance over u, positive definite.
  Matrix3 information = Matrix3::Identity();
};

struct RangeBearingFactor2D {
  std::size_t pose = 0;
  std::size_t landmark = 0;
  /// (range_m, bearing_rad).
  Vector2 z = Vector2::Zero();
  Matrix2 information = Matrix2::Identity();
};

/// Variables and factors. Pose 0 is held fixed (it defines the world frame).
struct LandmarkGraph2D {
  std::vector<Vector3> poses;       ///< T_world_body as (x, y, theta)
  std::vector<Vector2> landmarks;   ///< p_world
  std::vector<OdometryFactor2D> odometry;
  std::vector<RangeBearingFactor2D> observations;

  /// Empty when every index is in range and every value finite; else the first problem.
  std::string check() const;
  /// Sum over factors of e^T Omega e.
  double cost() const;
};

struct LandmarkGraphOptions {
  /// LM iterations at most (>= 1).
  int max_iterations = 100;
  /// Initial damping, relative to the diagonal of H: (H + lambda diag(H)) dx = -b (> 0); the
  /// engine's initial trust-region radius is 1 / initial_lambda, and later damping follows its
  /// LM (Ceres' rule, least_squares.hpp).
  double initial_lambda = 1e-5;
  /// Stop when a step changes the cost by less than this fraction of it (>= 0; the engine's
  /// function tolerance).
  double relative_cost_tolerance = 1e-10;
  /// Stop when ||step|| < step_tolerance (||x|| + step_tolerance), x every free variable (>= 0;
  /// the engine's parameter tolerance).
  double step_tolerance = 1e-10;

  bool is_valid(std::string* why) const;
};

enum class LandmarkGraphStatus { kConverged, kMaxIterations, kFailed };

struct LandmarkGraphSummary {
  LandmarkGraphStatus status = LandmarkGraphStatus::kFailed;
  std::string message;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  std::size_t variables = 0;         ///< scalar unknowns (free poses x 3 + landmarks x 2)
  std::size_t factorised_variables = 0;  ///< size of the system factorised (< variables after Schur elimination)
  std::size_t factor_nonzeros = 0;   ///< non-zeros of the last Cholesky factor
  double time_linearise_s = 0.0;
  double time_solve_s = 0.0;
  bool usable() const { return status != LandmarkGraphStatus::kFailed; }
};

/// Optimises `graph` in place (pose 0 fixed). Precondition: graph.check() is empty and
/// options.is_valid().
LandmarkGraphSummary optimize(LandmarkGraph2D& graph, const LandmarkGraphOptions& options = {});

struct LeastSquaresSummary;
/// Status, message, iterations, sizes and times of an engine solve (least_squares.hpp) in the
/// landmark graphs' summary (both graphs are front ends over the engine); costs are left alone
/// (the graphs' cost has no 1/2).
void copy_engine_summary(const LeastSquaresSummary& result, LandmarkGraphSummary& summary);

/// Marginal covariances from the inverse of the Gauss-Newton Hessian at the current estimate
/// (the Laplace approximation; pose 0 fixed, so its covariance is zero).
struct LandmarkGraphMarginals {
  /// For the requested pose / landmark indices, in order; NaN for an index out of range.
  std::vector<Matrix3> poses;
  std::vector<Matrix2> landmarks;
  bool ok = false;                                ///< false when H is not positive definite
};
LandmarkGraphMarginals marginal_covariances(const LandmarkGraph2D& graph, const std::vector<std::size_t>& pose_indices,
                                            const std::vector<std::size_t>& landmark_indices);

}  // namespace cairn::backend
