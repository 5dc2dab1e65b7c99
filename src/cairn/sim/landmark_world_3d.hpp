#pragma once
/// \file
/// A 3D point-landmark world with ground truth, for graph SLAM with SE(3) poses and 3D points
/// (backend/landmark_graph_3d.hpp): a body flying laps of a circle with climbing, rolling and
/// pitching motion among landmarks scattered in a box, observing each landmark in range and in
/// its viewing cone, with noisy odometry.
///
/// Trajectory (pose k of n, laps L, s = 2 pi L k / n):
///   position (R cos s, R sin s, h sin(3 s / L)),  yaw s + pi/2 (along the circle),
///   roll a sin(2 s), pitch a cos(5 s)        (a = attitude_amplitude_rad),
/// so every rotational degree of freedom is excited. Landmarks are uniform in
/// [-E, E] x [-E, E] x [z_min, z_max], or, with ring_half_width_m = w > 0, uniform in the annulus
/// R - w <= |(x, y)| <= R + w (uniform in angle and in radius) for the same z range, so that
/// their density along the route stays constant when R grows.
///
/// Sensors (one Gaussian variate per noisy component, drawn from independent streams):
/// * odometry: Z_k = T_k^-1 T_k+1 exp(n), n ~ N(0, diag(sigma_t^2 I3, sigma_r^2 I3)), translation
///   first, the right perturbation of the factors;
/// * a landmark with q = T_world_body^-1 p is seen when 0.5 m <= |q| <= max_range_m and the angle between
///   q and the body x axis is at most field_of_view_rad / 2; the observation is q + N(0,
///   point_sigma^2 I3) (kPoint: stereo / RGB-D) or (range, bearing, elevation)(q) + N(0,
///   diag(range_sigma^2, angle_sigma^2, angle_sigma^2)) (kRangeBearingElevation).

#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"

namespace cairn::sim {

enum class LandmarkSensor3D { kPoint, kRangeBearingElevation };

struct LandmarkWorld3DOptions {
  int poses = 300;                    ///< > 1
  int laps = 2;                       ///< >= 1
  double circle_radius_m = 15.0;      ///< > 0
  double climb_m = 3.0;               ///< h above, >= 0
  double attitude_amplitude_rad = 0.2;
  int landmarks = 400;                ///< >= 0
  double extent_m = 25.0;             ///< E, > 0
  double ring_half_width_m = 0.0;     ///< w, >= 0 (0: the box)
  double landmark_z_min_m = -5.0;
  double landmark_z_max_m = 10.0;     ///< > z_min
  LandmarkSensor3D sensor = LandmarkSensor3D::kPoint;
  double max_range_m = 12.0;          ///< > 0
  double field_of_view_rad = 2.0 * std::numbers::pi;  ///< full cone angle, (0, 2 pi]
  double point_sigma_m = 0.05;        ///< >= 0 (all sigmas)
  double range_sigma_m = 0.05;
  double angle_sigma_rad = 0.01;
  double odometry_translation_sigma_m = 0.02;
  double odometry_rotation_sigma_rad = 0.005;

  bool is_valid(std::string* why) const;
};

struct LandmarkObservation3D {
  std::size_t pose = 0;
  std::size_t landmark = 0;
  /// q_body (kPoint) or (range m, bearing rad, elevation rad).
  Vector3 z = Vector3::Zero();
};

struct LandmarkWorld3D {
  LandmarkSensor3D sensor = LandmarkSensor3D::kPoint;
  std::vector<core::SE3> T_world_body;   ///< ground truth, one per pose
  std::vector<Vector3> p_world;          ///< ground truth landmarks
  std::vector<core::SE3> odometry;       ///< measured T_k_k+1, poses - 1 of them
  Matrix6 odometry_covariance = Matrix6::Identity();
  std::vector<LandmarkObservation3D> observations;  ///< in pose order
  Matrix3 observation_covariance = Matrix3::Identity();
};

/// Precondition: options.is_valid(). Deterministic in `seed`.
LandmarkWorld3D simulate_landmark_world_3d(const LandmarkWorld3DOptions& options, std::uint64_t seed);

}  // namespace cairn::sim
