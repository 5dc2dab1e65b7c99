#pragma once
/// \file
/// Exact 3D ray casting: first hits of origin + t d (t >= 0, |d| = 1) with the ground plane,
/// axis-aligned boxes (slab method: Kay & Kajiya, SIGGRAPH 1986) and vertical cylinders (a
/// quadratic in x, y for the side, two planes for the caps). A ray starting inside a solid hits
/// its far side.

#include <optional>
#include <vector>

#include "cairn/sim/world_3d.hpp"

namespace cairn::sim {

/// The plane z = 0 seen from above: hit only when origin.z > 0 and d.z < 0.
std::optional<double> intersect_ground(const Vector3& origin, const Vector3& direction);
std::optional<double> intersect(const Vector3& origin, const Vector3& direction, const Box& box);
std::optional<double> intersect(const Vector3& origin, const Vector3& direction, const Cylinder& cylinder);

/// Nearest hit distance within max_range_m over the whole world, or nullopt.
/// Precondition: |direction| = 1 (asserted to 1e-9).
std::optional<double> cast_ray(const World3D& world, const Vector3& origin, const Vector3& direction,
                               double max_range_m);

/// The part of `world` that can be hit from within `radius_m` of `center` (horizontal distance):
/// a cheap per-scan cull so each ray tests only nearby objects. Landmarks are not copied.
World3D nearby(const World3D& world, const Vector2& center, double radius_m);

/// The boxes and cylinders of a world sorted into azimuth sectors as seen from anywhere within
/// `motion_radius_m` (horizontally) of `center`, so a ray tests only the objects of its own
/// sector: the same first hit as cast_ray, several times faster for a spinning LiDAR in a big
/// world. An object goes into every sector its footprint can subtend from such an origin:
/// the corners' (a box) or the tangents' (a cylinder) azimuths seen from `center`, widened by
/// asin(motion_radius / distance) (the largest change of direction to a point at that distance
/// when the origin moves by motion_radius); objects within motion_radius of `center` go into
/// every sector. The ground is always tested; moving boxes are not indexed.
class AzimuthIndex {
 public:
  AzimuthIndex(const World3D& world, const Vector2& center, double motion_radius_m, int sectors = 720);

  /// As cast_ray(world, ...). Precondition: |origin_xy - center| <= motion_radius_m, |direction| = 1.
  std::optional<double> cast(const Vector3& origin, const Vector3& direction, double max_range_m) const;

 private:
  bool ground_ = true;
  double sector_width_rad_ = 0.0;
  /// Per sector, the objects to test (copies, in the world's order).
  std::vector<std::vector<Box>> boxes_;
  std::vector<std::vector<Cylinder>> cylinders_;
};

}  // namespace cairn::sim
