// Localisation in a saved 3D map (lidar3d/localization.hpp) in the simulator's 3D worlds, with
// exact ground truth: the map is built by LidarSlam from one simulated run (seed 1) and saved
// through the file format; another run of the same route (seed 2: other range noise) is
// localised in it, with a kidnapping: after some scans the sensor is carried elsewhere on the
// route (the scans jump; the localiser is not told). A localised pose is wrong when it is more
// than 1 m or 3 degrees from the reference: the map's pose of the nearest keyframe composed with
// the true motion between the two scans. Zero wrong relocalisations is the requirement; the
// garage of identical bays may stay lost, and there the first scans after the carry are tracked
// on at the old place (see the test).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numbers>

#include "cairn/lidar3d/localization.hpp"
#include "cairn/lidar3d/map_file.hpp"
#include "cairn/lidar3d/saved_map.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/sim/street_run.hpp"
#include "sim_clouds.hpp"

namespace cairn::lidar3d {
namespace {

struct SimScans {
  std::vector<io::PointCloud> clouds;
  std::vector<double> times_s;
  std::vector<core::SE3> T_world_stamp;   ///< truth at each scan's stamp (sweep start)
  std::vector<core::SE3> T_world_middle;  ///< truth at each sweep's middle
};

SimScans simulate_scans(const sim::Scenario& scenario, std::uint64_t seed) {
  const sim::SimulationResult s = sim::simulate(scenario, seed);
  SimScans out;
  const double sample_period = s.truth[1].stamp.seconds() - s.truth[0].stamp.seconds();
  const auto half = static_cast<std::size_t>(std::lround(0.5 * scenario.lidar3d.period_s / sample_period));
  for (std::size_t k = 0; k < s.clouds.size(); ++k) {
    out.clouds.push_back(test::to_point_cloud(s.clouds[k]));
    out.times_s.push_back(s.truth[s.scan_samples[k]].stamp.seconds());
    const std::size_t middle = std::min(s.scan_samples[k] + half, s.truth.size() - 1);
    out.T_world_stamp.push_back(sim::lidar_pose(s.truth[s.scan_samples[k]].T_world_body, scenario.lidar3d));
    out.T_world_middle.push_back(sim::lidar_pose(s.truth[middle].T_world_body, scenario.lidar3d));
  }
  return out;
}

SavedMap3D build_map(const SimScans& scans) {
  LidarSlam slam;
  SlamRun run(slam.options().odometry, 0.25);
  for (std::size_t k = 0; k < scans.clouds.size(); ++k) {
    run.add_scan(k, scans.clouds[k], slam.add_scan(scans.clouds[k], scans.times_s[k]), 0.0);
  }
  slam.finish();
  run.finish(slam);
  return decode_saved_map(encode_saved_map(make_saved_map(slam, run, "{}", "simulation")), "memory");
}

struct Outcome {
  std::size_t localised = 0, wrong = 0, relocalisations = 0, localised_after_kidnap = 0;
  std::size_t wrong_relocalisations = 0;
  std::size_t wrong_tracked = 0;  ///< wrong poses that were not relocalisations (tracked on)
  double worst_m = 0.0;
};

/// Localises `scans` [0, kidnap_at) then [resume_at, resume_end) (the end of the run when 0) of a
/// second run in `map`, whose keyframes were made from `mapped`'s scans.
Outcome localise_with_kidnap(const SavedMap3D& map, const SimScans& mapped, const SimScans& scans, std::size_t kidnap_at,
                             std::size_t resume_at, std::size_t resume_end = 0) {
  Localizer3d localizer(map);
  Outcome o;
  double time_s = 0.0;
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < kidnap_at; ++k) order.push_back(k);
  const std::size_t end = resume_end > 0 ? std::min(resume_end, scans.clouds.size()) : scans.clouds.size();
  for (std::size_t k = resume_at; k < end; ++k) order.push_back(k);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::size_t k = order[i];
    time_s += 0.1;  // the clock goes on across the carry
    const Localization3dResult r = localizer.add_scan(scans.clouds[k], time_s);
    if (!r.localised) continue;
    ++o.localised;
    if (i >= kidnap_at) ++o.localised_after_kidnap;
    // The nearest keyframe by true position, and the true motion from it.
    const SavedKeyframe3D* nearest = nullptr;
    double best = 1e300;
    for (const SavedKeyframe3D& kf : map.keyframes) {
      const double d = (mapped.T_world_middle[kf.scan].translation() - scans.T_world_stamp[k].translation()).norm();
      if (d < best) best = d, nearest = &kf;
    }
    const core::SE3 reference = nearest->T_world_sensor * mapped.T_world_middle[nearest->scan].inverse() * scans.T_world_stamp[k];
    const core::SE3 e = reference.inverse() * r.T_map_sensor;
    const double t = e.translation().norm(), a = e.so3().log().norm() * 180.0 / std::numbers::pi;
    o.worst_m = std::max(o.worst_m, t);
    if (t > 1.0 || a > 3.0) {
      ++o.wrong;
      (r.relocalised ? o.wrong_relocalisations : o.wrong_tracked)++;
      std::printf("scan %zu (input %zu) wrong by %.2f m %.2f deg (%s, fitness %.3f, inlier RMSE %.3f m): %s\n", k, i, t, a,
                  std::string(core::to_string(r.health)).c_str(), r.fitness, r.inlier_rmse_m, r.reason.c_str());
    }
  }
  o.relocalisations = localizer.summary().relocalisations.size();
  std::printf("%zu scans: %zu localised (%zu after the kidnapping), %zu relocalisations (%zu wrong), %zu ambiguous "
              "scans, %zu wrong poses, worst %.2f m\n",
              order.size(), o.localised, o.localised_after_kidnap, o.relocalisations, o.wrong_relocalisations,
              localizer.summary().scans_ambiguous, o.wrong, o.worst_m);
  return o;
}

