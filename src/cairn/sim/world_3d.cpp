#include "cairn/sim/world_3d.hpp"

#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::sim {

Box MovingBox::at(double time_s) const {
  CAIRN_ASSERT(path.size() >= 2, "MovingBox::at: the path needs two vertices");
  double perimeter = 0.0;
  for (std::size_t i = 0; i < path.size(); ++i) perimeter += (path[(i + 1) % path.size()] - path[i]).norm();
  CAIRN_ASSERT(perimeter > 0.0, "MovingBox::at: the path has no length");
  double s = std::fmod(phase_m + speed_mps * time_s, perimeter);
  if (s < 0.0) s += perimeter;
  std::size_t edge = 0;
  for (;; edge = (edge + 1) % path.size()) {
    const double length = (path[(edge + 1) % path.size()] - path[edge]).norm();
    if (s <= length || edge + 1 == path.size()) break;
    s -= length;
  }
  const Vector2 a = path[edge];
  const Vector2 b = path[(edge + 1) % path.size()];
  const Vector2 along = (b - a).normalized();
  const Vector2 across(-along.y(), along.x());
  const Vector2 center = a + std::min(s, (b - a).norm()) * along;
  // Half extents of the rotated footprint's bounding box.
  const Vector2 half = 0.5 * length_m * along.cwiseAbs() + 0.5 * width_m * across.cwiseAbs();
  return Box{Vector3(center.x() - half.x(), center.y() - half.y(), 0.0),
             Vector3(center.x() + half.x(), center.y() + half.y(), height_m)};
}

}  // namespace cairn::sim
