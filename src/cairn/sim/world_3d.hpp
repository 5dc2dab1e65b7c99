#pragma once
/// \file
/// A 3D world: the ground plane z = 0, axis-aligned boxes (buildings, parked cars) and vertical
/// cylinders (poles, tree trunks and crowns), all in the `world` frame (z up), metres; plus
/// point landmarks with identities for the camera; and boxes that move (cars in traffic). Ray
/// casting: ray_cast_3d.hpp.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/types.hpp"

namespace cairn::sim {

struct Box {
  Vector3 min = Vector3::Zero();
  Vector3 max = Vector3::Zero();
};

/// A vertical solid cylinder: |xy - center| <= radius, z in [z_min, z_max].
struct Cylinder {
  Vector2 center = Vector2::Zero();
  double radius_m = 0.1;
  double z_min_m = 0.0;
  double z_max_m = 1.0;
};

struct Landmark3D {
  std::int64_t id = 0;
  Vector3 position = Vector3::Zero();
};

/// A box of fixed size driving at constant speed around a closed polygon (a car in traffic).
/// At time t its centre is s = phase_m + speed_mps t metres along the polygon (wrapping; the
/// last vertex joins the first), its length along the current edge and its width across it;
/// it turns instantly at the vertices. The box is the axis-aligned bounding box of that
/// footprint, z in [0, height_m]: exact for axis-aligned edges (the simulated streets).
struct MovingBox {
  std::vector<Vector2> path;
  double length_m = 4.5;
  double width_m = 1.8;
  double height_m = 1.5;
  double speed_mps = 5.0;
  double phase_m = 0.0;

  /// The box at `time_s`. Precondition: path has >= 2 distinct vertices.
  Box at(double time_s) const;
};

struct World3D {
  std::string name;
  /// Whether the plane z = 0 is solid (seen from above).
  bool ground = true;
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<Landmark3D> landmarks;
  /// Moving objects: the spinning LiDAR casts each ray against them at its own firing time.
  std::vector<MovingBox> moving_boxes;
};

/// A straight passage through a 3D world (a tunnel, a garage aisle): the route enters at
/// `entry`, leaves `length_m` further along the unit `axis` (both horizontal, world frame).
struct Passage3D {
  /// "tunnel" or "garage".
  std::string kind;
  Vector2 entry = Vector2::Zero();
  Vector2 axis = Vector2::UnitX();
  double length_m = 0.0;
};

/// A 3D world with the route driven through it (as WorldWithRoute for 2D worlds).
struct World3DWithRoute {
  World3D world;
  /// The route's waypoints; a closed route returns to its first point at the end.
  std::vector<Vector2> route;
  bool closed_route = true;
  /// Set for worlds built around one straight passage.
  std::optional<Passage3D> passage;
};

}  // namespace cairn::sim
