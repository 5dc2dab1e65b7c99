// Ray casting against analytic geometry: every expected value below is worked out by hand (or
// from an independent closed form), never by the code under test.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cairn/sim/lidar.hpp"
#include "cairn/sim/ray_cast.hpp"
#include "cairn/sim/world_builders.hpp"

namespace cairn::sim {
namespace {

const Vector2 kOrigin(0.0, 0.0);
const Vector2 kEast(1.0, 0.0);

TEST(RayCastSegment, PerpendicularWallAtIntegerDistanceIsExact) {
  // origin + t (1, 0) meets x = 2 at t = 2; every step of Cramer's rule is exact here.
  const auto t = intersect(kOrigin, kEast, Segment{{2, -1}, {2, 1}});
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(*t, 2.0);
}

TEST(RayCastSegment, DiagonalRay) {
  // Direction 45 degrees, wall x = 3: the hit is (3, 3), at distance 3 sqrt(2).
  const Vector2 d(std::sqrt(0.5), std::sqrt(0.5));
  const auto t = intersect(kOrigin, d, Segment{{3, -10}, {3, 10}});
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(*t, 3.0 * std::numbers::sqrt2, 1e-14);
}

TEST(RayCastSegment, EndpointsCountAsHits) {
  EXPECT_EQ(intersect(kOrigin, kEast, Segment{{4, 0}, {4, 1}}).value_or(-1), 4.0);
  EXPECT_EQ(intersect(kOrigin, kEast, Segment{{5, -1}, {5, 0}}).value_or(-1), 5.0);
}

TEST(RayCastSegment, Misses) {
  EXPECT_FALSE(intersect(kOrigin, kEast, Segment{{2, 0.5}, {2, 1}}));    // passes below the segment
  EXPECT_FALSE(intersect(kOrigin, kEast, Segment{{-2, -1}, {-2, 1}}));  // behind the origin
  EXPECT_FALSE(intersect(kOrigin, kEast, Segment{{1, 1}, {5, 1}}));     // parallel
  EXPECT_FALSE(intersect(kOrigin, kEast, Segment{{1, 0}, {5, 0}}));     // along the ray: no surface
}

TEST(RayCastCircle, HeadOnTangentInsideAndMiss) {
  const Circle circle{{5, 0}, 1.0};
  EXPECT_EQ(intersect(kOrigin, kEast, circle).value_or(-1), 4.0);
  // Tangent at (5, 1): discriminant exactly 0.
  EXPECT_EQ(intersect(Vector2(0, 1), kEast, circle).value_or(-1), 5.0);
  EXPECT_FALSE(intersect(Vector2(0, 1.5), kEast, circle));
  // From the centre the ray leaves through the boundary at distance r.
  EXPECT_EQ(intersect(Vector2(5, 0), kEast, circle).value_or(-1), 1.0);
  // Pointing away from a circle behind the origin.
  EXPECT_FALSE(intersect(Vector2(7, 0), kEast, circle));
}

TEST(RayCastCircle, ObliqueThreeFourFive) {
  // Centre (3, 4) at distance 5 along (0.6, 0.8), radius 1: the near hit is at 4.
  const auto t = intersect(kOrigin, Vector2(0.6, 0.8), Circle{{3, 4}, 1.0});
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(*t, 4.0, 1e-15);
}

TEST(RayCastWorld, NearestOfWallsAndCirclesAndMaxRange) {
  World world;
  world.add_rectangle({-1, -2}, {4, 2});
  EXPECT_EQ(cast_ray(world, kOrigin, kEast, 30)->range_m, 4.0);
  EXPECT_EQ(cast_ray(world, kOrigin, Vector2(-1, 0), 30)->range_m, 1.0);
  EXPECT_EQ(cast_ray(world, kOrigin, Vector2(0, 1), 30)->range_m, 2.0);
  EXPECT_FALSE(cast_ray(world, kOrigin, kEast, 3.5).has_value());  // beyond max range
  world.circles.push_back({{2, 0}, 0.5});
  const auto hit = cast_ray(world, kOrigin, kEast, 30);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->range_m, 1.5);
  EXPECT_EQ(hit->point, Vector2(1.5, 0));
}

// A glass pane at x = 2 between a wall at x = 5 and one at x = -3 behind the laser. A beam within
// 15 degrees of the pane's normal returns from the glass (2 / cos); between 15 and 60 degrees it
// passes through to the wall at x = 5 (5 / cos); beyond 60 degrees it is mirrored back to the wall
// at x = -3 and reads its whole path, (2 + 5) / cos: a phantom point behind the pane. Cameras and
// line of sight (cast_ray) see through the glass at any angle.
TEST(RayCastWorld, GlassReturnsNearItsNormalMirrorsGrazingBeamsAndPassesTheRest) {
  World world;
  world.add_glass({2, -40}, {2, 40});
  world.add_wall({5, -40}, {5, 40});
  world.add_wall({-3, -40}, {-3, 40});
  ASSERT_TRUE(world.walls[0].glass);
  ASSERT_FALSE(world.walls[1].glass);
  for (const double degrees : {0.0, 10.0, -14.9, 15.1, 30.0, -59.9, 60.1, 70.0, -75.0}) {
    const double angle = degrees * std::numbers::pi / 180.0;
    const Vector2 direction(std::cos(angle), std::sin(angle));
    const auto reading = cast_lidar_ray(world, kOrigin, direction, 60);
    ASSERT_TRUE(reading.has_value()) << degrees;
    const double a = std::abs(degrees);
    const double expected = (a <= 15.0 ? 2.0 : a < 60.0 ? 5.0 : 7.0) / std::cos(angle);
    EXPECT_NEAR(reading->range_m, expected, 1e-9) << degrees;
    EXPECT_NEAR((reading->point - expected * direction).norm(), 0.0, 1e-9) << degrees;  // along the beam as emitted
    EXPECT_NEAR(cast_ray(world, kOrigin, direction, 60)->range_m, 5.0 / std::cos(angle), 1e-9) << degrees;
  }
  // The mirrored path counts against the range: 7 / cos(70 deg) = 20.5 m is beyond 20 m.
  const double seventy = 70.0 * std::numbers::pi / 180.0;
  EXPECT_FALSE(cast_lidar_ray(world, kOrigin, Vector2(std::cos(seventy), std::sin(seventy)), 20).has_value());
  world.glass_return_max_incidence_rad = 5.0 * std::numbers::pi / 180.0;  // a narrower cone
  const double ten = 10.0 * std::numbers::pi / 180.0;
  EXPECT_NEAR(cast_lidar_ray(world, kOrigin, Vector2(std::cos(ten), std::sin(ten)), 60)->range_m, 5.0 / std::cos(ten), 1e-9);
  // For the robot a pane is as solid as a wall.
  EXPECT_NEAR(world.clearance(Vector2(1.5, 0.0)), 0.5, 1e-12);
}

TEST(RayCastWorld, LineOfSight) {
  World world;
  world.add_wall({2, -1}, {2, 1});
  EXPECT_FALSE(line_of_sight(world, kOrigin, Vector2(3, 0)));
  EXPECT_TRUE(line_of_sight(world, kOrigin, Vector2(1.9, 0)));
  EXPECT_TRUE(line_of_sight(world, kOrigin, Vector2(3, 3)));
}

TEST(IdealScan, SquareRoomMatchesClosedForm) {
  // A laser at the centre of a square of half-side a sees, at angle phi, the distance
  // a / max(|cos phi|, |sin phi|).
  const double a = 3.0;
  World world;
  world.add_rectangle({-a, -a}, {a, a});
  LidarOptions options;
  options.beams = 360;
  options.angle_min_rad = -std::numbers::pi;
  options.angle_increment_rad = std::numbers::pi / 180;
  options.max_range_m = 30;
  const double heading = 0.3;
  const auto ranges = ideal_scan(world, core::SE2(0, 0, heading), options);
  ASSERT_EQ(ranges.size(), 360u);
  for (int i = 0; i < options.beams; ++i) {
    const double phi = heading + options.beam_angle(i);
    const double expected = a / std::max(std::abs(std::cos(phi)), std::abs(std::sin(phi)));
    EXPECT_NEAR(ranges[static_cast<std::size_t>(i)], expected, 1e-12) << "beam " << i;
  }
}

TEST(IdealScan, MissesReadMaxRangeAndLaserOffsetIsApplied) {
  World world;
  world.add_wall({5, -100}, {5, 100});
  LidarOptions options;
  options.beams = 3;
  options.angle_min_rad = -std::numbers::pi / 2;
  options.angle_increment_rad = std::numbers::pi / 2;  // right, forward, left
  options.max_range_m = 10;
  options.forward_offset_m = 0.5;
  const core::SE2 T_world_laser = core::SE2(1, 0, 0) * options.T_body_laser();
  const auto ranges = ideal_scan(world, T_world_laser, options);
  EXPECT_EQ(ranges[0], 10.0);
  EXPECT_EQ(ranges[1], 3.5);  // 5 - (1 + 0.5)
  EXPECT_EQ(ranges[2], 10.0);
}

TEST(Walker, WalksBackAndForthAtItsSpeed) {
  const Walker walker{{0, 0}, {4, 0}, 1.0, 0.25, 0.0};
  EXPECT_EQ(walker.at(1.0).center, Vector2(1, 0));
  EXPECT_EQ(walker.at(5.0).center, Vector2(3, 0));  // 4 m out, 1 m back
  EXPECT_EQ(walker.at(8.0).center, Vector2(0, 0));
  EXPECT_EQ(Walker({{0, 0}, {4, 0}, 1.0, 0.25, 2.0}).at(1.0).center, Vector2(3, 0));  // phase shifts time
  EXPECT_EQ(walker.at(1.0).radius_m, 0.25);
}

TEST(IdealScan, SeesWalkersWhereTheyAreAtTheScanTime) {
  World world;
  world.add_wall({10, -10}, {10, 10});
  world.walkers.push_back({{5, -3}, {5, 3}, 1.0, 0.25, 0.0});
  LidarOptions options;
  options.beams = 1;
  options.angle_min_rad = 0.0;
  const core::SE2 T_world_laser;
  EXPECT_EQ(ideal_scan(world, T_world_laser, options, 0.0)[0], 10.0);  // walker at (5, -3)
  EXPECT_EQ(ideal_scan(world, T_world_laser, options, 3.0)[0], 4.75);  // walker at (5, 0)
}

TEST(CorridorWorld, ScansOneDoorPitchApartAreIdentical) {
  // Perceptual aliasing, measured: with an 8 m range the corridor looks the same from two
  // places one door pitch apart, so no scan matcher can tell them apart.
  const CorridorOptions options;
  const WorldWithRoute corridor = corridor_world(options);
  LidarOptions lidar;
  lidar.max_range_m = 8.0;
  const double y = 0.5 * options.width_m;
  const auto a = ideal_scan(corridor.world, core::SE2(20.2, y, 0.0), lidar);
  const auto b = ideal_scan(corridor.world, core::SE2(20.2 + options.door_pitch_m, y, 0.0), lidar);
  ASSERT_EQ(a.size(), b.size());
  std::size_t hits = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a[i], b[i], 1e-9) << "beam " << i;
    hits += a[i] < lidar.max_range_m ? 1 : 0;
  }
  EXPECT_GT(hits, a.size() / 2);  // and the scans are not empty
  // The door recesses show: some beams reach behind the wall line.
  std::size_t into_recess = 0;
  for (int i = 0; i < lidar.beams; ++i) {
    const double sin_angle = std::abs(std::sin(lidar.beam_angle(i)));
    const double r = a[static_cast<std::size_t>(i)];
    if (r < lidar.max_range_m && sin_angle > 0.2 && r * sin_angle > y + 1e-6) ++into_recess;
  }
  EXPECT_GT(into_recess, 0u);
}

}  // namespace
}  // namespace cairn::sim
