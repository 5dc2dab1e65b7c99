#include "cairn/sim/ray_cast_3d.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "cairn/core/assert.hpp"

namespace cairn::sim {

std::optional<double> intersect_ground(const Vector3& origin, const Vector3& direction) {
  if (!(origin.z() > 0.0) || !(direction.z() < 0.0)) return std::nullopt;
  return -origin.z() / direction.z();
}

std::optional<double> intersect(const Vector3& origin, const Vector3& direction, const Box& box) {
  double t_enter = -std::numeric_limits<double>::infinity();
  double t_exit = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    const double o = origin[axis];
    const double d = direction[axis];
    if (d == 0.0) {
      if (o < box.min[axis] || o > box.max[axis]) return std::nullopt;
      continue;
    }
    double t1 = (box.min[axis] - o) / d;
    double t2 = (box.max[axis] - o) / d;
    if (t1 > t2) std::swap(t1, t2);
    t_enter = std::max(t_enter, t1);
    t_exit = std::min(t_exit, t2);
  }
  if (t_exit < t_enter || t_exit < 0.0) return std::nullopt;
  return t_enter >= 0.0 ? t_enter : t_exit;
}

std::optional<double> intersect(const Vector3& origin, const Vector3& direction, const Cylinder& cylinder) {
  std::optional<double> best;
  auto consider = [&](double t) {
    if (t >= 0.0 && (!best || t < *best)) best = t;
  };
  // Side: |m + t d_xy|^2 = r^2 with m = origin_xy - centre.
  const Vector2 m = origin.head<2>() - cylinder.center;
  const Vector2 d = direction.head<2>();
  const double a = d.squaredNorm();
  if (a > 0.0) {
    const double b = m.dot(d);
    const double c = m.squaredNorm() - cylinder.radius_m * cylinder.radius_m;
    const double discriminant = b * b - a * c;
    if (discriminant >= 0.0) {
      const double root = std::sqrt(discriminant);
      for (double t : {(-b - root) / a, (-b + root) / a}) {
        const double z = origin.z() + t * direction.z();
        if (z >= cylinder.z_min_m && z <= cylinder.z_max_m) consider(t);
      }
    }
  }
  // Caps.
  if (direction.z() != 0.0) {
    for (double z_cap : {cylinder.z_min_m, cylinder.z_max_m}) {
      const double t = (z_cap - origin.z()) / direction.z();
      const Vector2 p = origin.head<2>() + t * d;
      if ((p - cylinder.center).squaredNorm() <= cylinder.radius_m * cylinder.radius_m) consider(t);
    }
  }
  return best;
}

std::optional<double> cast_ray(const World3D& world, const Vector3& origin, const Vector3& direction,
                               double max_range_m) {
  CAIRN_ASSERT(std::abs(direction.squaredNorm() - 1.0) < 1e-9, "cast_ray: the direction must be a unit vector");
  double best = max_range_m;
  bool hit = false;
  auto consider = [&](const std::optional<double>& t) {
    if (t && *t <= best) {
      best = *t;
      hit = true;
    }
  };
  if (world.ground) consider(intersect_ground(origin, direction));
  for (const auto& box : world.boxes) consider(intersect(origin, direction, box));
  for (const auto& cylinder : world.cylinders) consider(intersect(origin, direction, cylinder));
  if (!hit) return std::nullopt;
  return best;
}

World3D nearby(const World3D& world, const Vector2& center, double radius_m) {
  World3D out;
  out.name = world.name;
  out.ground = world.ground;
  for (const auto& box : world.boxes) {
    // Horizontal distance from the centre to the box footprint.
    const Vector2 lo = box.min.head<2>();
    const Vector2 hi = box.max.head<2>();
    const Vector2 closest = center.cwiseMax(lo).cwiseMin(hi);
    if ((closest - center).norm() <= radius_m) out.boxes.push_back(box);
  }
  for (const auto& cylinder : world.cylinders) {
    if ((cylinder.center - center).norm() - cylinder.radius_m <= radius_m) out.cylinders.push_back(cylinder);
  }
  return out;
}

namespace {

/// Sector of an azimuth in [-pi, pi].
int sector_of(double azimuth_rad, double width_rad, int sectors) {
  const int s = static_cast<int>(std::floor((azimuth_rad + std::numbers::pi) / width_rad));
  return std::clamp(s, 0, sectors - 1);
}

}  // namespace

