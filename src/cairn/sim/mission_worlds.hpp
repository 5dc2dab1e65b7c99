#pragma once
/// \file
/// Worlds for the failures a 2D LiDAR SLAM system must recover from, built from office floors
/// (office_floor.hpp), each with a one-way route (open: driven once, it ends elsewhere than it
/// starts), named regions the scans are labelled with, and the doors of the outer walls.
///
/// | builder                      | world                                              | provokes                   |
/// |------------------------------|----------------------------------------------------|----------------------------|
/// | building_yard_world          | the office plan with doors A (west) and B (east)   | scan matching fails in the |
/// |                              | to an open yard with a handful of trees, posts and | yard (few or no returns);  |
/// |                              | benches; route: a lap inside, out A, round the     | re-entry through B must    |
/// |                              | yard 35 m from the walls, in B, revisits           | re-join the building's map |
/// | building_yard_second_session | the same world, another route from another pose    | map-based localisation     |
/// | outdoor_stretch_world        | two office plans (4 and 3 rooms per row) 130 m     | a long blind stretch, two  |
/// |                              | apart, a path with a few posts and trees between   | maps to join on return     |
/// | two_wing_world               | two office plans joined by an indoor corridor      | a revisit after a long     |
/// |                              | (the long-absence route tours the east wing)       | absence                    |
///
/// Sizes default so that the yard and the path keep the robot farther from every wall than the
/// default LiDAR range (30 m) for most of the way; the tests measure the scans, not the plan.

#include <cstdint>
#include <numbers>
#include <string>

#include "cairn/sim/world_builders.hpp"

namespace cairn::sim {

struct BuildingYardOptions {
  /// Width of doors A (west outer wall) and B (east outer wall), metres; both open from the
  /// side corridors of the ring (at the middle of the block's height) straight to the yard.
  double door_width_m = 1.6;
  /// Distance from the facades to the yard legs of the route, metres (>= 5). Beyond the LiDAR's
  /// range the building is out of sight there (the LiDAR sees only ahead and to the sides).
  double yard_offset_m = 35.0;
  /// Trees (radius 0.3 m), posts (0.1 m) and benches (1.8 m x 0.6 m), in turn, spread evenly
  /// along the yard route 3-10 m to its outer side (0..30).
  int features = 6;
  /// Seed of the features' jitter along and across the route.
  std::uint64_t world_seed = 13;
};

/// Where the second session of building-yard starts.
struct SessionStartOptions {
  /// A place of the building (OfficeFloor::place_names): "middle-room", "bottom-room-<i>" or
  /// "top-room-<i>"; the robot starts at its centre.
  std::string place = "middle-room";
  /// Heading at the start, radians (0 = +x, east): the robot turns on the spot towards the
  /// place's door before it drives.
  double heading_rad = std::numbers::pi;
};

struct OutdoorStretchOptions {
  /// Distance between the facing facades of the two buildings, metres: the outdoor path (>= 40).
  double path_length_m = 130.0;
  /// Building 2 is the office plan of building 1 with this many rooms per row and this width,
  /// so the two buildings do not look alike.
  int building_2_rooms_per_row = 3;
  double building_2_width_m = 24.0;
  /// Width of the door at each end of the path (building 1 east, building 2 west), metres.
  double door_width_m = 1.6;
  /// Trees, posts and benches along the path, 3-8 m to either side in turn (0..30).
  int features = 4;
  /// Seed of the features' jitter.
  std::uint64_t world_seed = 17;
  /// The two facades that face the path (building 1's east, building 2's west) are glass
  /// (Segment::glass): from the path the LiDAR sees into the rooms behind them, and only beams
  /// near the panes' normal return from the facade itself.
  bool glass_facades = false;
};

struct TwoWingOptions {
  /// The east wing: the west wing's (office) plan with this many rooms per row and this width.
  int east_wing_rooms_per_row = 3;
  double east_wing_width_m = 24.0;
  /// The indoor corridor joining the west wing's east door to the east wing's west door, metres.
  double connector_length_m = 16.0;
  double connector_width_m = 2.4;
  /// Width of the two doors, metres (<= connector_width_m).
  double door_width_m = 1.6;
  /// Laps of the east wing's ring corridor before going back, each into another bottom room
  /// (1..20): how long the robot stays away.
  int away_laps = 4;
};

/// The building (the office plan at the origin, without people) with doors A (west) and B
/// (east) and the yard around it; the route: the office lap, out through A, west, north, east
/// and south round the building at yard_offset_m from its walls, in through B, then the north
/// corridor, the west corridor and the bottom corridor back to the office start (revisits).
/// Regions: "building"; outside it, "yard". Doors: "A", "B".
WorldWithRoute building_yard_world(const OfficeOptions& building, const BuildingYardOptions& yard);

/// building_yard_world's world (identical walls and features) with a second session's route:
/// from the centre of `start.place`, facing start.heading_rad, out of its door, once round the
/// ring clockwise (the first session drives it counter-clockwise), along the corridor to the
/// middle room and through it, into the room across the corridor and back out (bottom room 1
/// from the top corridor, top room n - 2 from the bottom one: both visited by the first
/// session), along that corridor to the east corridor, 6 m out of door B into the yard, a turn
/// on the spot and back in. Precondition: OfficeFloor(building).place_center(start.place).
WorldWithRoute building_yard_second_session(const OfficeOptions& building, const BuildingYardOptions& yard,
                                            const SessionStartOptions& start);

/// Building 1 (the office plan at the origin, a door in its east wall) and building 2 (a door in
/// its west wall, path_length_m east of it), the path between them; the route: the office lap
/// (its last loop leaving through the east door), the path, building 2's ring with one room,
/// the path back, then building 1's bottom corridor into bottom room 1 and to the start.
/// Regions: "building-1", "building-2"; outside them, "path".
WorldWithRoute outdoor_stretch_world(const OfficeOptions& building_1, const OutdoorStretchOptions& options);

/// The west wing (the office plan at the origin) and the east wing joined by an indoor
/// corridor; the route: the office lap leaving through the east door, the corridor, away_laps
/// laps of the east wing's ring, the corridor back, then the west wing's bottom corridor into
/// bottom room 1 and to the start. Regions: "west-wing", "connector", "east-wing".
WorldWithRoute two_wing_world(const OfficeOptions& west_wing, const TwoWingOptions& options);

}  // namespace cairn::sim
