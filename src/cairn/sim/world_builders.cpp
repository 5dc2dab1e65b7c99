#include "cairn/sim/world_builders.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "cairn/core/assert.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

/// Distance from `point` to the closed polyline `route`.
double distance_to_route(const std::vector<Vector2>& route, const Vector2& point) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < route.size(); ++i) {
    const Vector2& a = route[i];
    const Vector2& b = route[(i + 1) % route.size()];
    const Vector2 ab = b - a;
    const double t = std::clamp((point - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * ab - point).norm());
  }
  return best;
}

/// A door recess: an opening of `width` in a wall whose outward normal (away from the corridor)
/// is `normal`, centred at `center` on the wall line, with a box of depth `depth` behind it.
void add_recess(World& world, const Vector2& center, const Vector2& along, const Vector2& normal, double width,
                double depth) {
  const Vector2 left = center - 0.5 * width * along;
  const Vector2 right = center + 0.5 * width * along;
  world.add_wall(left, left + depth * normal);
  world.add_wall(left + depth * normal, right + depth * normal);
  world.add_wall(right + depth * normal, right);
}

/// A solid axis-aligned box (desk, parked car).
void add_box(World& world, const Vector2& min, const Vector2& max) { world.add_rectangle(min, max); }

}  // namespace

std::string WorldWithRoute::region_at(const Vector2& point) const {
  for (const auto& region : regions) {
    if ((point.array() >= region.bounds.min.array()).all() && (point.array() <= region.bounds.max.array()).all()) {
      return region.name;
    }
  }
  return outside_region;
}

WorldWithRoute office_world(const OfficeOptions& o) {
  CAIRN_ASSERT(o.rooms_per_row >= 2, "office_world: at least two rooms per row");
  WorldWithRoute result;
  result.world.name = "office";
  const OfficeFloor floor(o);
  add_office_floor(result.world, floor);
  result.route = floor.lap_route();
  return result;
}

WorldWithRoute corridor_world(const CorridorOptions& o) {
  WorldWithRoute result;
  World& world = result.world;
  world.name = "corridor-aliasing";
  const double L = o.length_m;
  const double w = o.width_m;
  const double H = 2 * w + o.block_depth_m;
  // Door centres along x, identical on all four long walls.
  std::vector<double> door_x;
  for (double x = w + 2.0; x + 0.5 * o.door_width_m <= L - w - 1.5; x += o.door_pitch_m) door_x.push_back(x);
  auto gaps_from = [&](double x0) {
    std::vector<std::pair<double, double>> gaps;
    for (double x : door_x) gaps.emplace_back(x - x0, o.door_width_m);
    return gaps;
  };
  const Vector2 ex(1, 0);
  const Vector2 ey(0, 1);
  // Outer walls: the bottom and top carry doors, the left end carries one wide alcove that
  // breaks the ring's 180-degree symmetry (so the two long corridors are not globally identical).
  world.add_wall_with_gaps({0, 0}, {L, 0}, gaps_from(0));
  world.add_wall_with_gaps({0, H}, {L, H}, gaps_from(0));
  world.add_wall({L, 0}, {L, H});
  world.add_wall_with_gaps({0, 0}, {0, H}, {{0.5 * H, 2.0}});
  add_recess(world, {0, 0.5 * H}, ey, -ex, 2.0, 1.0);
  // Inner block.
  world.add_wall_with_gaps({w, w}, {L - w, w}, gaps_from(w));
  world.add_wall_with_gaps({w, H - w}, {L - w, H - w}, gaps_from(w));
  world.add_wall({w, w}, {w, H - w});
  world.add_wall({L - w, w}, {L - w, H - w});
  for (double x : door_x) {
    add_recess(world, {x, 0}, ex, -ey, o.door_width_m, o.door_recess_m);
    add_recess(world, {x, H}, ex, ey, o.door_width_m, o.door_recess_m);
    add_recess(world, {x, w}, ex, ey, o.door_width_m, o.door_recess_m);
    add_recess(world, {x, H - w}, ex, -ey, o.door_width_m, o.door_recess_m);
  }
  const double half = 0.5 * w;
  result.route = {{w + 1.0, half}, {L - half, half}, {L - half, H - half}, {half, H - half}, {half, half}};
  return result;
}

