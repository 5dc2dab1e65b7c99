#pragma once
/// \file
/// Exact ray casting against a World: the first intersection of a ray with wall segments and
/// circles, computed in closed form (no grid, no marching).

#include <optional>
#include <vector>

#include "cairn/core/types.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// Where a ray first hits something.
struct RayHit {
  /// Distance from the origin along the unit direction, metres.
  double range_m = 0.0;
  /// Hit point in the world frame.
  Vector2 point = Vector2::Zero();
};

/// Distance along the ray origin + t * direction (t >= 0, `direction` a unit vector) to segment
/// `wall`, or nullopt when the ray misses it. Solves origin + t d = a + u (b - a) for (t, u)
/// by Cramer's rule, accepting u in [0, 1] (ends included) and t >= 0. A ray parallel to the
/// segment (including along it) counts as a miss: a zero-thickness wall seen edge-on has no
/// surface to reflect from.
std::optional<double> intersect(const Vector2& origin, const Vector2& direction, const Segment& wall);

/// Distance to the first crossing of the circle's boundary: the smaller root t of
/// |origin + t d - c|^2 = r^2 that is >= 0. A ray starting inside the circle hits the far side.
std::optional<double> intersect(const Vector2& origin, const Vector2& direction, const Circle& circle);

/// The nearest hit over all walls and circles of `world`, and the `moving` discs (walkers at the
/// scan's time, see World::walkers_at), within max_range_m, or nullopt: what is in sight. Glass
/// panes are transparent here (cameras, landmark sensors, line of sight).
/// Precondition: |direction| = 1 (asserted to 1e-9).
std::optional<RayHit> cast_ray(const World& world, const Vector2& origin, const Vector2& direction,
                               double max_range_m, const std::vector<Circle>& moving = {});

/// What a laser scanner's beam reads: as cast_ray, but a glass pane (Segment::glass) met within
/// World::glass_return_max_incidence_rad of its normal returns the beam, one met beyond
/// World::glass_reflection_min_incidence_rad mirrors it, and the beam passes through at angles in
/// between. A mirrored beam's reading is its whole path length along the direction it left in: a
/// phantom point behind the pane, the mirror image of what the reflection hit (the artefact of
/// glass facades in laser scans). At most three panes on one beam; max_range_m bounds the path.
std::optional<RayHit> cast_lidar_ray(const World& world, const Vector2& origin, const Vector2& direction,
                                     double max_range_m, const std::vector<Circle>& moving = {});

/// True when nothing in `world` lies strictly between `from` and `to` (line of sight), up to
/// `margin_m` before `to` (so a landmark on a wall is still visible).
bool line_of_sight(const World& world, const Vector2& from, const Vector2& to, double margin_m = 1e-6);

}  // namespace cairn::sim
