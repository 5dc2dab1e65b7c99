#pragma once
/// \file
/// A 3D world: the ground plane z = 0, axis-aligned boxes (buildings, parked cars) and vertical
/// cylinders (poles, tree trunks and crowns), all in the `world` frame (z up), metres; plus
/// point landmarks with identities for the camera. Ray casting: ray_cast_3d.hpp.

#include <cstdint>
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

struct World3D {
  std::string name;
  /// Whether the plane z = 0 is solid (seen from above).
  bool ground = true;
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<Landmark3D> landmarks;
};

}  // namespace cairn::sim
