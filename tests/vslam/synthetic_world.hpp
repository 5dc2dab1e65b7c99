#pragma once
/// \file
/// A synthetic world for visual-SLAM tests with exact ground truth: axis-aligned planar quads
/// (walls, floors, ceilings of rooms and corridors) carrying procedural grey textures, rendered by
/// ray casting into a rectified stereo pair (and a depth image) at any T_world_camera.
///
/// Textures are functions of a surface's coordinates relative to its `texture_origin`, seeded by
/// `texture.seed`: two surfaces with the same seed and the same origin-relative extent look
/// identical wherever they stand (aliasing), and a surface with `texture.textured == false` is a
/// flat grey (no corner at all). The texture is a "Mondrian" of 0.2 m cells, each with a random
/// background and three random rectangles or discs of random grey: every cell has corners and
/// T-junctions at several scales (ORB finds its 2000 features in a room view), and the ORB
/// descriptors of different seeds differ.
///
/// Frames: world and camera as cairn's (camera x right, y down, z forward); the world's y axis
/// points down too, so a camera with the identity rotation looks along +z with x to its right.
/// Rendering: one ray per pixel finds the nearest quad, then the texture is averaged over 2 x 2
/// sub-pixel samples on that quad's plane (anti-aliasing of the texture; quad silhouettes are
/// not anti-aliased).

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/io/image_sequence.hpp"

namespace cairn::test {

struct SurfaceTexture {
  std::uint64_t seed = 1;
  bool textured = true;  ///< false: flat `grey`
  double grey = 128.0;   ///< grey level of a texture-less surface, [0, 255]
};

/// An axis-aligned rectangle: `lower` and `upper` agree in the coordinate `normal_axis`.
struct Surface {
  int normal_axis = 2;  ///< 0 x, 1 y, 2 z
  Eigen::Vector3d lower = Eigen::Vector3d::Zero();
  Eigen::Vector3d upper = Eigen::Vector3d::Zero();
  SurfaceTexture texture;
  /// Texture coordinates are measured from here (metres, along the two in-plane axes).
  Eigen::Vector3d texture_origin = Eigen::Vector3d::Zero();
};

/// Rectified stereo pinhole camera; the right camera sits at +baseline along the left's x.
struct StereoCamera {
  double fx = 450.0, fy = 450.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;
  double baseline_m = 0.12;
  double depth_units_per_m = 5000.0;  ///< for render_depth (TUM's scale)
  io::CameraCalibration calibration() const;
};

/// Textures of a box room's six faces (walls by the axis and side they close).
struct RoomTextures {
  SurfaceTexture x_low, x_high, y_low, y_high, z_low, z_high;
};

class SyntheticWorld {
 public:
  void add(const Surface& surface) { surfaces_.push_back(surface); }
  /// A wall in the plane coord[normal_axis] = lower[normal_axis] spanning [lower, upper], with an
  /// optional rectangular opening [opening_lower, opening_upper] (same plane) cut out of it.
  void add_wall(int normal_axis, const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, const SurfaceTexture& texture,
                const Eigen::Vector3d& texture_origin, const Eigen::Vector3d* opening_lower = nullptr,
                const Eigen::Vector3d* opening_upper = nullptr);
  /// A closed box [lower, upper] seen from inside, textures measured from `texture_origin`
  /// (give two rooms of the same size the same textures and each its own lower corner as origin,
  /// and they look the same). Doors: openings in the z_low and z_high walls, |x - door_center_x|
  /// < door_half_width_m and y > door_top_y (y points down), when door_half_width_m > 0.
  void add_room(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, const RoomTextures& textures,
                const Eigen::Vector3d& texture_origin, double door_half_width_m = 0.0, double door_top_y = 0.0,
                double door_center_x = 0.0, bool door_low = true, bool door_high = true);
  /// A corridor along z: side walls at lower.x / upper.x, floor, ceiling; open ends.
  void add_corridor_z(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, std::uint64_t seed);

  const std::vector<Surface>& surfaces() const { return surfaces_; }

  /// 8-bit grey image seen by a pinhole camera at T_world_camera (rays that hit nothing: black).
  cv::Mat render(const core::SE3& T_world_camera, const StereoCamera& camera) const;
  /// The left image at T_world_left and the right one at T_world_left * (I, (baseline, 0, 0)).
  std::pair<cv::Mat, cv::Mat> render_stereo(const core::SE3& T_world_left, const StereoCamera& camera) const;
  /// 16-bit depth (z in the camera, x depth_units_per_m; 0 where nothing or beyond 65535 units).
  cv::Mat render_depth(const core::SE3& T_world_camera, const StereoCamera& camera) const;
  /// Fraction of the pixels whose ray hits a textured surface (0: a blank view).
  double textured_fraction(const core::SE3& T_world_camera, const StereoCamera& camera) const;

 private:
  std::vector<Surface> surfaces_;
};

/// Grey value [0, 255] of the procedural texture at surface coordinates (u, v) metres.
double texture_value(std::uint64_t seed, double u, double v);

/// Camera at `position` looking along +z turned by yaw about the (downward) world y axis
/// (positive yaw turns towards +x) and pitched by `pitch_rad` (positive: looks up).
core::SE3 camera_pose(const Eigen::Vector3d& position, double yaw_rad, double pitch_rad = 0.0);

/// Frames from `from` to `to` about `step_m` apart (both ends included) with a smooth sway: yaw
/// yaw_rad + yaw_amplitude_rad sin(2 pi s / period_m) and a lateral offset lateral_amplitude_m
/// sin(2 pi s / (1.7 period_m)) along x, s the distance travelled.
std::vector<core::SE3> walk(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double step_m, double yaw_rad = 0.0,
                            double yaw_amplitude_rad = 0.0, double lateral_amplitude_m = 0.0, double period_m = 4.0);
/// Turning on the spot from yaw_from to yaw_to by about step_rad per frame (both ends included).
std::vector<core::SE3> turn(const Eigen::Vector3d& position, double yaw_from_rad, double yaw_to_rad, double step_rad);
/// `count` copies of a pose (the camera standing still).
std::vector<core::SE3> hold(const core::SE3& pose, int count);
/// Appends b to a, dropping b's first pose when it equals a's last.
void append(std::vector<core::SE3>& a, const std::vector<core::SE3>& b);

}  // namespace cairn::test
