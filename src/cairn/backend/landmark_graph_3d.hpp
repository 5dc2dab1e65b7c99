#pragma once
/// \file
/// Graph SLAM with 3D point landmarks: SE(3) poses T_world_body and points p_world as
/// variables, relative-pose factors between poses and point / range-bearing-elevation factors
/// from a pose to a point (landmark_factors_3d.hpp), solved by Levenberg-Marquardt
/// (Grisetti et al. 2010, "A tutorial on graph-based SLAM", Sec. IV, here in 3D). This file is a
/// front end: it builds the factors (whitened by the Cholesky factor of their information) and
/// hands them to the least-squares engine (least_squares.hpp), whose LM and Schur elimination
/// do the solving.
///
/// Parameterisation: T <- T exp(delta), delta = (rho, phi) translation first
/// (docs/conventions.md); p <- p + dp.
///
/// Factors (cost e^T Omega e):
///   relative pose i -> j, measurement Z = T_i_j:  e = log(Z^-1 T_i^-1 T_j),
///     de/d(delta_j) = Jr^-1(e),  de/d(delta_i) = -Jr^-1(e) Adj(T_j^-1 T_i)
///     (the GeodesicFactor of factors.hpp, docs/math/pose_graph.md);
///   landmark l from pose i: e = q(T_i, p_l) - z or (r, b, el)(q) - z (landmark_factors_3d.hpp).
///
/// Linear solver: by default the landmarks are eliminated first (Schur complement, as in bundle
/// adjustment: Triggs et al. 2000, "Bundle adjustment -- a modern synthesis", Sec. 6.1; Ceres'
/// SPARSE_SCHUR). With the normal equations ordered [poses; landmarks],
///     [ A   W ] [dx_p]   [-b_p]
///     [ W^T V ] [dx_l] = [-b_l],   V block-diagonal with one 3x3 block per landmark,
/// the reduced system (A - W V^-1 W^T) dx_p = -b_p + W V^-1 b_l is factorised by CHOLMOD
/// (6x6 pose blocks, block AMD ordering), then dx_l = V^-1 (-b_l - W^T dx_p) landmark by
/// landmark. Which is faster depends on the data (bench/landmarks_3d_elimination.cpp,
/// docs/landmark-slam.md): with an omnidirectional sensor, each landmark seen from ~50 poses,
/// Schur elimination was 3-5.6x faster per iteration than `LandmarkElimination::kJoint` (one
/// CHOLMOD ordering of the whole system); with a narrow camera-like sensor the joint ordering
/// was 1.5-2x faster, because eliminating every landmark first fills the reduced pose system.

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/backend/landmark_graph.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"

namespace cairn::backend {

struct PoseFactor3D {
  std::size_t from = 0;
  std::size_t to = 0;
  core::SE3 T_from_to;
  /// Inverse covariance of log(Z^-1 T_from^-1 T_to), translation first; positive definite.
  Matrix6 information = Matrix6::Identity();
};

enum class LandmarkModel3D {
  kPoint,                  ///< z = q_body, the point in the body frame (stereo / RGB-D), metres
  kRangeBearingElevation,  ///< z = (range m, bearing rad, elevation rad) of q_body
};

struct LandmarkFactor3D {
  std::size_t pose = 0;
  std::size_t landmark = 0;
  LandmarkModel3D model = LandmarkModel3D::kPoint;
  Vector3 z = Vector3::Zero();
  /// Inverse covariance of z; positive definite.
  Matrix3 information = Matrix3::Identity();
};

/// Variables and factors. Pose 0 is held fixed (it defines the world frame).
struct LandmarkGraph3D {
  std::vector<core::SE3> poses;    ///< T_world_body
  std::vector<Vector3> landmarks;  ///< p_world
  std::vector<PoseFactor3D> odometry;
  std::vector<LandmarkFactor3D> observations;

  /// Empty when the graph is well formed (indices in range, finite values, positive definite
  /// information matrices, ranges > 0, every landmark observed at least once); else the first
  /// problem found, naming the factor or variable.
  std::string check() const;
  /// Sum over factors of e^T Omega e.
  double cost() const;
};

/// The initial landmark position implied by one observation from `T_world_body`.
Vector3 landmark_from_observation_3d(const core::SE3& T_world_body, const LandmarkFactor3D& observation);

enum class LandmarkElimination {
  kSchur,  ///< eliminate landmarks, factorise the reduced pose system (default)
  kJoint,  ///< factorise poses and landmarks together under one AMD ordering
};

/// The 2D solver's LM settings (documented there) plus the elimination, mapped onto the engine:
/// max_iterations as is, the initial damping as the initial trust-region radius
/// 1 / initial_lambda, relative_cost_tolerance as the function tolerance and step_tolerance as
/// the parameter tolerance (relative to the norm of the variables, Ceres' rule).
struct LandmarkGraph3DOptions : LandmarkGraphOptions {
  LandmarkElimination elimination = LandmarkElimination::kSchur;
};

/// Optimises `graph` in place (pose 0 fixed). Precondition: graph.check() is empty and
/// options.is_valid(). The summary's `factorised_variables` is the size of the system
/// handed to the sparse Cholesky (free poses x 6 with Schur elimination).
LandmarkGraphSummary optimize(LandmarkGraph3D& graph, const LandmarkGraph3DOptions& options = {});

}  // namespace cairn::backend
