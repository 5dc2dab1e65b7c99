#include "cairn/sim/office_floor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <charconv>

#include "cairn/core/assert.hpp"
#include "cairn/io/number_format.hpp"

namespace cairn::sim {
namespace {

/// "bottom-room-<i>" / "top-room-<i>" -> (row, i); nullopt otherwise. row 0 = bottom, 1 = top.
std::optional<std::pair<int, int>> parse_room(std::string_view place, int rooms_per_row) {
  int row = -1;
  std::string_view rest;
  if (place.starts_with("bottom-room-")) {
    row = 0;
    rest = place.substr(12);
  } else if (place.starts_with("top-room-")) {
    row = 1;
    rest = place.substr(9);
  } else {
    return std::nullopt;
  }
  int index = -1;
  const auto result = std::from_chars(rest.data(), rest.data() + rest.size(), index);
  if (result.ec != std::errc() || result.ptr != rest.data() + rest.size() || index < 0 || index >= rooms_per_row) {
    return std::nullopt;
  }
  return std::make_pair(row, index);
}

/// OfficeOptions::furnished's pieces, in plan coordinates of the default plan (28 m x 20.8 m:
/// ring corridor's bottom leg y 5-7.4, top leg 13.4-15.8, west leg x 0-2.4, east leg 25.6-28).
/// The plan is half-turn symmetric about its centre, (x, y) -> (28 - x, 20.8 - y): no piece lies
/// within 2 m of another's image.
void add_furniture(World& world, const OfficeFloor& floor, const OuterDoors& doors) {
  CAIRN_ASSERT(doors.west_width_m <= 0.0 && doors.east_width_m <= 0.0, "a furnished office floor has no outer doors");
  const OfficeOptions& o = floor.options();
  const Vector2 origin = floor.origin();
  auto box = [&](double x0, double y0, double x1, double y1) { world.add_rectangle(origin + Vector2(x0, y0), origin + Vector2(x1, y1)); };
  box(5.2, 5.0, 6.4, 5.45);  // bottom leg, against the rooms
  box(19.0, 5.0, 19.6, 5.35);
  box(8.0, 6.95, 9.6, 7.4);  // bottom leg, against the block
  box(23.0, 7.0, 23.5, 7.4);
  box(12.0, 15.4, 12.5, 15.8);  // top leg, against the rooms
  box(14.2, 15.35, 15.6, 15.8);
  box(9.0, 13.4, 9.8, 13.8);    // top leg, against the block
  box(0.0, 9.0, 0.45, 10.2);    // west leg, outer wall
  box(27.6, 7.8, 28.0, 8.3);    // east leg, outer wall
  box(25.6, 11.6, 26.0, 12.4);  // east leg, against the block
  box(0.6, 15.4, 1.4, 15.8);    // the two top corners
  box(25.4, 15.45, 26.4, 15.8);
  // One shelf per room against its east wall, each at another distance from the corridor and of
  // another length.
  const double room_width = o.width_m / o.rooms_per_row;
  const double y4 = floor.depth_m() - o.room_depth_m;
  for (int i = 0; i < o.rooms_per_row; ++i) {
    const double x1 = (i + 1) * room_width;
    const double bottom_y = 1.4 + 0.7 * i;
    box(x1 - 0.45, bottom_y, x1, bottom_y + 0.8 + 0.25 * i);
    const double top_y = y4 + 0.6 + 0.6 * i;
    box(x1 - 0.45, top_y, x1, top_y + 0.7 + 0.3 * i);
  }
}

}  // namespace

void check_office_options(const OfficeOptions& o, const std::string& prefix, std::vector<std::string>& problems) {
  // `value` must be > `low` and at most 10 km (a world beyond that collapses its walls to points
  // in double precision, 1e308 overflows them); the message names the field and what was found.
  auto above = [&](double value, double low, const std::string& field) {
    if (!(value > low && value <= 1e4)) {
      std::string found;
      io::append_number(found, value);
      std::string bound;
      io::append_number(bound, low);
      problems.push_back(field + " must be in (" + bound + ", 10000] (found " + found + ")");
    }
  };
  if (o.rooms_per_row < 2 || o.rooms_per_row > 20) problems.push_back(prefix + ".rooms_per_row must be in [2, 20]");
  above(o.room_depth_m, 2.0, prefix + ".room_depth_m");
  above(o.corridor_width_m, 1.0, prefix + ".corridor_width_m");
  above(o.block_depth_m, 2.0, prefix + ".block_depth_m");
  above(o.door_width_m, 0.5, prefix + ".door_width_m");
  if (o.people < 0 || o.people > 8) problems.push_back(prefix + ".people must be in [0, 8]");
  if (o.furnished) {
    const OfficeOptions plan;
    if (o.rooms_per_row != plan.rooms_per_row || o.width_m != plan.width_m || o.room_depth_m != plan.room_depth_m ||
        o.corridor_width_m != plan.corridor_width_m || o.block_depth_m != plan.block_depth_m || o.door_width_m != plan.door_width_m) {
      problems.push_back(prefix + ".furnished: the furniture is laid out for the default plan (4 rooms per row, 28 m wide, rooms 5 m "
                                  "deep, corridor 2.4 m, block 6 m, doors 1 m); leave the plan's sizes at their defaults");
    }
  }
  if (o.rooms_per_row >= 2) {
    above(o.width_m / o.rooms_per_row, std::max(3.0, o.door_width_m + 1.0), prefix + ".width_m / rooms_per_row");
    above((o.width_m - 2 * o.corridor_width_m) / 3.0, o.door_width_m + 3.0,
          "(" + prefix + ".width_m - 2 corridor_width_m) / 3");
  }
}

OfficeFloor::OfficeFloor(const OfficeOptions& options, const Vector2& origin) : options_(options), origin_(origin) {
  CAIRN_ASSERT(options.rooms_per_row >= 2, "OfficeFloor: at least two rooms per row");
  c_ = options.corridor_width_m;
  y1_ = options.room_depth_m;
  y2_ = y1_ + c_;
  y3_ = y2_ + options.block_depth_m;
  y4_ = y3_ + c_;
  y5_ = y4_ + options.room_depth_m;
  room_width_ = options.width_m / options.rooms_per_row;
  block_room_width_ = (options.width_m - 2 * c_) / 3.0;
}

std::vector<Vector2> OfficeFloor::lap_route() const {
  const double x_left = x_west();
  const double x_right = x_east();
  const Vector2 start(x_left + 2.5, y_bottom());
  const double bottom_room_x = origin_.x() + 1.5 * room_width_;
  const double top_room_x = origin_.x() + (options_.rooms_per_row - 1.5) * room_width_;
  const double D = options_.room_depth_m;
  return {start,
          {bottom_room_x, y_bottom()},
          {bottom_room_x, origin_.y() + 0.5 * D},  // into a bottom room and back out
          {bottom_room_x, y_bottom()},
          {x_right, y_bottom()},
          {x_right, y_top()},
          {top_room_x, y_top()},
          {top_room_x, origin_.y() + y4_ + 0.5 * D},  // into a top room and back out
          {top_room_x, y_top()},
          {x_left, y_top()},
          {x_left, y_bottom()},
          start,  // first loop closed: the ring corridor
          {middle_x(), y_bottom()},
          {middle_x(), y_top()},  // through the middle room of the block
          {x_left, y_top()},
          {x_left, y_bottom()}};  // second loop closes at start
}

std::vector<std::string> OfficeFloor::place_names() const {
  std::vector<std::string> names;
  for (int i = 0; i < options_.rooms_per_row; ++i) names.push_back("bottom-room-" + std::to_string(i));
  for (int i = 0; i < options_.rooms_per_row; ++i) names.push_back("top-room-" + std::to_string(i));
  names.push_back("middle-room");
  return names;
}

std::optional<Vector2> OfficeFloor::place_center(std::string_view place) const {
  if (place == "middle-room") return Vector2(middle_x(), side_door_y());
  const auto room = parse_room(place, options_.rooms_per_row);
  if (!room) return std::nullopt;
  const double y = room->first == 0 ? 0.5 * y1_ : y4_ + 0.5 * options_.room_depth_m;
  return Vector2(room_door_x(room->second), origin_.y() + y);
}

Vector2 OfficeFloor::place_exit(std::string_view place) const {
  if (place == "middle-room") return {middle_x(), y_top()};
  const auto room = parse_room(place, options_.rooms_per_row);
  CAIRN_ASSERT(room.has_value(), "OfficeFloor::place_exit: unknown place (check place_center first)");
  return {room_door_x(room->second), room->first == 0 ? y_bottom() : y_top()};
}

std::vector<Vector2> OfficeFloor::ring_from(const Vector2& from, bool counter_clockwise) const {
  // Corners counter-clockwise; leg k runs from corner k to corner k + 1.
  const std::array<Vector2, 4> corners = {Vector2(x_west(), y_bottom()), Vector2(x_east(), y_bottom()),
                                          Vector2(x_east(), y_top()), Vector2(x_west(), y_top())};
  constexpr double kOnLine = 1e-9;
  int leg = -1;
  if (std::abs(from.y() - y_bottom()) < kOnLine) leg = 0;
  else if (std::abs(from.x() - x_east()) < kOnLine) leg = 1;
  else if (std::abs(from.y() - y_top()) < kOnLine) leg = 2;
  else if (std::abs(from.x() - x_west()) < kOnLine) leg = 3;
  CAIRN_ASSERT(leg >= 0, "OfficeFloor::ring_from: the point is on no corridor centre line");
  std::vector<Vector2> route;
  for (int k = 1; k <= 4; ++k) {
    const int corner = counter_clockwise ? (leg + k) % 4 : ((leg + 1 - k) % 4 + 4) % 4;
    route.push_back(corners[static_cast<std::size_t>(corner)]);
  }
  route.push_back(from);
  return route;
}

void add_office_floor(World& world, const OfficeFloor& floor, const OuterDoors& doors) {
  const OfficeOptions& o = floor.options();
  const Vector2 origin = floor.origin();
  // Plan coordinates (relative to the south-west corner) to the world frame.
  auto at = [&](double x, double y) { return Vector2(origin.x() + x, origin.y() + y); };
  const double W = o.width_m;
  const double D = o.room_depth_m;
  const double c = o.corridor_width_m;
  const double B = o.block_depth_m;
  const double y1 = D;              // top wall of the bottom room row
  const double y2 = D + c;          // bottom wall of the central block
  const double y3 = D + c + B;      // top wall of the central block
  const double y4 = D + 2 * c + B;  // bottom wall of the top room row
  const double y5 = 2 * D + 2 * c + B;
  const double room_width = W / o.rooms_per_row;
  const double block_room_width = (W - 2 * c) / 3.0;
  const double door_y = 0.5 * (y2 + y3);

  // The outer rectangle in World::add_rectangle's order (south, east, north, west), each side
  // walls with its door left out.
  world.add_wall(at(0, 0), at(W, 0));
  if (doors.east_width_m > 0.0) world.add_wall_with_gaps(at(W, 0), at(W, y5), {{door_y, doors.east_width_m}});
  else world.add_wall(at(W, 0), at(W, y5));
  world.add_wall(at(W, y5), at(0, y5));
  if (doors.west_width_m > 0.0) world.add_wall_with_gaps(at(0, y5), at(0, 0), {{y5 - door_y, doors.west_width_m}});
  else world.add_wall(at(0, y5), at(0, 0));

  std::vector<std::pair<double, double>> room_doors;
  for (int i = 0; i < o.rooms_per_row; ++i) room_doors.emplace_back((i + 0.5) * room_width, o.door_width_m);
  world.add_wall_with_gaps(at(0, y1), at(W, y1), room_doors);
  world.add_wall_with_gaps(at(0, y4), at(W, y4), room_doors);
  for (int i = 1; i < o.rooms_per_row; ++i) {
    world.add_wall(at(i * room_width, 0), at(i * room_width, y1));
    world.add_wall(at(i * room_width, y4), at(i * room_width, y5));
  }
  // Desks against the back wall of every room, off the room's centre line (the route's).
  for (int i = 0; i < o.rooms_per_row; ++i) {
    const double x0 = i * room_width;
    world.add_rectangle(at(x0 + 0.5, 0.3), at(x0 + 2.1, 1.1));
    world.add_rectangle(at(x0 + room_width - 2.1, y5 - 1.1), at(x0 + room_width - 0.5, y5 - 0.3));
  }
  // Central block: three rooms; the middle one has doors on both long walls (the second loop),
  // the right one a door to the bottom corridor, the left one a door to the top corridor.
  world.add_wall_with_gaps(at(c, y2), at(W - c, y2),
                           {{1.5 * block_room_width, o.door_width_m}, {2.5 * block_room_width, o.door_width_m}});
  world.add_wall_with_gaps(at(c, y3), at(W - c, y3),
                           {{0.5 * block_room_width, o.door_width_m}, {1.5 * block_room_width, o.door_width_m}});
  world.add_wall(at(c, y2), at(c, y3));
  world.add_wall(at(W - c, y2), at(W - c, y3));
  world.add_wall(at(c + block_room_width, y2), at(c + block_room_width, y3));
  world.add_wall(at(c + 2 * block_room_width, y2), at(c + 2 * block_room_width, y3));
  const double block_mid_y = 0.5 * (y2 + y3);
  world.circles.push_back({at(c + 0.5 * block_room_width, block_mid_y), 0.6});
  world.circles.push_back({at(c + 2.5 * block_room_width, block_mid_y), 0.6});
  world.circles.push_back({at(c + 1.5 * block_room_width + 2.2, block_mid_y), 0.5});

  if (o.furnished) add_furniture(world, floor, doors);

  // People: eight tracks 0.45 m from a wall (0.5 m of free space to the route's lane) or in
  // rooms the route never enters; the first `people` of them are used.
  const std::array<std::array<Vector2, 2>, 8> tracks = {{
      {at(1.0, y1 + 0.45), at(W - 1.0, y1 + 0.45)},
      {at(c + 0.5, y3 + 0.45), at(W - c - 0.5, y3 + 0.45)},
      {at(0.45, y2 + 0.5), at(0.45, y3 - 0.5)},
      {at(c + 0.5, y2 - 0.45), at(W - c - 0.5, y2 - 0.45)},
      {at(1.0, y4 - 0.45), at(W - 1.0, y4 - 0.45)},
      {at(W - 0.45, y2 + 0.5), at(W - 0.45, y3 - 0.5)},
      {at(1.0, 2.0), at(room_width - 1.0, 0.8 * D)},
      {at(c + 0.7, y2 + 0.7), at(c + block_room_width - 0.7, y2 + 0.7)},
  }};
  for (int i = 0; i < std::clamp(o.people, 0, 8); ++i) {
    const auto& track = tracks[static_cast<std::size_t>(i)];
    world.walkers.push_back({track[0], track[1], 0.8 + 0.1 * (i % 5), 0.25, 2.3 * i});
  }
}

}  // namespace cairn::sim
