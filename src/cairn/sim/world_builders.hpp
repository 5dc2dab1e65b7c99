#pragma once
/// \file
/// Named 2D worlds, each with the route (waypoints) a robot drives through it. Every size is a
/// field with a default; the scenarios (scenario.hpp) expose them as parameters.
///
/// | builder                | what it is                                              | challenges SLAM with |
/// |------------------------|---------------------------------------------------------|----------------------|
/// | office_world           | rooms on two sides of a ring corridor around a block of  | loops, revisits,     |
/// |                        | three rooms; optionally people walking (`people`)        | moving objects       |
/// |                        | three rooms; the middle one has two doors (second loop)  |                      |
/// | corridor_world         | two long corridors joined at the ends into a ring, with  | perceptual aliasing  |
/// |                        | identical recessed doors at a fixed pitch on both sides  |                      |
/// | open_hall_world        | a large empty hall with a few pillars                    | degeneracy           |
/// | building_loop_world    | the outside of one building with recesses, trees and     | one long loop, drift |
/// |                        | parked boxes around it                                   |                      |
/// | landmark_field_world   | posts (circles) with identities scattered around a loop  | landmark SLAM        |

#include <cstdint>
#include <vector>

#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// A world and the closed route driven through it: the robot starts at route.front() facing
/// route[1], visits every waypoint in order and comes back to route.front() (one lap); an open
/// route (closed_route false, some 3D worlds) ends at route.back().
struct WorldWithRoute {
  World world;
  std::vector<Vector2> route;
  bool closed_route = true;
};

struct OfficeOptions {
  /// Rooms in the bottom row and in the top row (>= 2).
  int rooms_per_row = 4;
  /// Total width of the floor, metres.
  double width_m = 28.0;
  /// Depth of each room row (y extent), metres.
  double room_depth_m = 5.0;
  /// Width of the ring corridor, metres.
  double corridor_width_m = 2.4;
  /// Depth of the central block of three rooms, metres.
  double block_depth_m = 6.0;
  /// Width of every door opening, metres.
  double door_width_m = 1.0;
  /// People walking back and forth (0..8): along the corridors beside the robot's lane, and in
  /// rooms the route does not enter. They do not avoid the robot, nor it them.
  int people = 0;
};
WorldWithRoute office_world(const OfficeOptions& options = {});

struct CorridorOptions {
  /// Length of each long corridor (outer x extent of the ring), metres.
  double length_m = 50.0;
  /// Corridor width, metres.
  double width_m = 2.2;
  /// Depth of the block between the two long corridors, metres.
  double block_depth_m = 8.0;
  /// Distance between neighbouring doors along a corridor, metres.
  double door_pitch_m = 4.0;
  /// Door opening, metres.
  double door_width_m = 1.0;
  /// Depth of the recess behind each door opening, metres.
  double door_recess_m = 0.3;
};
WorldWithRoute corridor_world(const CorridorOptions& options = {});

struct OpenHallOptions {
  double width_m = 50.0;
  double depth_m = 40.0;
  /// Pillars (radius pillar_radius_m) placed on a fixed pattern, at most 8.
  int pillars = 4;
  double pillar_radius_m = 0.3;
  /// Size of the rectangular route in the middle of the hall, metres (x and y).
  double route_width_m = 30.0;
  double route_depth_m = 20.0;
};
WorldWithRoute open_hall_world(const OpenHallOptions& options = {});

struct BuildingLoopOptions {
  /// Footprint of the building, metres.
  double building_width_m = 40.0;
  double building_depth_m = 25.0;
  /// Distance from the facade to the route, metres.
  double street_offset_m = 4.0;
  /// Trees (radius 0.25 m) per metre of route, on the far side of the street.
  double trees_per_m = 0.08;
  /// Seed for tree placement (the world, not the sensor noise).
  std::uint64_t world_seed = 7;
};
WorldWithRoute building_loop_world(const BuildingLoopOptions& options = {});

struct LandmarkFieldOptions {
  /// Side lengths of the rectangular route, metres.
  double route_width_m = 30.0;
  double route_depth_m = 20.0;
  /// Number of landmarks (posts).
  int landmarks = 60;
  /// Landmarks are placed uniformly within this distance of the route, metres...
  double max_distance_from_route_m = 8.0;
  /// ...and never closer than this to it, metres.
  double min_distance_from_route_m = 1.0;
  /// Radius of the post at each landmark (seen by the LiDAR), metres; 0 for invisible ones.
  double post_radius_m = 0.1;
  /// Seed for landmark placement.
  std::uint64_t world_seed = 11;
};
WorldWithRoute landmark_field_world(const LandmarkFieldOptions& options = {});

}  // namespace cairn::sim
