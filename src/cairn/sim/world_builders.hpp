#pragma once
/// \file
/// Named 2D worlds, each with the route (waypoints) a robot drives through it. Every size is a
/// field with a default; the scenarios (scenario.hpp) expose them as parameters.
///
/// | builder                | what it is                                              | challenges SLAM with |
/// |------------------------|---------------------------------------------------------|----------------------|
/// | office_world           | rooms on two sides of a ring corridor around a block of  | loops, revisits,     |
/// |                        | three rooms; the middle one has two doors (second loop); | moving objects       |
/// |                        | optionally people walking (`people`)                     |                      |
/// | corridor_world         | two long corridors joined at the ends into a ring, with  | perceptual aliasing  |
/// |                        | identical recessed doors at a fixed pitch on both sides  |                      |
/// | open_hall_world        | a large empty hall with a few pillars                    | degeneracy           |
/// | building_loop_world    | the outside of one building with recesses, trees and     | one long loop, drift |
/// |                        | parked boxes around it                                   |                      |
/// | landmark_field_world   | posts (circles) with identities scattered around a loop  | landmark SLAM        |
///
/// The office plan is office_floor.hpp's; mission_worlds.hpp builds the recovery scenarios'
/// worlds (a yard, two buildings, two wings) from it.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cairn/sim/office_floor.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// A named part of a world (a building, a wing, the yard), for labelling where the robot is.
struct Region {
  std::string name;
  Bounds bounds;
};

/// An opening in a building's outer wall: the way between inside and outside.
struct Doorway {
  std::string name;
  /// Middle of the opening on the wall line (world frame) and the unit normal pointing out.
  Vector2 center = Vector2::Zero();
  Vector2 outward = Vector2::UnitX();
  double width_m = 0.0;
};

/// A world and the closed route driven through it: the robot starts at route.front() facing
/// route[1], visits every waypoint in order and comes back to route.front() (one lap); an open
/// route (closed_route false, some 3D worlds and the mission worlds) ends at route.back().
struct WorldWithRoute {
  World world;
  std::vector<Vector2> route;
  bool closed_route = true;
  /// The robot's heading at the start, radians; nullopt: facing route[1]. Otherwise it turns on
  /// the spot to route[1] before driving (second-session).
  std::optional<double> start_heading_rad;
  /// Named parts of the world (mission worlds); a point in none of them is in `outside_region`.
  /// The first region holding a point names it.
  std::vector<Region> regions;
  std::string outside_region;
  /// Doors in outer walls (building-yard: A and B).
  std::vector<Doorway> doors;

  /// The name of the region holding `point` (outside_region when none does).
  std::string region_at(const Vector2& point) const;
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
