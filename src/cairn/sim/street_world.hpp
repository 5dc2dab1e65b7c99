#pragma once
/// \file
/// A 3D street scene: a rectangular loop of streets around a city block, lined with building
/// facades (boxes of seeded random length and height) on both sides, lamp poles on the inner
/// sidewalk, trees (trunk + crown cylinders) on the outer one, and parked cars (boxes) at the
/// outer kerb. The route is the street's centre line (z = 0), driven counter-clockwise; with
/// `reverse_second_lap` it is driven once counter-clockwise, then (after a U-turn just past the
/// start) once clockwise `reverse_lane_offset_m` to the inside of the centre line. Optional
/// moving cars drive clockwise around the block 1.5 m outside the centre line.

#include <cstdint>
#include <vector>

#include "cairn/sim/world_3d.hpp"

namespace cairn::sim {

struct StreetOptions {
  /// Size of the route rectangle (street centre lines), metres.
  double loop_width_m = 60.0;
  double loop_depth_m = 40.0;
  /// Distance from the centre line to the facades on either side, metres (> 4).
  double street_half_width_m = 7.0;
  /// Building heights are uniform in [min, max], metres.
  double min_building_height_m = 8.0;
  double max_building_height_m = 20.0;
  /// Distance between lamp poles and between trees along a street, metres (> 2).
  double pole_spacing_m = 15.0;
  double tree_spacing_m = 12.0;
  /// Parked cars along the outer kerb.
  int parked_cars = 8;
  /// Seed of the building sizes and car places (the world, not the sensor noise).
  std::uint64_t world_seed = 5;
  /// Second lap in the opposite direction (an open route; use with one lap), offset towards
  /// the block by reverse_lane_offset_m (in [0, street_half_width_m - 3]).
  bool reverse_second_lap = false;
  double reverse_lane_offset_m = 3.0;
  /// Cars (4.5 m x 1.8 m x 1.5 m) driving clockwise around the block at moving_car_speed_mps,
  /// evenly spaced (a seeded common offset), in [0, 20].
  int moving_cars = 0;
  double moving_car_speed_mps = 5.0;
};

using StreetWorld = World3DWithRoute;

/// The lamps, 0.3 m above each 6 m pole, are the world's landmarks (ids from 0, for the camera).
StreetWorld street_world(const StreetOptions& options = {});

}  // namespace cairn::sim
