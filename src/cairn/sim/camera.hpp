#pragma once
/// \file
/// A pinhole camera observing the 3D point landmarks of a World3D, with identities (for
/// checking data association). Camera frame: z along the optical axis, x right, y down (the
/// OpenCV convention). Mounted `mount_height_m` above the body origin looking along the body's
/// x axis: R_body_camera has columns x_c = -y_b, y_c = -z_b, z_c = x_b.
///
/// A landmark p_c = (x, y, z) in the camera frame is observed when 0.1 m < z, |p_c| <=
/// max_range_m, its projection lies inside the image and nothing in the world lies on the segment
/// between the camera centre and the landmark (up to 1 cm before it). Observation:
///   u = fx x / z + cx + pixel_sigma n1,   v = fy y / z + cy + pixel_sigma n2,   n1, n2 ~ N(0, 1).
/// Each landmark passing the geometric tests draws two Gaussian variates.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/world_3d.hpp"

namespace cairn::sim {

struct CameraOptions {
  /// Intrinsics, pixels; image size, pixels.
  double fx = 500.0;
  double fy = 500.0;
  double cx = 320.0;
  double cy = 240.0;
  int width = 640;
  int height = 480;
  double pixel_sigma = 0.5;
  double max_range_m = 40.0;
  double mount_height_m = 1.5;
  /// Time between images, seconds: a multiple of the trajectory's sample period.
  double period_s = 0.1;

  bool is_valid(std::string* why) const;
  core::SE3 T_body_camera() const;
};

struct CameraObservation {
  core::Timestamp stamp;
  std::int64_t landmark_id = 0;
  double u_px = 0.0;
  double v_px = 0.0;
};

std::vector<CameraObservation> observe_with_camera(const World3D& world, const core::SE3& T_world_camera,
                                                   core::Timestamp stamp, const CameraOptions& options,
                                                   Random& random);

}  // namespace cairn::sim
