#include "cairn/sim/mission_worlds.hpp"

#include <cmath>
#include <vector>

#include "cairn/core/assert.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

/// Sparse outdoor features along the open polyline `path`: `count` of them at arc lengths spread
/// evenly over [margin, length - margin], each moved along by up to a fifth of the spacing and
/// put U(min_offset, max_offset) metres to the path's left (`alternate` false) or to its left and
/// right in turn; kinds in turn: tree (circle r 0.3 m), post (circle r 0.1 m), bench (a 1.8 m x
/// 0.6 m box, its long side along the path). Two draws per feature. Evenly spread, they stay
/// (length - 2 margin) / count apart give or take the jitter: far apart by construction.
void add_sparse_features(World& world, const std::vector<Vector2>& path, int count, double min_offset_m,
                         double max_offset_m, bool alternate, Random& random) {
  if (count <= 0) return;
  std::vector<double> end_s;
  double length = 0.0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    length += (path[i + 1] - path[i]).norm();
    end_s.push_back(length);
  }
  const double margin = std::min(10.0, 0.25 * length);
  const double spacing = (length - 2.0 * margin) / count;
  for (int k = 0; k < count; ++k) {
    const double jitter = random.uniform(-0.2, 0.2) * spacing;
    const double offset = random.uniform(min_offset_m, max_offset_m);
    const double s = margin + (k + 0.5) * spacing + jitter;
    std::size_t leg = 0;
    while (leg + 1 < end_s.size() && end_s[leg] < s) ++leg;
    const Vector2 direction = (path[leg + 1] - path[leg]).normalized();
    const double leg_start = leg == 0 ? 0.0 : end_s[leg - 1];
    const Vector2 left(-direction.y(), direction.x());
    const double side = alternate && k % 2 == 1 ? -1.0 : 1.0;
    const Vector2 p = path[leg] + (s - leg_start) * direction + side * offset * left;
    switch (k % 3) {
      case 0: world.circles.push_back({p, 0.3}); break;
      case 1: world.circles.push_back({p, 0.1}); break;
      default: {
        const bool along_x = std::abs(direction.x()) >= std::abs(direction.y());
        const Vector2 half = along_x ? Vector2(0.9, 0.3) : Vector2(0.3, 0.9);
        world.add_rectangle(p - half, p + half);
        break;
      }
    }
  }
}

/// The office lap whose last loop (through the middle room) leaves by the east side corridor:
/// ... north through the middle room, east along the top corridor, south to the east door.
std::vector<Vector2> lap_to_east_door(const OfficeFloor& floor) {
  std::vector<Vector2> route = floor.lap_route();
  route.resize(route.size() - 2);  // drop the last loop's return along the west corridor
  route.push_back({floor.x_east(), floor.y_top()});
  route.push_back({floor.x_east(), floor.side_door_y()});
  return route;
}

/// In through the east door: the bottom corridor west, into bottom room 1 and out, to the start.
void append_return_through_east_door(const OfficeFloor& floor, std::vector<Vector2>& route) {
  const Vector2 room = *floor.place_center("bottom-room-1");
  route.push_back({floor.x_east(), floor.side_door_y()});
  route.push_back({floor.x_east(), floor.y_bottom()});
  route.push_back({room.x(), floor.y_bottom()});
  route.push_back(room);
  route.push_back({room.x(), floor.y_bottom()});
  route.push_back(floor.lap_route().front());
}

/// In through the west door, `laps` times counter-clockwise round the ring (lap k into bottom
/// room k mod n and back out), then back to the west door.
void append_tour_from_west_door(const OfficeFloor& floor, int laps, std::vector<Vector2>& route) {
  const Vector2 door(floor.x_west(), floor.side_door_y());
  route.push_back(door);
  for (int lap = 0; lap < laps; ++lap) {
    const Vector2 room = *floor.place_center("bottom-room-" + std::to_string(lap % floor.options().rooms_per_row));
    route.push_back({floor.x_west(), floor.y_bottom()});
    route.push_back({room.x(), floor.y_bottom()});
    route.push_back(room);
    route.push_back({room.x(), floor.y_bottom()});
    route.push_back({floor.x_east(), floor.y_bottom()});
    route.push_back({floor.x_east(), floor.y_top()});
    route.push_back({floor.x_west(), floor.y_top()});
    route.push_back(door);
  }
}

