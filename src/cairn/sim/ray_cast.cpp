#include "cairn/sim/ray_cast.hpp"

#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::sim {

std::optional<double> intersect(const Vector2& origin, const Vector2& direction, const Segment& wall) {
  // origin + t d = a + u e, e = b - a. In matrix form [d, -e] (t, u)^T = a - origin.
  const Vector2 e = wall.b - wall.a;
  const Vector2 w = wall.a - origin;
  const double det = direction.x() * (-e.y()) - direction.y() * (-e.x());  // cross(d, -e)
  if (det == 0.0) return std::nullopt;
  const double t = (w.x() * (-e.y()) - w.y() * (-e.x())) / det;  // cross(w, -e) / det
  const double u = (direction.x() * w.y() - direction.y() * w.x()) / det;  // cross(d, w) / det
  if (t < 0.0 || u < 0.0 || u > 1.0) return std::nullopt;
  return t;
}

std::optional<double> intersect(const Vector2& origin, const Vector2& direction, const Circle& circle) {
  // |m + t d|^2 = r^2 with m = origin - c and |d| = 1: t^2 + 2 b t + c = 0, b = m.d, c = |m|^2 - r^2.
  const Vector2 m = origin - circle.center;
  const double b = m.dot(direction);
  const double c = m.squaredNorm() - circle.radius_m * circle.radius_m;
  if (c > 0.0 && b > 0.0) return std::nullopt;  // outside and pointing away
  const double discriminant = b * b - c;
  if (discriminant < 0.0) return std::nullopt;
  const double root = std::sqrt(discriminant);
  const double near = -b - root;
  if (near >= 0.0) return near;
  const double far = -b + root;  // origin inside (c <= 0): leave through the far side
  if (far >= 0.0) return far;
  return std::nullopt;
}

namespace {

struct Nearest {
  double t = 0.0;
  const Segment* wall = nullptr;  ///< null for a circle
};

// The nearest wall or circle (of the world and `moving`) within max_range_m; glass panes only
// when `with_glass`, and never `skip` (the pane a bounce starts on).
std::optional<Nearest> nearest_surface(const World& world, const Vector2& origin, const Vector2& direction, double max_range_m,
                                       const std::vector<Circle>& moving, bool with_glass, const Segment* skip) {
  Nearest best{max_range_m, nullptr};
  bool hit = false;
  for (const auto& wall : world.walls) {
    if ((wall.glass && !with_glass) || &wall == skip) continue;
    if (const auto t = intersect(origin, direction, wall); t && *t <= best.t) {
      best = {*t, &wall};
      hit = true;
    }
  }
  for (const auto* circles : {&world.circles, &moving}) {
    for (const auto& circle : *circles) {
      if (const auto t = intersect(origin, direction, circle); t && *t <= best.t) {
        best = {*t, nullptr};
        hit = true;
      }
    }
  }
  if (!hit) return std::nullopt;
  return best;
}

}  // namespace

std::optional<RayHit> cast_ray(const World& world, const Vector2& origin, const Vector2& direction,
                               double max_range_m, const std::vector<Circle>& moving) {
  CAIRN_ASSERT(std::abs(direction.squaredNorm() - 1.0) < 1e-9, "cast_ray: the direction must be a unit vector");
  const auto hit = nearest_surface(world, origin, direction, max_range_m, moving, false, nullptr);
  if (!hit) return std::nullopt;
  return RayHit{hit->t, origin + hit->t * direction};
}

std::optional<RayHit> cast_lidar_ray(const World& world, const Vector2& origin, const Vector2& direction,
                                     double max_range_m, const std::vector<Circle>& moving) {
  CAIRN_ASSERT(std::abs(direction.squaredNorm() - 1.0) < 1e-9, "cast_lidar_ray: the direction must be a unit vector");
  const double return_min_cos = std::cos(world.glass_return_max_incidence_rad);
  const double reflect_max_cos = std::cos(world.glass_reflection_min_incidence_rad);
  Vector2 from = origin, heading = direction;
  const Segment* pane = nullptr;
  double travelled = 0.0;
  for (int surface = 0; surface < 4; ++surface) {  // at most three panes on the way
    const auto hit = nearest_surface(world, from, heading, max_range_m - travelled, moving, true, pane);
    if (!hit) return std::nullopt;
    travelled += hit->t;
    const RayHit reading{travelled, origin + travelled * direction};  // along the beam as emitted
    if (hit->wall == nullptr || !hit->wall->glass) return reading;
    // |cos| of the angle between the beam and the pane's normal: |(b - a) x heading| / |b - a|.
    const Vector2 e = hit->wall->b - hit->wall->a;
    const double cos_incidence = std::abs(e.x() * heading.y() - e.y() * heading.x()) / e.norm();
    if (cos_incidence >= return_min_cos) return reading;
    from += hit->t * heading;
    if (cos_incidence <= reflect_max_cos) {
      const Vector2 normal = Vector2(-e.y(), e.x()).normalized();
      heading -= 2.0 * heading.dot(normal) * normal;  // mirror
    }
    pane = hit->wall;
  }
  return std::nullopt;
}

bool line_of_sight(const World& world, const Vector2& from, const Vector2& to, double margin_m) {
  const Vector2 delta = to - from;
  const double distance = delta.norm();
  if (distance <= margin_m) return true;
  const auto hit = cast_ray(world, from, delta / distance, distance - margin_m);
  return !hit.has_value();
}

}  // namespace cairn::sim
