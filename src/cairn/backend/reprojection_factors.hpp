#pragma once
/// \file
/// Reprojection factors for bundle adjustment on the least-squares engine (least_squares.hpp),
/// with analytic Jacobians (checked against numeric derivatives in
/// tests/backend/test_reprojection_factors.cpp).
///
/// BAL camera (Agarwal, Snavely, Seitz & Szeliski, "Bundle adjustment in the large", ECCV 2010;
/// grail.cs.washington.edu/projects/bal): 9 parameters (w, t, f, k1, k2), w an angle-axis
/// rotation, all additive (Ceres' bundle_adjuster without a local parameterisation):
///     P = R(w) X + t,  p = -(P_x, P_y) / P_z,  d = 1 + k1 |p|^2 + k2 |p|^4,
///     residual = f d p - observation   (pixels, origin at the image centre, y up).
///
/// Pinhole camera with known intrinsics (visual SLAM): variable T_world_camera on SE(3)
/// (se3_manifold(), T <- T exp(delta)), point p_world in R^3, p_camera = T^-1 p_world,
///     monocular: residual = (fx x/z + cx, fy y/z + cy) - (u, v),
///     stereo (ORB-SLAM's (u_l, v_l, u_r)): adds u_r = fx (x - b) / z + cx, b the baseline in m.

#include "cairn/backend/least_squares.hpp"

namespace cairn::backend {

/// Dimension of the BAL camera block.
inline constexpr int kBalCameraSize = 9;

class BalReprojectionFactor final : public Factor {
 public:
  BalReprojectionFactor(double observed_x, double observed_y) : observed_x_(observed_x), observed_y_(observed_y) {}
  int residual_size() const override { return 2; }
  /// values = {camera (9), point (3)}.
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  double observed_x_;
  double observed_y_;
};

struct PinholeIntrinsics {
  double fx = 1.0;
  double fy = 1.0;
  double cx = 0.0;
  double cy = 0.0;
};

class PinholeReprojectionFactor final : public Factor {
 public:
  PinholeReprojectionFactor(const PinholeIntrinsics& intrinsics, double u, double v)
      : intrinsics_(intrinsics), u_(u), v_(v) {}
  int residual_size() const override { return 2; }
  /// values = {T_world_camera (SE(3), 7), p_world (3)}. Not defined (false) for a point at or
  /// behind the camera plane (z <= 1e-9 m).
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  PinholeIntrinsics intrinsics_;
  double u_;
  double v_;
};

class StereoReprojectionFactor final : public Factor {
 public:
  StereoReprojectionFactor(const PinholeIntrinsics& intrinsics, double baseline_m, double u_left, double v_left,
                           double u_right)
      : intrinsics_(intrinsics), baseline_m_(baseline_m), u_left_(u_left), v_left_(v_left), u_right_(u_right) {}
  int residual_size() const override { return 3; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  PinholeIntrinsics intrinsics_;
  double baseline_m_;
  double u_left_;
  double v_left_;
  double u_right_;
};

}  // namespace cairn::backend
