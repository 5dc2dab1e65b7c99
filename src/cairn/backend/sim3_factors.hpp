#pragma once
/// \file
/// Sim(3) variables and factors on the least-squares engine (least_squares.hpp): the pose graph
/// of monocular SLAM, where scale drifts and loop closures correct it (Strasdat, Montiel &
/// Davison, "Scale drift-aware large scale monocular SLAM", RSS 2010; ORB-SLAM's
/// Optimizer::OptimizeEssentialGraph, whose g2o EdgeSim3 is the relative factor below written for
/// camera-from-world similarities S_cw, error log(Z S_iw S_jw^-1), where cairn's variables are
/// S_world_body).
///
/// Variables S_world_body on sim3_manifold(): stored as (qx, qy, qz, qw, tx, ty, tz, s), s > 0,
/// S * p = s R p + t (core/sim3.hpp), perturbed on the right S <- S exp(delta),
/// delta = (rho, phi, sigma) translation first.
///
/// Sim3RelativeFactor, the geodesic cost of factors.hpp's GeodesicFactor over Sim(3):
///   r = L log(Z_ij^-1 S_i^-1 S_j),  L^T L = information (7x7, tangent order (rho, phi, sigma)),
///   dr/d(delta_j) = L Jr^-1(e),  dr/d(delta_i) = -L Jr^-1(e) Adj(S_j^-1 S_i),  e = log(...)
/// (perturbing S_i gives E exp(-Adj(S_j^-1 S_i) delta_i), as for SE(3)). Jr^-1 and Adj are
/// core::Sim3's (Jr^-1 exact up to the truncation of its coupling series, sim3.hpp). ORB-SLAM
/// weighs every essential-graph edge with the identity information.
///
/// Sim3PriorFactor: r = L log(Z^-1 S), dr/d(delta) = L Jr^-1(e).

#include <Eigen/Core>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/sim3.hpp"

namespace cairn::backend {

/// Sim(3) stored as (qx, qy, qz, qw, tx, ty, tz, s), s > 0; delta = (rho, phi, sigma),
/// S <- S exp(delta).
const Manifold& sim3_manifold();

/// A similarity and the storage of sim3_manifold(), both ways.
core::Sim3 sim3_from_values(const double* x);
void sim3_to_values(const core::Sim3& S, double* x);

using Sim3SquareRootInformation = Eigen::Matrix<double, 7, 7>;

/// Relative Sim(3) measurement Z = S_i_j between S_world_i and S_world_j (values = {S_world_i,
/// S_world_j}, both sim3_manifold()).
class Sim3RelativeFactor final : public Factor {
 public:
  Sim3RelativeFactor(const core::Sim3& S_i_j, const Sim3SquareRootInformation& sqrt_information)
      : S_i_j_(S_i_j), sqrt_information_(sqrt_information) {}
  int residual_size() const override { return 7; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

  const core::Sim3& measurement() const { return S_i_j_; }

 private:
  core::Sim3 S_i_j_;
  Sim3SquareRootInformation sqrt_information_;
};

/// Prior Z = S_world_body on one Sim(3) variable (values = {S_world_body}).
class Sim3PriorFactor final : public Factor {
 public:
  Sim3PriorFactor(const core::Sim3& S_world_body, const Sim3SquareRootInformation& sqrt_information)
      : S_world_body_(S_world_body), sqrt_information_(sqrt_information) {}
  int residual_size() const override { return 7; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  core::Sim3 S_world_body_;
  Sim3SquareRootInformation sqrt_information_;
};

}  // namespace cairn::backend
