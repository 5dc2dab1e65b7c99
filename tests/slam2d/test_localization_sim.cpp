// Issue 20 in simulation: a map saved by Slam2d, then a kidnapped robot relocalised in it by
// Localizer2d, over ten seeds, against the simulator's exact ground truth. docs/slam2d.md ("Map
// reuse and localisation", "Measured") records the numbers.
//
// The world: the office plan (office_world) furnished with cabinets and shelves at irregular
// places (OfficeOptions::furnished), so that every part of the ring corridor looks different. The plain
// office is half-turn symmetric but for one pillar: there two places explain every scan and the
// right outcome is to stay lost (the `kidnapping` scenario; docs/slam2d.md). Real buildings are
// furnished; the furniture is what makes a place identifiable at all.
//
// Per seed: a map run (one office lap, Slam2d, the map written to a .cmap file and read back),
// then a second run with other noise through the same world: from the office start, localised
// from no prior, picked up after a while and put down elsewhere (the odometry shows no motion
// across the jump): on the ring corridor (KidnappedRobotThreeSeeds in `make test`, all ten on demand) or in a room, mostly unmapped
// (KidnappedIntoRoomsFourSeeds in `make test`, all ten on demand). The seed sets the noise of both runs, the
// time of the pick-up, where the robot is put down and its heading.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "cairn/io/carmen_log.hpp"
#include "cairn/sim/carmen_log.hpp"
#include "cairn/sim/kidnap.hpp"
#include "cairn/sim/lidar.hpp"
#include "cairn/sim/odometry.hpp"
#include "cairn/sim/office_floor.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/trajectory.hpp"
#include "cairn/sim/world_builders.hpp"
#include "cairn/slam2d/localization.hpp"
#include "cairn/slam2d/map_file.hpp"
#include "cairn/slam2d/slam.hpp"

namespace cairn::slam2d {
namespace {

namespace fs = std::filesystem;
using cairn::Vector2;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn-test-localization-sim-" + name + "-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

struct SimulatedLog {
  std::vector<sim::TrajectorySample> truth;
  std::vector<std::size_t> scan_samples;
  io::CarmenLog log;  ///< as the CLI reads it: written by sim::write_carmen, read back
  std::optional<std::size_t> first_scan_after_jump;
};

// The sensors of the simulator's scenarios (scenario.cpp's simulate with default settings): wheel
// odometry, a 180-beam LiDAR at 10 Hz; `carried` lists the truth samples reached by a carry.
SimulatedLog simulate_log(const sim::World& world, std::vector<sim::TrajectorySample> truth,
                          const std::vector<std::size_t>& carried, std::uint64_t seed, const fs::path& dir) {
  SimulatedLog out;
  out.truth = std::move(truth);
  const sim::OdometryNoise noise;
  const sim::LidarOptions lidar;
  const sim::TrajectoryOptions trajectory;
  const sim::OdometryTrack odometry =
      sim::simulate_odometry(out.truth, noise, sim::Random::derive_seed(seed, 1), carried);
  sim::Random lidar_random(sim::Random::derive_seed(seed, 2));
  const auto scan_step = static_cast<std::size_t>(std::llround(lidar.period_s / trajectory.sample_period_s));
  const auto odometry_step = static_cast<std::size_t>(std::llround(0.05 / trajectory.sample_period_s));
  sim::CarmenLog log;
  log.lidar = lidar;
  for (std::size_t k = 0; k < out.truth.size(); k += odometry_step)
    log.odometry.push_back({out.truth[k].stamp, odometry.poses[k], 0.0, 0.0});
  for (std::size_t k = 0; k < out.truth.size(); k += scan_step) {
    const core::SE2 T_world_laser = out.truth[k].T_world_body * lidar.T_body_laser();
    std::vector<double> ranges = sim::add_scan_noise(sim::ideal_scan(world, T_world_laser, lidar), lidar, lidar_random);
    if (!carried.empty() && k >= carried.front() && !out.first_scan_after_jump) out.first_scan_after_jump = out.scan_samples.size();
    out.scan_samples.push_back(k);
    log.scans.push_back({out.truth[k].stamp, std::move(ranges), odometry.poses[k] * lidar.T_body_laser(), odometry.poses[k]});
  }
  const std::string path = (dir / ("seed-" + std::to_string(seed) + ".clf")).string();
  sim::write_carmen(path, log);
  out.log = io::read_carmen_log(path);
  EXPECT_EQ(out.log.scans.size(), out.scan_samples.size());
  return out;
}

// The map's points in the map frame on a 10 cm hash grid: what fraction of a scan, placed at its
// true pose, lies within `distance_m` of the map (how much of what the robot sees the map holds).
class MapPoints {
 public:
  explicit MapPoints(const SavedMap2D& map) {
    for (const SavedSubmap& submap : map.submaps)
      for (const Eigen::Vector2d& p : submap.points_submap) {
        const Eigen::Vector2d q = submap.T_world_submap * p;
        cells_[key(cell(q.x()), cell(q.y()))].push_back(q);
      }
  }
  double explained_fraction(const io::LaserScan& scan, const core::SE2& T_map_laser, double min_range_m, double max_range_m,
                            double distance_m) const {
    int returns = 0, explained = 0;
    for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
      const double r = scan.ranges_m[i];
      if (!(r >= min_range_m && r < max_range_m)) continue;
      const double angle = scan.geometry.start_angle_rad + static_cast<double>(i) * scan.geometry.angular_resolution_rad;
      const Eigen::Vector2d q = T_map_laser * Eigen::Vector2d(r * std::cos(angle), r * std::sin(angle));
      ++returns;
      bool near = false;
      for (long di = -1; di <= 1 && !near; ++di)
        for (long dj = -1; dj <= 1 && !near; ++dj) {
          const auto it = cells_.find(key(cell(q.x()) + di, cell(q.y()) + dj));
          if (it == cells_.end()) continue;
          for (const Eigen::Vector2d& p : it->second)
            if ((p - q).squaredNorm() <= distance_m * distance_m) {
              near = true;
              break;
            }
        }
      explained += near ? 1 : 0;
    }
    return returns > 0 ? static_cast<double>(explained) / returns : 0.0;
  }

