#pragma once
/// \file
/// 3D worlds built around one straight passage along the world x axis, driven once from
/// x = -approach_m to x = length_m + approach_m along y = 0 (an open route: nothing is revisited):
///
///  - garage_world: a parking garage, perfectly periodic inside: pillars, ceiling beams and
///    identical perpendicular-parked cars repeat every bay_pitch_m, so places a whole number of
///    bays apart look the same (perceptual aliasing without a single true loop closure).
///  - tunnel_world: a straight tunnel with flat walls, floor and ceiling and nothing else: along
///    its axis a LiDAR sees no structure once both portals are out of range (degenerate
///    geometry for scan matching).
///
/// Outside, both approaches are lined with seeded random buildings, lamp poles and trees, so
/// entry and exit differ from each other and from the inside. World3DWithRoute::passage gives
/// the passage's entry (x = 0, y = 0), axis (+x) and length.

#include <cstdint>

#include "cairn/sim/world_3d.hpp"

namespace cairn::sim {

struct GarageOptions {
  /// Length of the garage along the route, metres (>= 4 bays).
  double length_m = 160.0;
  /// From the centre of the driving aisle to the side walls, metres, in [6, 20].
  double half_width_m = 8.0;
  /// Ceiling height, metres, in [2.6, 10]; the entrances are 2.4 m high.
  double ceiling_height_m = 3.0;
  /// Distance between pillars (and ceiling beams) along the aisle, metres, in [3, 30].
  double bay_pitch_m = 8.0;
  /// Length of the street before and after the garage, metres, in [10, 200].
  double approach_m = 30.0;
  /// Seed of the buildings, poles and trees outside.
  std::uint64_t world_seed = 7;
};

struct TunnelOptions {
  /// Length of the tunnel, metres, in [20, 2000].
  double length_m = 150.0;
  /// From the centre line to either wall, metres, in [3, 20].
  double half_width_m = 5.0;
  /// Ceiling height, metres, in [3, 20].
  double height_m = 5.5;
  /// Length of the road before and after the tunnel, metres, in [10, 200].
  double approach_m = 40.0;
  /// Seed of the buildings, poles and trees outside.
  std::uint64_t world_seed = 9;
};

World3DWithRoute garage_world(const GarageOptions& options = {});
World3DWithRoute tunnel_world(const TunnelOptions& options = {});

}  // namespace cairn::sim
