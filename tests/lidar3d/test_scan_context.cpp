// Scan Context place recognition (lidar3d/scan_context.hpp): the descriptor's bins, the yaw it
// recovers and its sign, the two-phase database search against brute force, and the distances
// between real KITTI 00 scans of places that are not revisits.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>
#include <set>
#include <sstream>

#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/scan_context.hpp"
#include "cairn/sim/lidar_3d.hpp"
#include "cairn/sim/street_world.hpp"
#include "kitti_key_frames.hpp"
#include "test_data.hpp"

namespace cairn::lidar3d {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

Eigen::Matrix3d rot_z(double yaw) { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

std::vector<Eigen::Vector3d> transformed(const Eigen::Matrix3d& R, const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(R * p);
  return out;
}

double angle_difference(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

// A town seen from a sensor 1.7 m above flat ground: a ground grid, and `boxes` buildings of
// random footprint and height whose walls and roofs are sampled densely. Points in the sensor
// frame (the world frame here).
std::vector<Eigen::Vector3d> synthetic_scene(unsigned seed, int boxes = 40) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  const double ground_z = -1.7;
  // The ground as a spinning sensor sees it: circles of returns, denser near the sensor.
  for (double r = 2.5; r < 78.0; r += 0.5) {
    for (double azimuth = 0.1; azimuth < 360.0; azimuth += 1.0) {
      points.emplace_back(r * std::cos(azimuth * kDeg), r * std::sin(azimuth * kDeg), ground_z);
    }
  }
  for (int b = 0; b < boxes; ++b) {
    const double range = 8.0 + 62.0 * uniform(rng);
    const double bearing = 2.0 * kPi * uniform(rng);
    const double cx = range * std::cos(bearing), cy = range * std::sin(bearing);
    const double hx = 1.0 + 5.0 * uniform(rng), hy = 1.0 + 5.0 * uniform(rng);
    const double height = 2.0 + 18.0 * uniform(rng);
    for (double u = -hx; u <= hx; u += 0.25) {
      for (double v = -hy; v <= hy; v += 0.25) points.emplace_back(cx + u, cy + v, ground_z + height);
    }
  }
  return points;
}

// ---------------------------------------------------------------------------------------------

TEST(ScanContext, PointsLandInTheirRingAndSector) {
  ScanContextOptions options;  // 20 rings of 4 m, 60 sectors of 6 deg, h = 2 m
  const std::vector<Eigen::Vector3d> points = {
      {10.0, 0.1, 1.0},                           // r 10 -> ring 2, theta ~0.6 deg -> sector 0
      {10.0, 0.1, 0.5},                           // same bin, lower: the maximum stays
      {-5.0, -5.0, 0.5},                          // r 7.07 -> ring 1, theta 225 deg -> sector 37
      {0.0, 85.0, 3.0},                           // beyond 80 m: ignored
      {std::nan(""), 1.0, 1.0},                   // not finite: ignored
      {30.0 * std::cos(100.0 * kDeg), 30.0 * std::sin(100.0 * kDeg), -3.0},  // ring 7, sector 16, z + h < 0
  };
  const ScanContext context = make_scan_context(points, options);
  ASSERT_EQ(context.descriptor.rows(), 20);
  ASSERT_EQ(context.descriptor.cols(), 60);
  EXPECT_FLOAT_EQ(context.descriptor(2, 0), 3.0f);
  EXPECT_FLOAT_EQ(context.descriptor(1, 37), 2.5f);
  EXPECT_FLOAT_EQ(context.descriptor(7, 16), 0.0f);  // clamped like an empty bin
  EXPECT_EQ((context.descriptor.array() != 0.0f).count(), 2);
  EXPECT_FLOAT_EQ(context.ring_key(2), 3.0f / 60.0f);
  EXPECT_FLOAT_EQ(context.sector_key(37), 2.5f / 20.0f);
  EXPECT_FLOAT_EQ(context.ring_key(0), 0.0f);

  // Left of the sensor is +y, counter-clockwise from forward: just past 90 deg -> sector 15.
  const ScanContext left = make_scan_context({{-0.1, 20.0, 0.0}}, options);
  EXPECT_FLOAT_EQ(left.descriptor(5, 15), 2.0f);
  // Exactly at max_radius_m joins the last ring.
  const ScanContext edge = make_scan_context({{80.0, 0.0, 0.0}}, options);
  EXPECT_FLOAT_EQ(edge.descriptor(19, 0), 2.0f);
}

TEST(ScanContext, OptionsAreValidatedAllAtOnce) {
  ScanContextOptions options;
  std::string error;
  EXPECT_TRUE(options.is_valid(&error));
  options.rings = 0;
  options.search_ratio = 1.5;
  options.max_distance = -0.1;
  EXPECT_FALSE(options.is_valid(&error));
  EXPECT_NE(error.find("rings"), std::string::npos);
  EXPECT_NE(error.find("search_ratio"), std::string::npos);
  EXPECT_NE(error.find("max_distance"), std::string::npos);
  EXPECT_THROW(ScanContextDatabase database(options), std::invalid_argument);
}

TEST(ScanContext, EmptyScansAreAsFarAsPossible) {
  ScanContextOptions options;
  const ScanContext empty = make_scan_context({}, options);
  const ScanContext scene = make_scan_context(synthetic_scene(1), options);
  EXPECT_DOUBLE_EQ(compare(empty, scene, options).distance, 1.0);
  EXPECT_DOUBLE_EQ(compare(empty, empty, options).distance, 1.0);
}

// The query sensor stands where the candidate's stood, turned by `yaw` (R_candidate_query =
// Rz(yaw)): it sees the candidate's points p_c at p_q = Rz(yaw)^T p_c.
TEST(ScanContext, RecoversTheYawAndItsSign) {
  const std::vector<Eigen::Vector3d> candidate_points = synthetic_scene(7);
  for (const double search_ratio : {0.1, 0.0}) {
    ScanContextOptions options;
    options.search_ratio = search_ratio;
    const ScanContext candidate = make_scan_context(candidate_points, options);
    for (const double yaw_deg : {0.0, 6.0, 17.0, 45.0, 90.0, -45.0, -93.0, 137.0, 180.0, -150.0, 179.0}) {
      SCOPED_TRACE("yaw " + std::to_string(yaw_deg) + " deg, search_ratio " + std::to_string(search_ratio));
      const double yaw = yaw_deg * kDeg;
      const std::vector<Eigen::Vector3d> query_points = transformed(rot_z(yaw).transpose(), candidate_points);
      const ScanContext query = make_scan_context(query_points, options);
      const ScanContextMatch match = compare(query, candidate, options);
      // A multiple of the sector moves whole columns; another yaw re-bins the points, worst at
      // half a sector (45, -45, -93 deg: 0.13 here, the box tops straddle sector borders).
      EXPECT_LT(match.distance, std::fmod(std::abs(yaw_deg), 6.0) == 0.0 ? 0.01 : 0.15);
      EXPECT_LE(std::abs(angle_difference(match.yaw_rad, yaw)), 6.0 * kDeg);
      EXPECT_GT(match.yaw_rad, -kPi);
      EXPECT_LE(match.yaw_rad, kPi);
      EXPECT_NEAR(match.yaw_rad, std::remainder(match.shift_sectors * 6.0 * kDeg, 2.0 * kPi), 1e-12);
      // The sign as a verifier uses it: T_candidate_query = Rz(yaw_rad) takes the query's points
      // back onto the candidate's, whose descriptor then matches without a shift.
      const ScanContext undone = make_scan_context(transformed(rot_z(match.yaw_rad), query_points), options);
      ScanContextOptions no_shift = options;
      no_shift.search_ratio = 0.0;
      const ScanContextMatch check = compare(undone, candidate, no_shift);
      EXPECT_EQ(check.shift_sectors, 0);
    }
  }
}

// The query sensor stands 4 m to the candidate's +x, turned by 90 deg: the candidate sits 4 m to
// the query's left, where its +4 m lateral view looks from.
TEST(ScanContext, ALateralViewGivesTheTranslation) {
  ScanContextOptions options;
  options.lateral_offsets_m = {-4.0, 4.0};
  const std::vector<Eigen::Vector3d> candidate_points = synthetic_scene(7);
  const Eigen::Matrix3d R_candidate_query = rot_z(90.0 * kDeg);
  const Eigen::Vector3d t_candidate_query(4.0, 0.0, 0.0);
  std::vector<Eigen::Vector3d> query_points;
  for (const auto& p : candidate_points) query_points.push_back(R_candidate_query.transpose() * (p - t_candidate_query));
  const ScanContext query = make_scan_context(query_points, options);
  ASSERT_EQ(query.lateral_views.size(), 2u);
  EXPECT_EQ(query.lateral_views[1].lateral_offset_m, 4.0);
  const ScanContext candidate = make_scan_context(candidate_points, ScanContextOptions{});
  const ScanContextMatch match = compare(query, candidate, options);
  EXPECT_LT(match.distance, 0.01);
  EXPECT_EQ(match.lateral_offset_m, 4.0);
  EXPECT_NEAR(match.yaw_rad, 90.0 * kDeg, 1e-9);
  EXPECT_LT((match.t_candidate_query - t_candidate_query).norm(), 1e-9);
  // From its own viewpoint the query is far from the candidate.
  ScanContextOptions plain = options;
  plain.lateral_offsets_m.clear();
  EXPECT_GT(compare(make_scan_context(query_points, plain), candidate, plain).distance, 0.2);
}

TEST(ScanContext, DifferentScenesAreFarApart) {
  ScanContextOptions options;
  const ScanContext a = make_scan_context(synthetic_scene(1), options);
  const ScanContext b = make_scan_context(synthetic_scene(2), options);
  EXPECT_GT(compare(a, b, options).distance, 0.2);
}

// ---------------------------------------------------------------------------------------------
// Database

ScanContext random_context(std::mt19937& rng, const ScanContextOptions& options) {
  std::uniform_real_distribution<float> uniform(0.0f, 10.0f);
  ScanContext context;
  context.descriptor = Eigen::MatrixXf::NullaryExpr(options.rings, options.sectors, [&] { return uniform(rng); });
  context.ring_key = context.descriptor.rowwise().mean();
  context.sector_key = context.descriptor.colwise().mean().transpose();
  return context;
}

// Phase 1 must return exactly the eligible entries nearest by ring key, whether they sit in the
// tree or among the entries added since it was built.
TEST(ScanContextDatabase, RingKeySearchMatchesBruteForce) {
  std::mt19937 rng(3);
  for (const int period : {1, 7, 50, 1000}) {
    SCOPED_TRACE("tree_rebuild_period " + std::to_string(period));
    ScanContextOptions options;
    options.tree_rebuild_period = period;
    options.exclude_recent = 20;
    options.candidates = 10;
    ScanContextDatabase database(options);
    std::vector<ScanContext> stored;
    for (int id = 0; id < 300; ++id) {
      stored.push_back(random_context(rng, options));
      database.add(id, stored.back());
      if (id % 37 != 0) continue;
      const ScanContext query = random_context(rng, options);
      const int query_id = id + 1;
      const auto candidates = database.query(query, query_id);
      std::vector<std::pair<float, int>> brute;
      for (int i = 0; i <= id; ++i) {
        if (std::abs(i - query_id) < options.exclude_recent) continue;
        brute.emplace_back((stored[static_cast<std::size_t>(i)].ring_key - query.ring_key).squaredNorm(), i);
      }
      std::sort(brute.begin(), brute.end());
      brute.resize(std::min<std::size_t>(brute.size(), 10));
      std::set<int> expected, got;
      for (const auto& [d, i] : brute) expected.insert(i);
      for (const auto& c : candidates) got.insert(c.id);
      EXPECT_EQ(got, expected) << "after " << id + 1 << " entries";
      for (std::size_t i = 1; i < candidates.size(); ++i) {
        EXPECT_LE(candidates[i - 1].match.distance, candidates[i].match.distance);
      }
    }
  }
}

TEST(ScanContextDatabase, FindsTheRotatedSceneAndExcludesRecentIds) {
  ScanContextOptions options;
  options.exclude_recent = 3;
  ScanContextDatabase database(options);
  for (int id = 0; id < 12; ++id) database.add(id, make_scan_context(synthetic_scene(100 + id), options));
  EXPECT_EQ(database.size(), 12u);
  ASSERT_NE(database.find(4), nullptr);
  EXPECT_EQ(database.find(99), nullptr);

  const ScanContext query = make_scan_context(transformed(rot_z(-120.0 * kDeg).transpose(), synthetic_scene(104)), options);
  const auto candidates = database.query(query, 40);
  ASSERT_EQ(candidates.size(), 10u);
  EXPECT_EQ(candidates[0].id, 4);
  EXPECT_TRUE(candidates[0].below_threshold);
  EXPECT_LT(candidates[0].match.distance, 0.1);
  EXPECT_NEAR(angle_difference(candidates[0].match.yaw_rad, -120.0 * kDeg), 0.0, 6.0 * kDeg);
  // The second best is another place: far, so a uniqueness test passes.
  EXPECT_FALSE(candidates[1].below_threshold);
  EXPECT_GT(candidates[1].match.distance, 2.0 * candidates[0].match.distance);

  // As scan 6 (ids 4..8 are within 3): scan 4 is not offered.
  for (const auto& c : database.query(query, 6)) EXPECT_GE(std::abs(c.id - 6), 3);
  // Nothing eligible.
  ScanContextDatabase empty(options);
  EXPECT_TRUE(empty.query(query, 0).empty());
}

// ---------------------------------------------------------------------------------------------
// Real KITTI 00 key frames: no revisit in this stretch (SOURCE.txt), so every pair far apart in
// time is a non-revisit.

struct KittiScans {
  std::vector<std::vector<Eigen::Vector3d>> points;
  std::vector<Eigen::Vector3d> positions;  // ENU, from poses_keyframes.txt
};

const KittiScans& kitti_scans() {
  static const KittiScans scans = [] {
    KittiScans k;
    const test::KittiKeyFrames key_frames = test::read_kitti_key_frames();
    for (std::size_t i = 0; i < key_frames.files.size(); ++i) {
      const io::PointCloud cloud = io::read_point_cloud(key_frames.files[i]);
      std::vector<Eigen::Vector3d> points;
      points.reserve(cloud.points.size());
      for (const auto& p : cloud.points) points.push_back(p.cast<double>());
      k.points.push_back(std::move(points));
      k.positions.push_back(key_frames.T_enu_velo[i].translation());
    }
    return k;
  }();
  return scans;
}

ScanContextOptions with_lateral_views() {
  ScanContextOptions options;
  options.lateral_offsets_m = {-4.0, -2.0, 2.0, 4.0};
  return options;
}

// Prints the distances between the KITTI scans and returns the smallest over pairs more than 50
// frames apart (the later scan as the query, with its lateral views if `options` has any).
double kitti_distances(const KittiScans& k, const std::vector<ScanContext>& contexts, const ScanContextOptions& options,
                       const char* name) {
  const auto distance = [&](int query, int candidate) {
    return compare(contexts[static_cast<std::size_t>(query)], contexts[static_cast<std::size_t>(candidate)], options).distance;
  };
  const int n = static_cast<int>(contexts.size());
  std::vector<double> far;
  double closest_far_m = 1e9;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 51; j < n; ++j) {
      far.push_back(distance(j, i));
      closest_far_m = std::min(closest_far_m, (k.positions[static_cast<std::size_t>(j)] - k.positions[static_cast<std::size_t>(i)]).norm());
    }
  }
  std::sort(far.begin(), far.end());
  const auto quantile = [&](double q) { return far[static_cast<std::size_t>(q * static_cast<double>(far.size() - 1))]; };
  std::printf("KITTI 00, %s: %zu pairs > 50 frames apart (>= %.1f m): distance min %.3f, 1%% %.3f, 5%% %.3f, median %.3f\n",
              name, far.size(), closest_far_m, far.front(), quantile(0.01), quantile(0.05), quantile(0.5));
  // Near neighbours are the same place seen from a little farther on: what a same-direction
  // revisit at that offset would score.
  for (int gap = 1; gap <= 5; ++gap) {
    std::vector<double> d;
    double metres = 0.0;
    for (int i = 0; i + gap < n; ++i) {
      d.push_back(distance(i + gap, i));
      metres += (k.positions[static_cast<std::size_t>(i + gap)] - k.positions[static_cast<std::size_t>(i)]).norm();
    }
    std::sort(d.begin(), d.end());
    std::printf("  gap %d frames (%.1f m on average): distance min %.3f median %.3f max %.3f, %.0f%% <= %.2f\n", gap,
                metres / static_cast<double>(d.size()), d.front(), d[d.size() / 2], d.back(),
                100.0 * static_cast<double>(std::upper_bound(d.begin(), d.end(), options.max_distance) - d.begin()) /
                    static_cast<double>(d.size()),
                options.max_distance);
  }
  // Through the database, as SLAM uses it: no candidate below the threshold, ever.
  ScanContextDatabase database(options);
  int below = 0;
  for (int i = 0; i < n; ++i) {
    for (const auto& c : database.query(contexts[static_cast<std::size_t>(i)], i)) below += c.below_threshold ? 1 : 0;
    database.add(i, contexts[static_cast<std::size_t>(i)]);
  }
  EXPECT_EQ(below, 0) << name;
  return far.front();
}