AzimuthIndex::AzimuthIndex(const World3D& world, const Vector2& center, double motion_radius_m, int sectors)
    : ground_(world.ground),
      sector_width_rad_(2.0 * std::numbers::pi / sectors),
      boxes_(static_cast<std::size_t>(sectors)),
      cylinders_(static_cast<std::size_t>(sectors)) {
  CAIRN_ASSERT(sectors >= 1 && motion_radius_m >= 0.0, "AzimuthIndex: need sectors >= 1 and motion_radius_m >= 0");
  constexpr double kSlack = 1e-9;
  // Adds `object` to every sector meeting [middle - below, middle + above] (radians), or to all.
  auto insert = [&](auto& lists, const auto& object, bool everywhere, double middle, double below, double above) {
    if (everywhere || below + above + 2.0 * sector_width_rad_ >= 2.0 * std::numbers::pi) {
      for (auto& list : lists) list.push_back(object);
      return;
    }
    const int first = static_cast<int>(std::floor((middle - below + std::numbers::pi) / sector_width_rad_));
    const int last = static_cast<int>(std::floor((middle + above + std::numbers::pi) / sector_width_rad_));
    for (int s = first; s <= last; ++s) lists[static_cast<std::size_t>(((s % sectors) + sectors) % sectors)].push_back(object);
  };
  for (const auto& box : world.boxes) {
    const Vector2 lo = box.min.head<2>();
    const Vector2 hi = box.max.head<2>();
    const double distance = (center.cwiseMax(lo).cwiseMin(hi) - center).norm();
    if (distance <= motion_radius_m + 1e-6) {
      insert(boxes_, box, true, 0.0, 0.0, 0.0);
      continue;
    }
    // The footprint does not contain `center`, so its corners span less than pi around the
    // direction to its middle.
    const Vector2 to_middle = 0.5 * (lo + hi) - center;
    const double middle = std::atan2(to_middle.y(), to_middle.x());
    double below = 0.0;
    double above = 0.0;
    for (const Vector2& corner : {lo, hi, Vector2(lo.x(), hi.y()), Vector2(hi.x(), lo.y())}) {
      const Vector2 v = corner - center;
      const double relative = std::atan2(to_middle.x() * v.y() - to_middle.y() * v.x(), to_middle.dot(v));
      below = std::max(below, -relative);
      above = std::max(above, relative);
    }
    const double widen = std::asin(std::min(1.0, motion_radius_m / distance)) + kSlack;
    insert(boxes_, box, false, middle, below + widen, above + widen);
  }
  for (const auto& cylinder : world.cylinders) {
    const Vector2 to_center = cylinder.center - center;
    const double distance = to_center.norm();
    if (distance - cylinder.radius_m <= motion_radius_m + 1e-6) {
      insert(cylinders_, cylinder, true, 0.0, 0.0, 0.0);
      continue;
    }
    const double half = std::asin(std::min(1.0, cylinder.radius_m / distance)) +
                        std::asin(std::min(1.0, motion_radius_m / (distance - cylinder.radius_m))) + kSlack;
    insert(cylinders_, cylinder, false, std::atan2(to_center.y(), to_center.x()), half, half);
  }
}

std::optional<double> AzimuthIndex::cast(const Vector3& origin, const Vector3& direction, double max_range_m) const {
  const int sectors = static_cast<int>(boxes_.size());
  const auto s = static_cast<std::size_t>(sector_of(std::atan2(direction.y(), direction.x()), sector_width_rad_, sectors));
  // As cast_ray: the same tests in the same order, over this sector's objects only.
  double best = max_range_m;
  bool hit = false;
  auto consider = [&](const std::optional<double>& t) {
    if (t && *t <= best) {
      best = *t;
      hit = true;
    }
  };
  if (ground_) consider(intersect_ground(origin, direction));
  for (const auto& box : boxes_[s]) consider(intersect(origin, direction, box));
  for (const auto& cylinder : cylinders_[s]) consider(intersect(origin, direction, cylinder));
  if (!hit) return std::nullopt;
  return best;
}

}  // namespace cairn::sim
