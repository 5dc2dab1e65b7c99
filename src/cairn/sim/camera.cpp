#include "cairn/sim/camera.hpp"

#include <sstream>

#include "cairn/sim/ray_cast_3d.hpp"

namespace cairn::sim {

bool CameraOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  if (!(fx > 0.0 && fy > 0.0)) problems << "fx and fy must be > 0; ";
  if (width < 1 || height < 1) problems << "width and height must be >= 1; ";
  if (!(pixel_sigma >= 0.0)) problems << "pixel_sigma must be >= 0; ";
  if (!(max_range_m > 0.1)) problems << "max_range_m must be > 0.1; ";
  if (!(mount_height_m > 0.0)) problems << "mount_height_m must be > 0; ";
  if (!(period_s > 0.0)) problems << "period_s must be > 0; ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

core::SE3 CameraOptions::T_body_camera() const {
  Matrix3 R_body_camera;
  R_body_camera.col(0) = Vector3(0, -1, 0);
  R_body_camera.col(1) = Vector3(0, 0, -1);
  R_body_camera.col(2) = Vector3(1, 0, 0);
  return core::SE3(Quaternion(R_body_camera), Vector3(0, 0, mount_height_m));
}

std::vector<CameraObservation> observe_with_camera(const World3D& world, const core::SE3& T_world_camera,
                                                   core::Timestamp stamp, const CameraOptions& options,
                                                   Random& random) {
  std::vector<CameraObservation> observations;
  const core::SE3 T_camera_world = T_world_camera.inverse();
  const Vector3 centre = T_world_camera.translation();
  for (const auto& landmark : world.landmarks) {
    const Vector3 p = T_camera_world * landmark.position;
    if (!(p.z() > 0.1) || p.norm() > options.max_range_m) continue;
    const double u = options.fx * p.x() / p.z() + options.cx;
    const double v = options.fy * p.y() / p.z() + options.cy;
    if (u < 0.0 || v < 0.0 || u >= options.width || v >= options.height) continue;
    const Vector3 to_landmark = landmark.position - centre;
    const double distance = to_landmark.norm();
    if (cast_ray(world, centre, to_landmark / distance, distance - 0.01)) continue;  // occluded
    const double n1 = random.gaussian(options.pixel_sigma);
    const double n2 = random.gaussian(options.pixel_sigma);
    observations.push_back({stamp, landmark.id, u + n1, v + n2});
  }
  return observations;
}

}  // namespace cairn::sim
