#include "cairn/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cairn/core/assert.hpp"

namespace cairn::sim {

void World::add_rectangle(const Vector2& min, const Vector2& max) {
  add_wall({min.x(), min.y()}, {max.x(), min.y()});
  add_wall({max.x(), min.y()}, {max.x(), max.y()});
  add_wall({max.x(), max.y()}, {min.x(), max.y()});
  add_wall({min.x(), max.y()}, {min.x(), min.y()});
}

void World::add_wall_with_gaps(const Vector2& a, const Vector2& b,
                               std::vector<std::pair<double, double>> gaps) {
  const double length = (b - a).norm();
  CAIRN_ASSERT(length > 0.0, "add_wall_with_gaps: a wall needs two distinct ends");
  const Vector2 direction = (b - a) / length;
  std::sort(gaps.begin(), gaps.end());
  double start = 0.0;
  for (const auto& [centre, width] : gaps) {
    const double gap_begin = centre - 0.5 * width;
    const double gap_end = centre + 0.5 * width;
    CAIRN_ASSERT(gap_begin >= start && gap_end <= length, "add_wall_with_gaps: gaps overlap or leave the wall");
    if (gap_begin > start) add_wall(a + start * direction, a + gap_begin * direction);
    start = gap_end;
  }
  if (start < length) add_wall(a + start * direction, b);
}

Circle Walker::at(double time_s) const {
  const double length = (to - from).norm();
  if (length == 0.0 || speed_mps == 0.0) return {from, radius_m};
  const double s = std::fmod(std::abs(speed_mps * (time_s + phase_s)), 2.0 * length);
  const Vector2 direction = (to - from) / length;
  return {s < length ? Vector2(from + s * direction) : Vector2(to - (s - length) * direction), radius_m};
}

std::vector<Circle> World::walkers_at(double time_s) const {
  std::vector<Circle> discs;
  discs.reserve(walkers.size());
  for (const auto& walker : walkers) discs.push_back(walker.at(time_s));
  return discs;
}

Bounds World::bounds() const {
  CAIRN_ASSERT(!walls.empty() || !circles.empty() || !landmarks.empty() || !walkers.empty(), "World::bounds of an empty world");
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Bounds box{Vector2(kInf, kInf), Vector2(-kInf, -kInf)};
  auto grow = [&](const Vector2& p) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  };
  for (const auto& wall : walls) {
    grow(wall.a);
    grow(wall.b);
  }
  for (const auto& circle : circles) {
    grow(circle.center - Vector2::Constant(circle.radius_m));
    grow(circle.center + Vector2::Constant(circle.radius_m));
  }
  for (const auto& landmark : landmarks) grow(landmark.position);
  for (const auto& walker : walkers) {
    grow(walker.from);
    grow(walker.to);
  }
  return box;
}

double World::clearance(const Vector2& point) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& wall : walls) {
    const Vector2 ab = wall.b - wall.a;
    const double length_squared = ab.squaredNorm();
    const double t = length_squared > 0.0 ? std::clamp((point - wall.a).dot(ab) / length_squared, 0.0, 1.0) : 0.0;
    best = std::min(best, (wall.a + t * ab - point).norm());
  }
  for (const auto& circle : circles) best = std::min(best, (point - circle.center).norm() - circle.radius_m);
  return best;
}

}  // namespace cairn::sim