TEST(ScanContextKitti, NoFalseMatchBetweenDistantRealScans) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const KittiScans& k = kitti_scans();
  ASSERT_EQ(k.points.size(), 110u);
  // One pass makes both: a context with lateral views holds the plain one too.
  const ScanContextOptions lateral = with_lateral_views();
  std::vector<ScanContext> with_views, plain;
  for (const auto& points : k.points) {
    with_views.push_back(make_scan_context(points, lateral));
    plain.push_back(with_views.back());
    plain.back().lateral_views.clear();
  }
  // Measured: 0.300 either way (and with every shift tried, search_ratio 0); neighbours 1 frame
  // (1.8 m) apart score 0.108-0.284, median 0.173, 2 frames (3.5 m) median 0.250, either way.
  EXPECT_GT(kitti_distances(k, plain, ScanContextOptions{}, "reference settings"), 0.25);
  EXPECT_GT(kitti_distances(k, with_views, lateral, "lateral views -4 -2 2 4 m"), 0.25);
}

TEST(ScanContextKitti, ARealScanMatchesItselfTurned) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/keyframes.txt");
  const KittiScans& k = kitti_scans();
  const ScanContextOptions options;
  for (const std::size_t index : {std::size_t{0}, std::size_t{40}, std::size_t{90}}) {
    const ScanContext candidate = make_scan_context(k.points[index], options);
    for (const double yaw_deg : {23.0, -71.0, 21.0, 93.0, 180.0}) {
      SCOPED_TRACE("scan " + std::to_string(index) + ", yaw " + std::to_string(yaw_deg) + " deg");
      const double yaw = yaw_deg * kDeg;
      const ScanContext query = make_scan_context(transformed(rot_z(yaw).transpose(), k.points[index]), options);
      const ScanContextMatch match = compare(query, candidate, options);
      std::printf("scan %zu turned %.0f deg: distance %.3f, yaw %.1f deg\n", index, yaw_deg, match.distance,
                  match.yaw_rad / kDeg);
      // 21 and 93 deg are half a sector off the grid, the worst case of the binning (0.11-0.14
      // measured); 23 and -71 deg 0.04-0.06; 180 deg moves whole columns (0).
      const bool half_sector = yaw_deg == 21.0 || yaw_deg == 93.0;
      EXPECT_LT(match.distance, half_sector ? 0.16 : 0.08);
      EXPECT_LE(std::abs(angle_difference(match.yaw_rad, yaw)), 6.0 * kDeg);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Revisits in the simulated street (sim/street_world.hpp): a straight 60 m street between
// facades, trees, poles and parked cars, seen by a simulated 64-ring LiDAR (HDL-64E-like
// elevations) standing still.

struct StreetPose {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

class SimulatedStreet {
 public:
  SimulatedStreet() : world_(sim::street_world()) {
    lidar_.rings = 64;
    lidar_.elevation_min_rad = -24.9 * kDeg;
    lidar_.elevation_max_rad = 2.0 * kDeg;
    lidar_.columns = 1024;
    lidar_.max_range_m = 80.0;
  }
  std::vector<Eigen::Vector3d> scan(const StreetPose& pose) {
    const core::SE3 T_world_lidar(core::SO3::exp(Eigen::Vector3d(0.0, 0.0, pose.yaw)),
                                  Eigen::Vector3d(pose.x, pose.y, lidar_.mount_height_m));
    std::vector<Eigen::Vector3d> points;
    for (const auto& p : sim::spin_scan(world_.world, 0.0, [&](double) { return T_world_lidar; }, lidar_, random_)) {
      points.push_back(p.position);
    }
    return points;
  }

 private:
  sim::StreetWorld world_;
  sim::Lidar3DOptions lidar_;
  sim::Random random_{11};
};

TEST(ScanContextStreet, FindsSameDirectionAndReverseRevisits) {
  // The street from (0, 0) to (60, 0) is the first route leg; lanes at y = -1.75 (driving +x) and
  // +1.75 (driving -x). First pass: a key frame every 2 m in the right lane, ids 0..28 at x = 2..58.
  SimulatedStreet street;
  ScanContextOptions plain;
  plain.exclude_recent = 5;
  ScanContextOptions lateral = plain;
  lateral.lateral_offsets_m = {-4.0, -2.0, 2.0, 4.0};
  ScanContextDatabase plain_database(plain), lateral_database(lateral);
  std::vector<StreetPose> first_pass;
  for (int id = 0; id < 29; ++id) {
    first_pass.push_back({2.0 + 2.0 * id, -1.75, 0.0});
    const ScanContext context = make_scan_context(street.scan(first_pass.back()), plain);
    plain_database.add(id, context);
    lateral_database.add(id, context);
  }
  struct Revisit {
    const char* name;
    StreetPose pose;
    bool plain_finds_it;
  };
  const Revisit revisits[] = {
      {"same direction, 0.3 m left, 4 deg", {31.0, -1.45, 4.0 * kDeg}, true},
      {"reverse, same lane", {31.0, -1.75, 182.0 * kDeg}, true},
      {"reverse, opposite lane (3.5 m across)", {31.0, 1.75, 182.0 * kDeg}, false},
  };
  for (const Revisit& revisit : revisits) {
    SCOPED_TRACE(revisit.name);
    const std::vector<Eigen::Vector3d> points = street.scan(revisit.pose);
    for (const bool with_views : {false, true}) {
      const ScanContextOptions& options = with_views ? lateral : plain;
      const auto candidates = (with_views ? lateral_database : plain_database).query(make_scan_context(points, options), 1000);
      ASSERT_FALSE(candidates.empty());
      const LoopCandidate& best = candidates.front();
      const StreetPose& c = first_pass[static_cast<std::size_t>(best.id)];
      // The truth: T_candidate_query, both sensors level.
      const double true_yaw = revisit.pose.yaw - c.yaw;
      const Eigen::Vector3d true_t = rot_z(-c.yaw) * Eigen::Vector3d(revisit.pose.x - c.x, revisit.pose.y - c.y, 0.0);
      std::printf("%-40s %s: best id %d (x %.0f) distance %.3f yaw %.0f deg (true %.0f) t (%.1f, %.1f) (true %.1f, %.1f), "
                  "second %.3f\n",
                  revisit.name, with_views ? "lateral views" : "plain        ", best.id, c.x, best.match.distance,
                  best.match.yaw_rad / kDeg, true_yaw / kDeg, best.match.t_candidate_query.x(),
                  best.match.t_candidate_query.y(), true_t.x(), true_t.y(),
                  candidates.size() > 1 ? candidates[1].match.distance : 1.0);
      if (!with_views && !revisit.plain_finds_it) {
        // The documented weakness: the polar bins moved with the sensor, so the right alignment
        // scores far above the threshold. What comes out instead (0.162, second best 0.164) is
        // the street's own symmetry: the corridor seen from the other lane the other way looks
        // like the first pass at yaw 0, a wrong yaw that only geometric verification can reject.
        EXPECT_FALSE(best.below_threshold && std::abs(angle_difference(best.match.yaw_rad, true_yaw)) <= 6.0 * kDeg);
        continue;
      }
      EXPECT_TRUE(best.below_threshold);
      EXPECT_LE(std::abs(revisit.pose.x - c.x), 2.0) << "a key frame of the same place";
      EXPECT_LE(std::abs(angle_difference(best.match.yaw_rad, true_yaw)), 6.0 * kDeg);
      EXPECT_LT((best.match.t_candidate_query - true_t).norm(), 2.0);
    }
  }
  // A place of the first pass seen from 25 m farther down the street is not a match.
  const auto far = plain_database.query(make_scan_context(street.scan({54.0, -1.75, 0.0}), plain), 1000);
  ASSERT_FALSE(far.empty());
  for (const auto& c : far) {
    std::printf("from x 54: id %d (x %.0f) distance %.3f\n", c.id, first_pass[static_cast<std::size_t>(c.id)].x, c.match.distance);
    if (std::abs(first_pass[static_cast<std::size_t>(c.id)].x - 54.0) > 10.0) {
      EXPECT_FALSE(c.below_threshold) << c.id;
    }
  }
}

}  // namespace
}  // namespace cairn::lidar3d