TEST(Localization3dSimulation, KidnappedOnTheStreetItRelocalisesAndIsNeverWrong) {
  const sim::Scenario scenario = *sim::make_scenario("street-3d");
  const SimScans mapped = simulate_scans(scenario, 1);
  const SavedMap3D map = build_map(mapped);
  const SimScans run = simulate_scans(scenario, 2);
  const std::size_t n = run.clouds.size();
  const Outcome o = localise_with_kidnap(map, mapped, run, n / 4, n / 2);
  EXPECT_EQ(o.wrong, 0u);
  EXPECT_GE(o.relocalisations, 2u) << "at the start and after the kidnapping";
  EXPECT_GT(o.localised_after_kidnap, (n - n / 2) * 8 / 10);
}

TEST(Localization3dSimulation, KidnappedInTheGarageOfIdenticalBaysItIsNeverWrong) {
  const sim::Scenario scenario = *sim::make_scenario("garage-3d");
  const SimScans mapped = simulate_scans(scenario, 1);
  const SavedMap3D map = build_map(mapped);
  const SimScans run = simulate_scans(scenario, 2);
  const std::size_t n = run.clouds.size();
  // 120 scans after the carry (48 m): the localiser stays lost over the rest of the garage too
  // (measured over the whole run: 291 scans, none relocalised), at a global search per scan.
  const Outcome o = localise_with_kidnap(map, mapped, run, n / 4, n / 2, n / 2 + 120);
  EXPECT_EQ(o.wrong_relocalisations, 0u);
  // The scans just after the carry are tracked on at the old place: the garage repeats, the scan
  // fits there as well as where it is (fitness 0.96), and constant velocity (or the odometry)
  // follows it without a jump. Nothing in one scan tells them apart; tracking ends once the scans
  // stop fitting and the localiser then stays lost (every bay explains the scans). Bounded, not
  // zero. Measured: 1 scan with lean tracking (the default, since its sparse first iterations;
  // 6 before them), 4 with odometry_while_tracking before them. The bound is the largest seen.
  EXPECT_LE(o.wrong_tracked, 6u);
}

}  // namespace
}  // namespace cairn::lidar3d
