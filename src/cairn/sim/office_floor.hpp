#pragma once
/// \file
/// The office floor plan (office_world's) as a reusable piece: its walls placed anywhere in a
/// world, with optional doors in the outer walls, and the named places and corridor lines routes
/// are drawn through. The office, building-yard, outdoor-stretch, long-absence, kidnapping and
/// second-session worlds are all made of it.
///
/// Plan (relative to the south-west corner `origin`; W = width_m, D = room_depth_m,
/// c = corridor_width_m, B = block_depth_m; rooms_per_row = 4 drawn):
///
///   y5 = 2D + 2c + B  +-------+-------+-------+-------+
///                     | top-0 | top-1 | top-2 | top-3 |   a door in the middle of each
///   y4 = D + 2c + B   +--- ---+--- ---+--- ---+--- ---+   room's corridor wall
///                     |        ring corridor          |
///   y3 = D + c + B    |  +--- ---+--- ---+-------+  |
///   outer west door   |  | left  |middle | right |  |   outer east door
///   at (y2 + y3) / 2  |  +-------+--- ---+--- ---+  |   at (y2 + y3) / 2
///   y2 = D + c        |                               |
///   y1 = D            +--- ---+--- ---+--- ---+--- ---+
///                     | bot-0 | bot-1 | bot-2 | bot-3 |   (a desk against each back wall)
///   0                 +-------+-------+-------+-------+
///                     0                               W
///
/// The block's three rooms are (W - 2c) / 3 wide (pillars in the left and right ones, a post in
/// the middle one); the middle one has doors on both long sides, the left one on its top side,
/// the right one on its bottom side. The outer doors exist only when asked for (OuterDoors).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/types.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

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
  /// Furniture at irregular places: 12 cabinets along the ring corridor (two of them in its top
  /// corners) and a shelf against the east wall of every room, each room's at another distance
  /// from the corridor and of another length. No piece lies within 2 m of another's half-turn
  /// image, so no stretch of the ring and no room looks like another, shifted or turned half
  /// round: the bare plan is half-turn symmetric but for one pillar, and there a robot that does
  /// not know where it is cannot tell the two halves apart. Every piece leaves >= 0.75 m to the
  /// centre lines the routes drive and none stands in a doorway. Laid out for the default plan
  /// (check_office_options refuses it on another) and for floors without outer doors.
  bool furnished = false;
};

/// Checks an office plan; every problem is appended to `problems`, each naming `prefix`.field.
void check_office_options(const OfficeOptions& options, const std::string& prefix, std::vector<std::string>& problems);

/// The coordinates of an office plan placed with its south-west corner at `origin` (world frame).
/// Every point returned is in the world frame.
class OfficeFloor {
 public:
  /// Precondition: check_office_options reported nothing.
  OfficeFloor(const OfficeOptions& options, const Vector2& origin = Vector2::Zero());

  const OfficeOptions& options() const { return options_; }
  const Vector2& origin() const { return origin_; }
  double width_m() const { return options_.width_m; }
  /// y5: the whole floor's depth.
  double depth_m() const { return y5_; }
  /// The floor's footprint.
  Bounds bounds() const { return {origin_, origin_ + Vector2(width_m(), depth_m())}; }

  /// Centre lines of the ring corridor's four legs.
  double x_west() const { return origin_.x() + 0.5 * c_; }
  double x_east() const { return origin_.x() + width_m() - 0.5 * c_; }
  double y_bottom() const { return origin_.y() + y1_ + 0.5 * c_; }
  double y_top() const { return origin_.y() + y3_ + 0.5 * c_; }
  /// Height of the outer-wall doors (west and east): the middle of the side corridors beside
  /// the block, where the ring's side legs touch the outer walls.
  double side_door_y() const { return origin_.y() + 0.5 * (y2_ + y3_); }
  /// x of the route through the middle block room (its two doors).
  double middle_x() const { return origin_.x() + c_ + 1.5 * block_room_width_; }
  /// x of the door of room `i` of either row (0 = west).
  double room_door_x(int i) const { return origin_.x() + (i + 0.5) * room_width_; }

  /// The office route (one lap): the ring, into bottom room 1 and top room n - 2 (turning on
  /// the spot in each), then a second loop through the middle room; closed, it ends at its start
  /// (x_west + 2.5, y_bottom) facing east.
  std::vector<Vector2> lap_route() const;

  /// Places a robot can be put or start: "bottom-room-<i>", "top-room-<i>" (i = 0 .. n - 1, west
  /// to east) and "middle-room" (the block's middle room).
  std::vector<std::string> place_names() const;
  /// The centre of the named place; nullopt for an unknown name.
  std::optional<Vector2> place_center(std::string_view place) const;
  /// Where a robot leaves the named place: the point on the corridor centre line in front of its
  /// door (the middle room: its top door). Precondition: place_center(place) has a value.
  Vector2 place_exit(std::string_view place) const;

  /// The ring corridor driven once from `from` (a point on one of its centre lines) back to
  /// `from`: the four corners in order, then `from`. Counter-clockwise (west -> east along the
  /// bottom) or clockwise.
  std::vector<Vector2> ring_from(const Vector2& from, bool counter_clockwise) const;

 private:
  OfficeOptions options_;
  Vector2 origin_;
  double c_ = 0.0;
  double y1_ = 0.0, y2_ = 0.0, y3_ = 0.0, y4_ = 0.0, y5_ = 0.0;
  double room_width_ = 0.0;
  double block_room_width_ = 0.0;
};

/// Doors in the floor's outer walls, centred at side_door_y(); width 0 = no door on that side.
struct OuterDoors {
  double west_width_m = 0.0;
  double east_width_m = 0.0;
};

/// Adds the floor's walls, desks, block pillars and its people (options().people) to `world`.
/// With no outer doors the walls are those office_world has always written, in the same order.
void add_office_floor(World& world, const OfficeFloor& floor, const OuterDoors& doors = {});

}  // namespace cairn::sim
