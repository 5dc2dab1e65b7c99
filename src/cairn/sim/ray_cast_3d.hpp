#pragma once
/// \file
/// Exact 3D ray casting: first hits of origin + t d (t >= 0, |d| = 1) with the ground plane,
/// axis-aligned boxes (slab method: Kay & Kajiya, SIGGRAPH 1986) and vertical cylinders (a
/// quadratic in x, y for the side, two planes for the caps). A ray starting inside a solid hits
/// its far side.

#include <optional>

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

}  // namespace cairn::sim