OfficeOptions without_people(OfficeOptions options) {
  options.people = 0;
  return options;
}

/// A second floor beside the first: its plan with other rooms per row and width.
OfficeOptions variant(const OfficeOptions& first, int rooms_per_row, double width_m) {
  OfficeOptions options = without_people(first);
  options.rooms_per_row = rooms_per_row;
  options.width_m = width_m;
  return options;
}

}  // namespace

WorldWithRoute building_yard_world(const OfficeOptions& building, const BuildingYardOptions& yard) {
  WorldWithRoute result;
  result.world.name = "building-yard";
  const OfficeFloor floor(without_people(building));
  add_office_floor(result.world, floor, {yard.door_width_m, yard.door_width_m});
  const double W = floor.width_m();
  const double H = floor.depth_m();
  const double d = yard.yard_offset_m;
  const double door_y = floor.side_door_y();
  result.regions = {{"building", floor.bounds()}};
  result.outside_region = "yard";
  result.doors = {{"A", {0.0, door_y}, {-1.0, 0.0}, yard.door_width_m}, {"B", {W, door_y}, {1.0, 0.0}, yard.door_width_m}};

  // Round the yard with the building on the right: it stays behind or beside the robot, at
  // least d away, until the approach to door B.
  const std::vector<Vector2> yard_path = {{0.0, door_y}, {-d, door_y}, {-d, H + d}, {W + d, H + d}, {W + d, door_y},
                                          {W, door_y}};
  Random random(yard.world_seed);
  add_sparse_features(result.world, yard_path, yard.features, 3.0, 10.0, false, random);

  result.route = floor.lap_route();
  result.route.back() = {floor.x_west(), door_y};  // the last loop turns out through door A
  for (std::size_t i = 1; i + 1 < yard_path.size(); ++i) result.route.push_back(yard_path[i]);
  result.route.push_back({floor.x_east(), door_y});  // in through door B
  result.route.push_back({floor.x_east(), floor.y_top()});
  result.route.push_back({floor.x_west(), floor.y_top()});
  result.route.push_back({floor.x_west(), floor.y_bottom()});
  result.route.push_back(floor.lap_route().front());
  result.closed_route = false;
  return result;
}

WorldWithRoute building_yard_second_session(const OfficeOptions& building, const BuildingYardOptions& yard,
                                            const SessionStartOptions& start) {
  WorldWithRoute result = building_yard_world(building, yard);
  const OfficeFloor floor(without_people(building));
  const auto center = floor.place_center(start.place);
  CAIRN_ASSERT(center.has_value(), "building_yard_second_session: unknown start place (check is_valid first)");
  const Vector2 exit = floor.place_exit(start.place);
  const bool from_bottom = std::abs(exit.y() - floor.y_bottom()) < 1e-9;
  // Across the block from the exit's corridor: a room the first session went into.
  const std::string across = from_bottom ? "top-room-" + std::to_string(floor.options().rooms_per_row - 2)
                                         : "bottom-room-1";
  const Vector2 room = *floor.place_center(across);
  const double y_here = from_bottom ? floor.y_bottom() : floor.y_top();
  const double y_there = from_bottom ? floor.y_top() : floor.y_bottom();

  result.route = {*center, exit};
  const std::vector<Vector2> ring = floor.ring_from(exit, false);
  result.route.insert(result.route.end(), ring.begin(), ring.end());
  result.route.push_back({floor.middle_x(), y_here});
  result.route.push_back({floor.middle_x(), y_there});
  result.route.push_back({room.x(), y_there});
  result.route.push_back(room);
  result.route.push_back({room.x(), y_there});
  // A look out of door B (the first session came in through it): 6 m into the yard, turn on the
  // spot, back into the east corridor.
  const double door_y = floor.side_door_y();
  result.route.push_back({floor.x_east(), y_there});
  result.route.push_back({floor.x_east(), door_y});
  result.route.push_back({floor.width_m() + 6.0, door_y});
  result.route.push_back({floor.x_east(), door_y});
  result.start_heading_rad = start.heading_rad;
  result.closed_route = false;
  return result;
}

