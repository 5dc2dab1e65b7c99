#pragma once
/// \file
/// A 2D world: wall segments, circles (pillars, posts) and point landmarks, all in the `world`
/// frame, metres. Worlds are plain data; builders live in world_builders.hpp and ray casting in
/// ray_cast.hpp.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/core/types.hpp"

namespace cairn::sim {

/// A wall from `a` to `b` (both ends in the world frame). Zero thickness; seen from both sides.
/// A glass pane (`glass`) is as solid as a wall for the robot and transparent to cameras; a LiDAR
/// beam returns from it near its normal, is mirrored at grazing incidence and passes through in
/// between (cast_lidar_ray, World's glass angles).
struct Segment {
  Vector2 a = Vector2::Zero();
  Vector2 b = Vector2::Zero();
  bool glass = false;
};

/// A solid disc: a pillar, a post or a person standing still.
struct Circle {
  Vector2 center = Vector2::Zero();
  double radius_m = 0.1;
};

/// A point feature with a known identity, seen by the range-bearing sensor. It does not block
/// rays (a landmark that should also appear in LiDAR scans needs a Circle at the same place).
struct Landmark {
  std::int64_t id = 0;
  Vector2 position = Vector2::Zero();
};

/// A person walking back and forth between `from` and `to` at constant speed, seen by the
/// LiDAR as a disc: the moving objects that leave ghost trails in maps. At time t (seconds) it
/// has walked s = speed * (t + phase) metres along the closed path from -> to -> from.
struct Walker {
  Vector2 from = Vector2::Zero();
  Vector2 to = Vector2::Zero();
  double speed_mps = 1.0;
  double radius_m = 0.25;
  double phase_s = 0.0;

  /// The disc at `time_s`.
  Circle at(double time_s) const;
};

/// Axis-aligned box, for images and sanity checks.
struct Bounds {
  Vector2 min = Vector2::Zero();
  Vector2 max = Vector2::Zero();
};

struct World {
  std::string name;
  std::vector<Segment> walls;
  std::vector<Circle> circles;
  std::vector<Landmark> landmarks;
  /// Moving people; ray casts see them at the scan's time (ideal_scan), nothing else does
  /// (clearance, landmark occlusion and the route ignore them).
  std::vector<Walker> walkers;

  /// Glass panes return a LiDAR beam within this angle of their normal, radians (a specular
  /// return straight back), and mirror it beyond glass_reflection_min_incidence_rad (glass's
  /// Fresnel reflectance rises steeply towards grazing incidence: about 4 % head-on, 9 % at 60
  /// deg, 39 % at 80 deg; one threshold in place of a probability keeps the simulation exact).
  double glass_return_max_incidence_rad = 0.2617993877991494;     // 15 deg
  double glass_reflection_min_incidence_rad = 1.0471975511965976;  // 60 deg
  /// Adds the wall a -> b.
  void add_wall(const Vector2& a, const Vector2& b) { walls.push_back({a, b}); }
  /// Adds the glass pane a -> b (Segment::glass).
  void add_glass(const Vector2& a, const Vector2& b) { walls.push_back({a, b, true}); }
  /// Adds the four walls of the rectangle [min.x, max.x] x [min.y, max.y].
  void add_rectangle(const Vector2& min, const Vector2& max);
  /// Adds a straight wall from a to b with the openings `gaps` left out. Each gap is
  /// (centre, width) measured in metres along a -> b from a; gaps must not overlap and must lie
  /// inside the wall (asserted: builders are code, not user input).
  void add_wall_with_gaps(const Vector2& a, const Vector2& b,
                          std::vector<std::pair<double, double>> gaps);

  /// The walkers as discs at `time_s`.
  std::vector<Circle> walkers_at(double time_s) const;
  /// Smallest box holding every wall, circle, landmark and walker path. Precondition: not empty.
  Bounds bounds() const;
  /// Distance from `point` to the nearest wall or circle surface (inf for an empty world).
  double clearance(const Vector2& point) const;
};

}  // namespace cairn::sim
