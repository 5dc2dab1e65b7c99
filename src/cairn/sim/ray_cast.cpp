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

std::optional<RayHit> cast_ray(const World& world, const Vector2& origin, const Vector2& direction,
                               double max_range_m, const std::vector<Circle>& moving) {
  CAIRN_ASSERT(std::abs(direction.squaredNorm() - 1.0) < 1e-9, "cast_ray: the direction must be a unit vector");
  double best = max_range_m;
  bool hit = false;
  for (const auto& wall : world.walls) {
    if (const auto t = intersect(origin, direction, wall); t && *t <= best) {
      best = *t;
      hit = true;
    }
  }
  for (const auto* circles : {&world.circles, &moving}) {
    for (const auto& circle : *circles) {
      if (const auto t = intersect(origin, direction, circle); t && *t <= best) {
        best = *t;
        hit = true;
      }
    }
  }
  if (!hit) return std::nullopt;
  return RayHit{best, origin + best * direction};
}

bool line_of_sight(const World& world, const Vector2& from, const Vector2& to, double margin_m) {
  const Vector2 delta = to - from;
  const double distance = delta.norm();
  if (distance <= margin_m) return true;
  const auto hit = cast_ray(world, from, delta / distance, distance - margin_m);
  return !hit.has_value();
}

}  // namespace cairn::sim