 private:
  static long cell(double v) { return static_cast<long>(std::floor(v / 0.1)); }
  static long long key(long i, long j) { return (static_cast<long long>(i) << 32) ^ static_cast<long long>(j & 0xffffffffL); }
  std::unordered_map<long long, std::vector<Eigen::Vector2d>> cells_;
};

// As in test_localization.cpp: a wrong pose is farther from the truth than the map can be off
// (the maps here are within a few centimetres of the truth).
bool wrong(const core::SE2& estimate, const core::SE2& truth) {
  const core::SE2 e = truth.inverse() * estimate;
  return e.translation().norm() > 0.5 || std::abs(e.angle()) > 5.0 * std::numbers::pi / 180.0;
}

struct SeedResult {
  std::uint64_t seed = 0;
  std::string drop_place;
  double pick_up_s = 0.0;
  double jump_m = 0.0;
  std::optional<std::size_t> start_fix;          ///< first relocalisation, scans from the first scan
  std::optional<std::size_t> noticed_after;      ///< scans from the jump to the first scan not `ok`
  std::optional<std::size_t> lost_after;         ///< scans from the jump to the first `lost`
  std::optional<std::size_t> mapped_view_after;  ///< scans from the jump to the first view the map holds
  std::optional<std::size_t> relocalised_after;  ///< scans from the jump to the relocalisation
  std::size_t wrong_relocalisations = 0, wrong_ok = 0, ok_scans = 0, scans = 0;
  double max_ok_error_m = 0.0;
  /// Acceptances the localiser refused (Localizer2dSummary): a partly mapped place fitted too,
  /// or the pose put scan points where another submap saw empty space.
  std::size_t partly_mapped_look_alikes = 0, refused_empty_space_elsewhere = 0;
  double map_s = 0.0, localise_s = 0.0, total_s = 0.0;
};

// How much of a scan must lie on the map (at its true pose) before it counts as seeing mapped
// structure: the localiser's own verification threshold (verification_min_inlier_fraction).
constexpr double kMappedView = 0.9;
// The localisation run ends this long after the jump: out of the room and along the ring.
constexpr double kAfterJumpS = 40.0;

// Where the second run's robot is put down: a point of the ring corridor (mapped, and told
// apart by its furniture) or the centre of a room (mostly unmapped: the map saw it through its
// door; see expect_relocalised_after_kidnappings_into_rooms).
enum class Drop { kRing, kRoom };

SeedResult run_seed(std::uint64_t seed, Drop drop, const fs::path& dir) {
  const auto start = std::chrono::steady_clock::now();
  SeedResult result;
  result.seed = seed;
  sim::OfficeOptions plan;
  plan.furnished = true;
  const sim::WorldWithRoute office = sim::office_world(plan);
  const sim::OfficeFloor floor(plan);
  sim::TrajectoryOptions one_lap;
  one_lap.laps = 1;

  // The map run: one office lap.
  const SimulatedLog mapping =
      simulate_log(office.world, sim::generate_trajectory(office.route, one_lap, office.closed_route), {}, seed, dir);
  Slam2d slam;
  for (const io::LaserScan& scan : mapping.log.scans) slam.add_scan(scan);
  slam.finish();
  const std::string map_path = (dir / ("seed-" + std::to_string(seed) + ".cmap")).string();
  write_saved_map(map_path, slam.export_map());
  const SavedMap2D map = read_saved_map(map_path);
  // The map frame is the one Slam2d fixed at its first scan: T_map_world from that scan.
  const sim::LidarOptions lidar;
  const core::SE2 T_map_world = slam.trajectory().front().T_world_laser *
                                (mapping.truth[mapping.scan_samples.front()].T_world_body * lidar.T_body_laser()).inverse();
  result.map_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The second run: the lap from the same start, picked up at pick_up_s (20-56 s: on the bottom
  // corridor, in bottom room 1 or on the east corridor), put down facing a random way.
  result.pick_up_s = 20.0 + 4.0 * static_cast<double>((seed * 7) % 10);
  const std::vector<sim::TrajectorySample> before = sim::generate_trajectory(office.route, one_lap, office.closed_route);
  const Vector2 pick_up =
      before[static_cast<std::size_t>(std::llround(result.pick_up_s / one_lap.sample_period_s))].T_world_body.translation();
  sim::Random random(sim::Random::derive_seed(seed, 99));
  const double drop_heading_rad = random.uniform(-std::numbers::pi, std::numbers::pi);
  std::vector<Vector2> route;
  if (drop == Drop::kRoom) {
    const std::vector<std::string> places = {"top-room-0",    "bottom-room-3", "middle-room",   "top-room-3",
                                             "bottom-room-0", "top-room-1",    "bottom-room-2", "top-room-2",
                                             "bottom-room-1", "top-room-0"};
    result.drop_place = places[(seed - 1) % places.size()];
    route = sim::route_after_drop(floor, result.drop_place);
  } else {
    // A point on a centre line of the ring, at least 8 m from the pick-up and 1.5 m from the
    // corners; then the ring, counter-clockwise for odd seeds.
    const double x0 = floor.x_west() + 1.5, x1 = floor.x_east() - 1.5, y0 = floor.y_bottom() + 1.5, y1 = floor.y_top() - 1.5;
    const double legs[4] = {x1 - x0, y1 - y0, x1 - x0, y1 - y0};
    Vector2 at = Vector2::Zero();
    do {
      double u = random.uniform(0.0, legs[0] + legs[1] + legs[2] + legs[3]);
      int leg = 0;
      while (leg < 3 && u > legs[leg]) u -= legs[leg++];
      at = leg == 0 ? Vector2(x0 + u, floor.y_bottom())
           : leg == 1 ? Vector2(floor.x_east(), y0 + u)
           : leg == 2 ? Vector2(x1 - u, floor.y_top())
                      : Vector2(floor.x_west(), y1 - u);
    } while ((at - pick_up).norm() < 8.0);
    char name[64];
    std::snprintf(name, sizeof name, "ring (%.1f, %.1f)", at.x(), at.y());
    result.drop_place = name;
    const std::vector<Vector2> ring = floor.ring_from(at, seed % 2 == 1);
    route.reserve(ring.size() + 1);
    route.push_back(at);
    route.insert(route.end(), ring.begin(), ring.end());
  }
  std::vector<sim::TrajectorySample> after = sim::generate_trajectory(route, one_lap, false, drop_heading_rad);
  after.resize(std::min(after.size(), static_cast<std::size_t>(kAfterJumpS / one_lap.sample_period_s)));
  std::size_t first_after = 0;
  std::vector<sim::TrajectorySample> truth = sim::splice_kidnap(before, after, result.pick_up_s, &first_after);
  result.jump_m = (truth[first_after].T_world_body.translation() - truth[first_after - 1].T_world_body.translation()).norm();
  const SimulatedLog run = simulate_log(office.world, std::move(truth), {first_after}, seed + 1000, dir);
  EXPECT_TRUE(run.first_scan_after_jump.has_value());
  const std::size_t jump = *run.first_scan_after_jump;

  const auto localise_start = std::chrono::steady_clock::now();
  const MapPoints map_points(map);
  Localizer2d localizer(map);
  for (std::size_t k = 0; k < run.log.scans.size(); ++k) {
    const io::LaserScan& scan = run.log.scans[k];
    const LocalizationResult r = localizer.add_scan(scan);
    const core::SE2 T_map_laser_true = T_map_world * run.truth[run.scan_samples[k]].T_world_body * lidar.T_body_laser();
    ++result.scans;
    if (r.relocalised && k < jump && !result.start_fix) result.start_fix = k;
    if (k >= jump) {
      if (r.health != Health::kOk && !result.noticed_after) result.noticed_after = k - jump;
      if (r.health == Health::kLost && !result.lost_after) result.lost_after = k - jump;
      if (r.relocalised && !result.relocalised_after) result.relocalised_after = k - jump;
      if (!result.mapped_view_after &&
          map_points.explained_fraction(scan, T_map_laser_true, map.filter.min_range_m, map.filter.max_range_m,
                                        Localizer2dOptions{}.matching.icp.inlier_distance_m) >= kMappedView)
        result.mapped_view_after = k - jump;
    }
    if (r.relocalised && wrong(r.T_map_laser, T_map_laser_true)) ++result.wrong_relocalisations;
    if (r.localised && r.health == Health::kOk) {
      ++result.ok_scans;
      if (wrong(r.T_map_laser, T_map_laser_true)) ++result.wrong_ok;
      result.max_ok_error_m = std::max(result.max_ok_error_m, (T_map_laser_true.inverse() * r.T_map_laser).translation().norm());
    }
  }
  result.partly_mapped_look_alikes = localizer.summary().partly_mapped_look_alikes;
  result.refused_empty_space_elsewhere = localizer.summary().refused_empty_space_elsewhere;
  const auto end = std::chrono::steady_clock::now();
  result.localise_s = std::chrono::duration<double>(end - localise_start).count();
  result.total_s = std::chrono::duration<double>(end - start).count();
  return result;
}

std::string text(const std::optional<std::size_t>& scans) { return scans ? std::to_string(*scans) : std::string("never"); }

void print(const SeedResult& r) {
  std::printf("seed %2llu: pick-up %.0f s, put down in %-18s (%.1f m away): localised at scan %s; after the jump not ok %s, "
              "lost %s, mapped view %s, relocalised %s scans; %zu ok of %zu scans, max ok error %.3f m, wrong: %zu "
              "relocalisations %zu ok; refused: %zu partly mapped look-alike, %zu empty space elsewhere; map %.1f s, "
              "localisation %.1f s\n",
              static_cast<unsigned long long>(r.seed), r.pick_up_s, r.drop_place.c_str(), r.jump_m, text(r.start_fix).c_str(),
              text(r.noticed_after).c_str(), text(r.lost_after).c_str(), text(r.mapped_view_after).c_str(),
              text(r.relocalised_after).c_str(), r.ok_scans, r.scans, r.max_ok_error_m, r.wrong_relocalisations, r.wrong_ok,
              r.partly_mapped_look_alikes, r.refused_empty_space_elsewhere, r.map_s, r.localise_s);
}

// Ten seeds, ten kidnappings onto the ring corridor. Every seed: localised before the
// kidnapping, no `ok` pose from the scan after the jump on (noticed at once), `lost` declared,
// relocalised at most 20 scans after the later of being lost and seeing mapped structure, and
// never a wrong relocalisation or a wrong ok pose. How soon `lost` follows the jump is printed,
// not asserted per seed: where the scans still fit the old pose at 70-79 % (the half-turn image
// of the corridor, a corner turned by 90 degrees) the pose stays `degraded` until the match
// fails 5 times (25 and 53 scans on seeds 7 and 5; docs/slam2d.md; the other 8 seeds: 4 scans).
void expect_relocalised_after_kidnappings_onto_the_ring(const std::vector<std::uint64_t>& seeds) {
  const fs::path dir = temp_dir("kidnapping");
  std::size_t wrong_relocalisations = 0, wrong_ok = 0, lost_within_6 = 0;
  double total_s = 0.0;
  for (const std::uint64_t seed : seeds) {
    const SeedResult r = run_seed(seed, Drop::kRing, dir);
    total_s += r.total_s;
    print(r);
    wrong_relocalisations += r.wrong_relocalisations;
    wrong_ok += r.wrong_ok;
    EXPECT_EQ(r.wrong_relocalisations, 0u) << "seed " << seed;
    EXPECT_EQ(r.wrong_ok, 0u) << "seed " << seed;
    EXPECT_TRUE(r.start_fix.has_value()) << "seed " << seed << ": not localised before the kidnapping";
    ASSERT_TRUE(r.noticed_after.has_value()) << "seed " << seed;
    EXPECT_EQ(*r.noticed_after, 0u) << "seed " << seed << ": ok after the jump";
    EXPECT_TRUE(r.lost_after.has_value()) << "seed " << seed << ": never lost after the kidnapping";
    if (r.lost_after && *r.lost_after <= 6) ++lost_within_6;
    EXPECT_TRUE(r.mapped_view_after.has_value()) << "seed " << seed << ": never saw mapped structure";
    EXPECT_TRUE(r.relocalised_after.has_value()) << "seed " << seed << ": not relocalised";
    if (r.relocalised_after && r.mapped_view_after && r.lost_after) {
      EXPECT_LE(*r.relocalised_after, std::max(*r.lost_after, *r.mapped_view_after) + 20) << "seed " << seed;
    }
  }
  std::printf("%zu seeds: %zu wrong relocalisations, %zu wrong ok poses, %zu lost within 6 scans of the jump; %.1f s\n",
              seeds.size(), wrong_relocalisations, wrong_ok, lost_within_6, total_s);
  fs::remove_all(dir);
}

// Three seeds in `make test` (about 25 s): seed 1, noticed within 4 scans, and seeds 5 and 7, whose
// scans still fit the old pose for a while; all ten (about 80 s) on demand:
//   build/tests/slam2d/test_slam2d_localization_sim --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_KidnappedRobot*'
TEST(LocalizationSimulation, KidnappedRobotThreeSeeds) { expect_relocalised_after_kidnappings_onto_the_ring({1, 5, 7}); }
TEST(LocalizationSimulation, DISABLED_KidnappedRobotTenSeeds) {
  expect_relocalised_after_kidnappings_onto_the_ring({1, 2, 3, 4, 5, 6, 7, 8, 9, 10});
}

// Ten seeds, ten kidnappings into the middle of a room (seven of them into rooms the map run saw
// only through their doors). There the robot sees what it would see in a twin room the
// map holds whole while the furniture that tells the rooms apart is out of view; only the map's
// partial view of the true room fits as well (Localizer2dOptions::look_alike_places). Every
// seed: no wrong relocalisation, no wrong ok pose, lost after the jump, and relocalised before
// the end of the run (out of the room and along the ring: how soon is printed, not asserted;
// where a partly mapped twin fits, not before the robot has left the room). Before the
// partly-mapped look-alike test (2026-11-28) 6 of the 10 seeds relocalised in a room 7-21 m away.
void expect_relocalised_after_kidnappings_into_rooms(std::uint64_t first, std::uint64_t last) {
  const fs::path dir = temp_dir("kidnapping-rooms");
  std::size_t wrong_relocalisations = 0, wrong_ok = 0, refusals = 0;
  double total_s = 0.0;
  for (std::uint64_t seed = first; seed <= last; ++seed) {
    const SeedResult r = run_seed(seed, Drop::kRoom, dir);
    total_s += r.total_s;
    print(r);
    wrong_relocalisations += r.wrong_relocalisations;
    wrong_ok += r.wrong_ok;
    refusals += r.partly_mapped_look_alikes + r.refused_empty_space_elsewhere;
    EXPECT_EQ(r.wrong_relocalisations, 0u) << "seed " << seed;
    EXPECT_EQ(r.wrong_ok, 0u) << "seed " << seed;
    EXPECT_TRUE(r.start_fix.has_value()) << "seed " << seed << ": not localised before the kidnapping";
    EXPECT_TRUE(r.lost_after.has_value()) << "seed " << seed << ": never lost after the kidnapping";
    EXPECT_TRUE(r.relocalised_after.has_value()) << "seed " << seed << ": not relocalised";
  }
  std::printf("seeds %d-%d: %zu wrong relocalisations, %zu wrong ok poses, %zu acceptances refused; %.1f s\n",
              static_cast<int>(first), static_cast<int>(last), wrong_relocalisations, wrong_ok, refusals, total_s);
  fs::remove_all(dir);
}

// Four seeds in `make test` (about 35 s; drops into rooms the map saw only through their doors, seeds
// 1, 2 and 4, and one it drove through, seed 3); all ten (about 90 s) on demand:
//   build/tests/slam2d/test_slam2d_localization_sim --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_KidnappedIntoRooms*'
TEST(LocalizationSimulation, KidnappedIntoRoomsFourSeeds) { expect_relocalised_after_kidnappings_into_rooms(1, 4); }
TEST(LocalizationSimulation, DISABLED_KidnappedIntoRoomsTenSeeds) { expect_relocalised_after_kidnappings_into_rooms(1, 10); }

}  // namespace
}  // namespace cairn::slam2d
