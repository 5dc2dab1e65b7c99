#include "cairn/sim/street_world.hpp"

#include <array>
#include <tuple>
#include <utility>
#include <cmath>

#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

constexpr double kBuildingDepth = 8.0;
constexpr double kPoleHeight = 6.0;
/// The landmark is the lamp, this far above the pole's top (so the pole does not hide it).
constexpr double kLampAbovePole = 0.3;

/// A box from a footprint given as a start point, a unit direction along the street, a length,
/// a unit normal away from the street, a depth, and a height.
Box footprint_box(const Vector2& start, const Vector2& along, double length, const Vector2& normal, double depth,
                  double z_min, double z_max) {
  const Vector2 a = start;
  const Vector2 b = start + length * along + depth * normal;
  return Box{Vector3(std::min(a.x(), b.x()), std::min(a.y(), b.y()), z_min),
             Vector3(std::max(a.x(), b.x()), std::max(a.y(), b.y()), z_max)};
}

}  // namespace

StreetWorld street_world(const StreetOptions& o) {
  StreetWorld result;
  World3D& world = result.world;
  world.name = "street-3d";
  world.ground = true;
  const double W = o.loop_width_m;
  const double D = o.loop_depth_m;
  const double h = o.street_half_width_m;
  result.route = {{0.5 * W, 0}, {W, 0}, {W, D}, {0, D}, {0, 0}};
  Random random(o.world_seed);

  // The four sides of a rectangle, counter-clockwise: start corner, direction, length.
  auto sides = [](double x0, double y0, double x1, double y1) {
    return std::array<std::tuple<Vector2, Vector2, double>, 4>{{{Vector2(x0, y0), Vector2(1, 0), x1 - x0},
                                                               {Vector2(x1, y0), Vector2(0, 1), y1 - y0},
                                                               {Vector2(x1, y1), Vector2(-1, 0), x1 - x0},
                                                               {Vector2(x0, y1), Vector2(0, -1), y1 - y0}}};
  };
  // Inner facades face outwards (normal into the block = left of the direction of travel for a
  // counter-clockwise rectangle); outer facades face inwards (normal = right).
  for (const bool inner : {true, false}) {
    const auto rectangle = inner ? sides(h, h, W - h, D - h) : sides(-h, -h, W + h, D + h);
    for (const auto& [corner, along, length] : rectangle) {
      const Vector2 left(-along.y(), along.x());
      const Vector2 normal = inner ? left : Vector2(-left);
      double s = 0.0;
      while (s < length - 2.0) {
        const double building = std::min(random.uniform(8.0, 16.0), length - s);
        const double height = random.uniform(o.min_building_height_m, o.max_building_height_m);
        world.boxes.push_back(footprint_box(corner + s * along, along, building, normal, kBuildingDepth, 0.0, height));
        s += building + random.uniform(0.0, 2.0);
      }
    }
  }

  // Poles on the inner sidewalk (1.5 m in front of the facades), trees on the outer one.
  const double sidewalk = h - 1.5;
  std::int64_t id = 0;
  for (const auto& [corner, along, length] : sides(sidewalk, sidewalk, W - sidewalk, D - sidewalk)) {
    for (double s = 0.5 * o.pole_spacing_m; s < length - 2.0; s += o.pole_spacing_m) {
      const Vector2 p = corner + s * along;
      world.cylinders.push_back({p, 0.12, 0.0, kPoleHeight});
      world.landmarks.push_back({id++, Vector3(p.x(), p.y(), kPoleHeight + kLampAbovePole)});
    }
  }
  const auto outer = sides(-sidewalk, -sidewalk, W + sidewalk, D + sidewalk);
  for (const auto& [corner, along, length] : outer) {
    for (double s = 0.5 * o.tree_spacing_m; s < length - 2.0; s += o.tree_spacing_m) {
      const Vector2 p = corner + s * along;
      world.cylinders.push_back({p, 0.2, 0.0, 2.5});
      world.cylinders.push_back({p, 1.2, 2.5, 5.0});
    }
  }
  // Parked cars: 4.5 m x 1.8 m x 1.5 m, their inner side 2.6 m from the centre line, away from
  // the corners.
  // Cars take whole 6 m slots so they never overlap; slots are drawn without repetition.
  std::vector<std::pair<std::size_t, int>> slots;
  for (std::size_t side = 0; side < 4; ++side) {
    const double usable = std::get<2>(outer[side]) - 2.0 * (sidewalk + 8.0);
    for (int slot = 0; slot < static_cast<int>(usable / 6.0); ++slot) slots.emplace_back(side, slot);
  }
  for (int i = 0; i < o.parked_cars && !slots.empty(); ++i) {
    const std::size_t pick = static_cast<std::size_t>(random.index(slots.size()));
    const auto [side, slot] = slots[pick];
    slots.erase(slots.begin() + static_cast<std::ptrdiff_t>(pick));
    const auto& [corner, along, length] = outer[side];
    const Vector2 right(along.y(), -along.x());
    const double s = sidewalk + 8.0 + 6.0 * slot + random.uniform(0.0, 1.5);
    const Vector2 kerb = corner + s * along + (sidewalk - 2.6) * (-right);
    // `corner` lies on the outer sidewalk line; step back towards the street by sidewalk - 2.6.
    world.boxes.push_back(footprint_box(kerb, along, 4.5, right, 1.8, 0.0, 1.5));
  }

  if (o.reverse_second_lap) {
    // On past the start, a U-turn over two quarter arcs into the inner lane, then clockwise.
    const double lane = o.reverse_lane_offset_m;
    result.closed_route = false;
    result.route.push_back({0.5 * W, 0});
    result.route.push_back({0.5 * W + 6.0, 0});
    result.route.push_back({0.5 * W + 6.0, lane});
    result.route.push_back({lane, lane});
    result.route.push_back({lane, D - lane});
    result.route.push_back({W - lane, D - lane});
    result.route.push_back({W - lane, lane});
    result.route.push_back({0.5 * W, lane});
  }
  // Moving cars: clockwise around the rectangle 1.5 m outside the centre line (oncoming
  // traffic on a counter-clockwise lap), evenly spaced along its perimeter.
  if (o.moving_cars > 0) {
    const double lane = 1.5;
    const std::vector<Vector2> path = {{-lane, -lane}, {-lane, D + lane}, {W + lane, D + lane}, {W + lane, -lane}};
    const double perimeter = 2.0 * (W + D + 4.0 * lane);
    const double offset = random.uniform(0.0, perimeter);
    for (int i = 0; i < o.moving_cars; ++i) {
      MovingBox car;
      car.path = path;
      car.speed_mps = o.moving_car_speed_mps;
      car.phase_m = offset + perimeter * i / o.moving_cars;
      world.moving_boxes.push_back(car);
    }
  }
  return result;
}

}  // namespace cairn::sim
