#include "cairn/sim/landmark_world_3d.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

constexpr double kPi = std::numbers::pi;
// Nearer landmarks are not reported (a noisy range must stay > 0).
constexpr double kMinRange = 0.5;

core::SE3 true_pose(const LandmarkWorld3DOptions& o, int k) {
  const double s = 2.0 * kPi * o.laps * static_cast<double>(k) / static_cast<double>(o.poses);
  const Vector3 t(o.circle_radius_m * std::cos(s), o.circle_radius_m * std::sin(s),
                  o.climb_m * std::sin(3.0 * s / o.laps));
  const double yaw = s + kPi / 2.0;
  const double roll = o.attitude_amplitude_rad * std::sin(2.0 * s);
  const double pitch = o.attitude_amplitude_rad * std::cos(5.0 * s);
  const core::SO3 R = core::SO3::exp(Vector3(0, 0, yaw)) * core::SO3::exp(Vector3(0, pitch, 0)) *
                      core::SO3::exp(Vector3(roll, 0, 0));
  return core::SE3(R, t);
}

}  // namespace

bool LandmarkWorld3DOptions::is_valid(std::string* why) const {
  std::string problems;
  const auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
  if (poses < 2) add("poses must be > 1");
  if (laps < 1) add("laps must be >= 1");
  if (!(circle_radius_m > 0.0)) add("circle_radius_m must be > 0");
  if (!(climb_m >= 0.0) || !std::isfinite(attitude_amplitude_rad)) add("climb_m must be >= 0, the attitude amplitude finite");
  if (landmarks < 0) add("landmarks must be >= 0");
  if (!(extent_m > 0.0)) add("extent_m must be > 0");
  if (!(ring_half_width_m >= 0.0 && std::isfinite(ring_half_width_m))) add("ring_half_width_m must be >= 0");
  if (!(landmark_z_max_m > landmark_z_min_m)) add("landmark_z_max_m must be > landmark_z_min_m");
  if (!(max_range_m > 0.0)) add("max_range_m must be > 0");
  if (!(field_of_view_rad > 0.0 && field_of_view_rad <= 2.0 * kPi)) add("field_of_view_rad must be in (0, 2 pi]");
  for (const double sigma : {point_sigma_m, range_sigma_m, angle_sigma_rad, odometry_translation_sigma_m,
                             odometry_rotation_sigma_rad}) {
    if (!(sigma >= 0.0 && std::isfinite(sigma))) {
      add("noise standard deviations must be finite and >= 0");
      break;
    }
  }
  if (why != nullptr) *why = problems;
  return problems.empty();
}

LandmarkWorld3D simulate_landmark_world_3d(const LandmarkWorld3DOptions& options, std::uint64_t seed) {
  CAIRN_ASSERT(options.is_valid(nullptr), "simulate_landmark_world_3d: invalid options");
  LandmarkWorld3D world;
  world.sensor = options.sensor;
  Random placement(Random::derive_seed(seed, 1));
  Random odometry_noise(Random::derive_seed(seed, 2));
  Random observation_noise(Random::derive_seed(seed, 3));
  for (int l = 0; l < options.landmarks; ++l) {
    const double a = placement.uniform(-options.extent_m, options.extent_m);
    const double b = placement.uniform(-options.extent_m, options.extent_m);
    const double z = placement.uniform(options.landmark_z_min_m, options.landmark_z_max_m);
    if (options.ring_half_width_m > 0.0) {
      // a, b in [-E, E) mapped to an angle and a radius.
      const double angle = kPi * a / options.extent_m;
      const double radius = options.circle_radius_m + options.ring_half_width_m * b / options.extent_m;
      world.p_world.emplace_back(radius * std::cos(angle), radius * std::sin(angle), z);
    } else {
      world.p_world.emplace_back(a, b, z);
    }
  }
  for (int k = 0; k < options.poses; ++k) world.T_world_body.push_back(true_pose(options, k));

  const double st = options.odometry_translation_sigma_m;
  const double sr = options.odometry_rotation_sigma_rad;
  world.odometry_covariance.setZero();
  world.odometry_covariance.diagonal() << st * st, st * st, st * st, sr * sr, sr * sr, sr * sr;
  for (int k = 0; k + 1 < options.poses; ++k) {
    Vector6 n;
    for (int c = 0; c < 6; ++c) n(c) = odometry_noise.gaussian(c < 3 ? st : sr);
    world.odometry.push_back(world.T_world_body[k].inverse() * world.T_world_body[k + 1] * core::SE3::exp(n));
  }

  const bool point = options.sensor == LandmarkSensor3D::kPoint;
  world.observation_covariance.setZero();
  if (point) {
    world.observation_covariance.diagonal().setConstant(options.point_sigma_m * options.point_sigma_m);
  } else {
    const double sa = options.angle_sigma_rad;
    world.observation_covariance.diagonal() << options.range_sigma_m * options.range_sigma_m, sa * sa, sa * sa;
  }
  const double half_fov = options.field_of_view_rad / 2.0;
  for (std::size_t k = 0; k < world.T_world_body.size(); ++k) {
    const core::SE3 T_body_world = world.T_world_body[k].inverse();
    for (std::size_t l = 0; l < world.p_world.size(); ++l) {
      const Vector3 q = T_body_world.rotation_matrix() * world.p_world[l] + T_body_world.translation();
      const double r = q.norm();
      if (r > options.max_range_m || r < kMinRange) continue;
      if (std::acos(std::clamp(q.x() / r, -1.0, 1.0)) > half_fov) continue;
      LandmarkObservation3D observation{k, l, q};
      if (point) {
        for (int c = 0; c < 3; ++c) observation.z(c) += observation_noise.gaussian(options.point_sigma_m);
      } else {
        const double rho = std::hypot(q.x(), q.y());
        if (rho < 1e-3) continue;  // straight above or below: bearing undefined
        observation.z = Vector3(r + observation_noise.gaussian(options.range_sigma_m),
                                std::atan2(q.y(), q.x()) + observation_noise.gaussian(options.angle_sigma_rad),
                                std::atan2(q.z(), rho) + observation_noise.gaussian(options.angle_sigma_rad));
        observation.z.y() = std::remainder(observation.z.y(), 2.0 * kPi);
      }
      world.observations.push_back(observation);
    }
  }
  return world;
}

}  // namespace cairn::sim