WorldWithRoute open_hall_world(const OpenHallOptions& o) {
  WorldWithRoute result;
  World& world = result.world;
  world.name = "open-hall";
  const double W = o.width_m;
  const double D = o.depth_m;
  world.add_rectangle({0, 0}, {W, D});
  // Pillars inside the route rectangle first, then near the hall's corners.
  static constexpr std::array<std::array<double, 2>, 8> kPattern = {{{0.35, 0.40},
                                                                     {0.65, 0.60},
                                                                     {0.40, 0.62},
                                                                     {0.60, 0.38},
                                                                     {0.08, 0.10},
                                                                     {0.92, 0.90},
                                                                     {0.08, 0.90},
                                                                     {0.92, 0.10}}};
  const int pillars = std::clamp(o.pillars, 0, 8);
  for (int i = 0; i < pillars; ++i) {
    world.circles.push_back({{kPattern[i][0] * W, kPattern[i][1] * D}, o.pillar_radius_m});
  }
  const double x0 = 0.5 * (W - o.route_width_m);
  const double y0 = 0.5 * (D - o.route_depth_m);
  result.route = {{x0, y0}, {x0 + o.route_width_m, y0}, {x0 + o.route_width_m, y0 + o.route_depth_m},
                  {x0, y0 + o.route_depth_m}};
  return result;
}

WorldWithRoute building_loop_world(const BuildingLoopOptions& o) {
  WorldWithRoute result;
  World& world = result.world;
  world.name = "loop-building";
  const double W = o.building_width_m;
  const double D = o.building_depth_m;
  const Vector2 ex(1, 0);
  const Vector2 ey(0, 1);
  // Facade with recessed entrances (3 m wide, 0.8 m deep) at fixed fractions of each side.
  const std::vector<std::pair<double, double>> long_side = {{0.3 * W, 3.0}, {0.75 * W, 3.0}};
  const std::vector<std::pair<double, double>> short_side = {{0.5 * D, 3.0}};
  world.add_wall_with_gaps({0, 0}, {W, 0}, long_side);
  world.add_wall_with_gaps({W, 0}, {W, D}, short_side);
  world.add_wall_with_gaps({W, D}, {0, D}, {{0.4 * W, 3.0}});
  world.add_wall_with_gaps({0, D}, {0, 0}, short_side);
  add_recess(world, {0.3 * W, 0}, ex, ey, 3.0, 0.8);
  add_recess(world, {0.75 * W, 0}, ex, ey, 3.0, 0.8);
  add_recess(world, {W, 0.5 * D}, ey, -ex, 3.0, 0.8);
  add_recess(world, {0.6 * W, D}, ex, -ey, 3.0, 0.8);
  add_recess(world, {0, 0.5 * D}, ey, ex, 3.0, 0.8);
  // Columns along the south facade.
  for (double x = 4.0; x < W - 2.0; x += 8.0) world.circles.push_back({{x, -0.6}, 0.3});

  const double s = o.street_offset_m;
  // Start half-way along the south street, so a single lap ends where and as it started
  // (same heading): the one loop closure of the run.
  result.route = {{0.5 * W, -s}, {W + s, -s}, {W + s, D + s}, {-s, D + s}, {-s, -s}};

  // Trees 2.5-4.5 m beyond the route, parked boxes (cars) at fixed places on the same side.
  Random random(o.world_seed);
  const double perimeter = 2 * (W + 2 * s) + 2 * (D + 2 * s);
  const int trees = static_cast<int>(std::floor(o.trees_per_m * perimeter));
  for (int i = 0; i < trees; ++i) {
    // A point on the route rectangle, pushed outwards.
    const double along = random.uniform(0.0, perimeter);
    const double out = random.uniform(2.5, 4.5);
    Vector2 p;
    const double a = W + 2 * s;
    const double b = D + 2 * s;
    if (along < a) p = {-s + along, -s - out};
    else if (along < a + b) p = {W + s + out, -s + (along - a)};
    else if (along < 2 * a + b) p = {W + s - (along - a - b), D + s + out};
    else p = {-s - out, D + s - (along - 2 * a - b)};
    world.circles.push_back({p, 0.25});
  }
  add_box(world, {0.2 * W, -s - 3.3}, {0.2 * W + 4.5, -s - 1.5});
  add_box(world, {W + s + 1.5, 0.6 * D}, {W + s + 3.3, 0.6 * D + 4.5});
  add_box(world, {0.5 * W, D + s + 1.5}, {0.5 * W + 4.5, D + s + 3.3});
  return result;
}

WorldWithRoute landmark_field_world(const LandmarkFieldOptions& o) {
  WorldWithRoute result;
  World& world = result.world;
  world.name = "landmarks";
  result.route = {{0, 0}, {o.route_width_m, 0}, {o.route_width_m, o.route_depth_m}, {0, o.route_depth_m}};
  Random random(o.world_seed);
  const double margin = o.max_distance_from_route_m;
  std::int64_t id = 0;
  // Rejection sampling; the loop is bounded because the accepted band has positive area.
  while (id < o.landmarks) {
    const Vector2 p(random.uniform(-margin, o.route_width_m + margin), random.uniform(-margin, o.route_depth_m + margin));
    const double d = distance_to_route(result.route, p);
    if (d < o.min_distance_from_route_m || d > o.max_distance_from_route_m) continue;
    world.landmarks.push_back({id++, p});
    if (o.post_radius_m > 0.0) world.circles.push_back({p, o.post_radius_m});
  }
  return result;
}

}  // namespace cairn::sim
