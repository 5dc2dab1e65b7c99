#include "cairn/sim/passage_worlds.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/sim/random.hpp"

namespace cairn::sim {
namespace {

Box box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return Box{Vector3(std::min(x0, x1), std::min(y0, y1), z0), Vector3(std::max(x0, x1), std::max(y0, y1), z1)};
}

/// A road along y = 0 from x0 to x1: on each side seeded buildings (fronts 10-14 m from the
/// centre line, 6-14 m long, 4-16 m high, gaps of 1-6 m), lamp poles 6.5 m out every 8-16 m and
/// trees 8 m out every 6-14 m, so every stretch of road looks different.
void add_roadside(World3D& world, double x0, double x1, Random& random) {
  for (const double side : {1.0, -1.0}) {
    for (double x = x0 + random.uniform(0.0, 3.0); x < x1 - 4.0;) {
      const double length = std::min(random.uniform(6.0, 14.0), x1 - x);
      const double front = random.uniform(10.0, 14.0);
      world.boxes.push_back(box(x, side * front, 0.0, x + length, side * (front + 8.0), random.uniform(4.0, 16.0)));
      x += length + random.uniform(1.0, 6.0);
    }
    for (double x = x0 + random.uniform(2.0, 8.0); x < x1 - 1.0; x += random.uniform(8.0, 16.0)) {
      world.cylinders.push_back({Vector2(x, side * 6.5), 0.12, 0.0, 6.0});
    }
    for (double x = x0 + random.uniform(2.0, 8.0); x < x1 - 1.5; x += random.uniform(6.0, 14.0)) {
      world.cylinders.push_back({Vector2(x, side * 8.0), 0.2, 0.0, 2.5});
      world.cylinders.push_back({Vector2(x, side * 8.0), random.uniform(0.8, 1.6), 2.5, random.uniform(4.0, 7.0)});
    }
  }
}

}  // namespace

World3DWithRoute garage_world(const GarageOptions& o) {
  World3DWithRoute result;
  World3D& world = result.world;
  world.name = "garage-3d";
  world.ground = true;
  const double L = o.length_m;
  const double w = o.half_width_m;
  const double H = o.ceiling_height_m;
  constexpr double kWall = 0.3;
  constexpr double kDoorHalfWidth = 3.0;
  constexpr double kDoorHeight = 2.4;
  world.boxes.push_back(box(0.0, -w - kWall, H, L, w + kWall, H + kWall));  // ceiling slab
  world.boxes.push_back(box(0.0, w, 0.0, L, w + kWall, H));                 // side walls
  world.boxes.push_back(box(0.0, -w - kWall, 0.0, L, -w, H));
  for (const double x : {-kWall, L}) {  // end walls with an entrance
    world.boxes.push_back(box(x, kDoorHalfWidth, 0.0, x + kWall, w + kWall, H));
    world.boxes.push_back(box(x, -w - kWall, 0.0, x + kWall, -kDoorHalfWidth, H));
    world.boxes.push_back(box(x, -kDoorHalfWidth, kDoorHeight, x + kWall, kDoorHalfWidth, H));
  }
  // Pillars (0.6 m square, their inner faces 3.5 m from the aisle centre) and ceiling beams
  // every bay_pitch_m; between neighbouring pillars, identical cars parked nose-in, 2.5 m apart.
  const double p = o.bay_pitch_m;
  const int cars_per_bay = static_cast<int>(std::floor((p - 0.6) / 2.5));
  for (double x = 0.5 * p; x < L - 0.3; x += p) {
    for (const double side : {1.0, -1.0}) {
      world.boxes.push_back(box(x - 0.3, side * 3.5, 0.0, x + 0.3, side * 4.1, H));
      if (x + p < L - 0.3) {
        const double first = x + 0.5 * p - 1.25 * (cars_per_bay - 1);
        for (int c = 0; c < cars_per_bay; ++c) {
          const double cx = first + 2.5 * c;
          world.boxes.push_back(box(cx - 0.9, side * (w - 0.5), 0.0, cx + 0.9, side * (w - 5.0), 1.5));
        }
      }
    }
    world.boxes.push_back(box(x - 0.2, -w, H - 0.5, x + 0.2, w, H));
  }
  Random random(o.world_seed);
  add_roadside(world, -o.approach_m, -kWall - 1.0, random);
  add_roadside(world, L + kWall + 1.0, L + o.approach_m, random);
  result.route = {{-o.approach_m, 0.0}, {L + o.approach_m, 0.0}};
  result.closed_route = false;
  result.passage = Passage3D{"garage", Vector2::Zero(), Vector2::UnitX(), L};
  return result;
}

World3DWithRoute tunnel_world(const TunnelOptions& o) {
  World3DWithRoute result;
  World3D& world = result.world;
  world.name = "tunnel-3d";
  world.ground = true;
  const double L = o.length_m;
  const double w = o.half_width_m;
  const double H = o.height_m;
  constexpr double kWall = 0.5;
  world.boxes.push_back(box(0.0, w, 0.0, L, w + kWall, H));
  world.boxes.push_back(box(0.0, -w - kWall, 0.0, L, -w, H));
  world.boxes.push_back(box(0.0, -w - kWall, H, L, w + kWall, H + kWall));
  // Portals: a hillside face 25 m wide on each side of the opening and 6 m above it.
  for (const double x : {-1.0, L}) {
    world.boxes.push_back(box(x, w, 0.0, x + 1.0, w + 25.0, H + 6.0));
    world.boxes.push_back(box(x, -w - 25.0, 0.0, x + 1.0, -w, H + 6.0));
    world.boxes.push_back(box(x, -w, H, x + 1.0, w, H + 6.0));
  }
  Random random(o.world_seed);
  add_roadside(world, -o.approach_m, -2.0, random);
  add_roadside(world, L + 2.0, L + o.approach_m, random);
  result.route = {{-o.approach_m, 0.0}, {L + o.approach_m, 0.0}};
  result.closed_route = false;
  result.passage = Passage3D{"tunnel", Vector2::Zero(), Vector2::UnitX(), L};
  return result;
}

}  // namespace cairn::sim