WorldWithRoute outdoor_stretch_world(const OfficeOptions& building_1, const OutdoorStretchOptions& options) {
  WorldWithRoute result;
  result.world.name = "outdoor-stretch";
  const OfficeFloor first(without_people(building_1));
  // Building 2 sits so that its west door faces building 1's east door: the path is straight.
  const OfficeOptions second_options = variant(building_1, options.building_2_rooms_per_row, options.building_2_width_m);
  const double second_door_height = OfficeFloor(second_options).side_door_y();
  const double door_y = first.side_door_y();
  const double x_second = first.width_m() + options.path_length_m;
  const OfficeFloor second(second_options, {x_second, door_y - second_door_height});
  add_office_floor(result.world, first, {0.0, options.door_width_m});
  add_office_floor(result.world, second, {options.door_width_m, 0.0});
  if (options.glass_facades) {
    for (Segment& wall : result.world.walls) {
      const bool vertical = std::abs(wall.a.x() - wall.b.x()) < 1e-9;
      const bool facing = std::abs(wall.a.x() - first.width_m()) < 1e-9 || std::abs(wall.a.x() - x_second) < 1e-9;
      if (vertical && facing) wall.glass = true;
    }
  }
  result.regions = {{"building-1", first.bounds()}, {"building-2", second.bounds()}};
  result.outside_region = "path";
  result.doors = {{"building-1", {first.width_m(), door_y}, {1.0, 0.0}, options.door_width_m},
                  {"building-2", {x_second, door_y}, {-1.0, 0.0}, options.door_width_m}};
  Random random(options.world_seed);
  add_sparse_features(result.world, {{first.width_m(), door_y}, {x_second, door_y}}, options.features, 3.0, 8.0, true,
                      random);

  result.route = lap_to_east_door(first);
  append_tour_from_west_door(second, 1, result.route);
  append_return_through_east_door(first, result.route);
  result.closed_route = false;
  return result;
}

WorldWithRoute two_wing_world(const OfficeOptions& west_wing, const TwoWingOptions& options) {
  WorldWithRoute result;
  result.world.name = "long-absence";
  const OfficeFloor west(without_people(west_wing));
  const OfficeOptions east_options = variant(west_wing, options.east_wing_rooms_per_row, options.east_wing_width_m);
  const double east_door_height = OfficeFloor(east_options).side_door_y();
  const double door_y = west.side_door_y();
  const double x_east = west.width_m() + options.connector_length_m;
  const OfficeFloor east(east_options, {x_east, door_y - east_door_height});
  add_office_floor(result.world, west, {0.0, options.door_width_m});
  add_office_floor(result.world, east, {options.door_width_m, 0.0});
  // The connector's side walls meet the two facades beside the doors.
  const double half = 0.5 * options.connector_width_m;
  result.world.add_wall({west.width_m(), door_y - half}, {x_east, door_y - half});
  result.world.add_wall({west.width_m(), door_y + half}, {x_east, door_y + half});
  result.regions = {{"west-wing", west.bounds()},
                    {"connector", {{west.width_m(), door_y - half}, {x_east, door_y + half}}},
                    {"east-wing", east.bounds()}};
  result.outside_region = "outside";
  result.doors = {{"west-wing", {west.width_m(), door_y}, {1.0, 0.0}, options.door_width_m},
                  {"east-wing", {x_east, door_y}, {-1.0, 0.0}, options.door_width_m}};

  result.route = lap_to_east_door(west);
  append_tour_from_west_door(east, options.away_laps, result.route);
  append_return_through_east_door(west, result.route);
  result.closed_route = false;
  return result;
}

}  // namespace cairn::sim
