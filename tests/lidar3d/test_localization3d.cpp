// Localisation in a saved 3D map (lidar3d/localization.hpp) on the real KITTI 00 key frames, as
// issue 42 asks: the map holds the even key frames of a LidarSlam run over all of them (see
// even_odd), saved and read back (map_file.hpp), and the odd key frames (other scans, about
// 1.75 m from the nearest mapped one, whose points are not in the map) are localised in it. The reference for a localised scan is the map's pose of the nearest mapped
// scan composed with the GNSS/INS motion between the two scans (the GNSS/INS rotation is good to
// about 0.1 degree, so that is the floor of the rotation errors).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numbers>
#include <numeric>

#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/localization.hpp"
#include "cairn/lidar3d/localization_outputs.hpp"
#include "cairn/lidar3d/map_file.hpp"
#include "cairn/lidar3d/saved_map.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"
#include "kitti_key_frames.hpp"

namespace cairn::lidar3d {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

struct EvenOdd {
  test::KittiKeyFrames frames;
  std::vector<io::PointCloud> clouds;
  SavedMap3D map;
  std::vector<std::size_t> mapped;  ///< key frames in the map, in order
  std::vector<core::SE3> T_map_mapped;
};

/// SLAM over every key frame; the map holds the even ones only (their points, poses and
/// descriptors), through the file format. (SLAM over the even key frames alone, 3.5 m apart, loses
/// track in the turn near key frame 38 with the kitti preset: 3 lost scans, 4 map segments.)
const EvenOdd& even_odd() {
  static const EvenOdd data = [] {
    EvenOdd d;
    d.frames = test::read_kitti_key_frames();
    for (const std::string& file : d.frames.files) d.clouds.push_back(io::read_point_cloud(file));
    LidarSlamOptions options;
    options.odometry = preset_options("kitti");
    LidarSlam slam(options);
    SlamRun run(options.odometry, 0.25);
    for (std::size_t k = 0; k < d.clouds.size(); ++k) {
      run.add_scan(k, d.clouds[k], slam.add_scan(d.clouds[k], d.frames.times_s[k]), 0.0);
    }
    slam.finish();
    run.finish(slam);
    const std::vector<std::size_t> keyframe_scans = slam.keyframe_scans();
    const std::vector<core::SE3> keyframe_poses = slam.keyframe_poses();
    std::vector<bool> keep;
    for (std::size_t i = 0; i < keyframe_scans.size(); ++i) {
      keep.push_back(keyframe_scans[i] % 2 == 0);
      if (keep.back()) {
        d.mapped.push_back(keyframe_scans[i]);
        d.T_map_mapped.push_back(keyframe_poses[i]);
      }
    }
    d.map = decode_saved_map(encode_saved_map(make_saved_map(slam, run, "{}", "kitti even key frames", &keep)), "memory");
    return d;
  }();
  return data;
}

struct PoseError {
  double translation_m = 0.0;
  double rotation_deg = 0.0;
};

/// Key frame `k` localised at `T_map_sensor`, against the nearest mapped key frame's map pose and
/// the GNSS/INS motion between them.
PoseError error_of(const EvenOdd& d, std::size_t k, const core::SE3& T_map_sensor) {
  std::size_t best = 0;
  double best_distance = 1e300;
  for (std::size_t i = 0; i < d.mapped.size(); ++i) {
    const double distance = (d.frames.T_enu_velo[d.mapped[i]].translation() - d.frames.T_enu_velo[k].translation()).norm();
    if (distance < best_distance) best_distance = distance, best = i;
  }
  const core::SE3 reference = d.T_map_mapped[best] * d.frames.T_enu_velo[d.mapped[best]].inverse() * d.frames.T_enu_velo[k];
  const core::SE3 e = reference.inverse() * T_map_sensor;
  return {e.translation().norm(), e.so3().log().norm() * kDeg};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Tracking times over hand-made results: only scans localised and not relocalised count; the
// median of an even count is the mean of the middle two; the 90th percentile is the nearest rank.
TEST(Localization3dOutputs, TrackingTimesCountTrackedScansOnly) {
  std::vector<Localization3dResult> results;
  const auto add = [&](double ms, bool localised, bool relocalised) {
    Localization3dResult r;
    r.total_s = ms / 1e3;
    r.localised = localised;
    r.relocalised = relocalised;
    results.push_back(r);
  };
  EXPECT_EQ(tracking_times(results).scans, 0u);
  EXPECT_EQ(tracking_times(results).max_ms, 0.0);
  for (const double ms : {5.0, 1.0, 3.0, 2.0, 4.0}) add(ms, true, false);
  add(100.0, true, true);   // a relocalisation
  add(50.0, false, false);  // searching
  TrackingTimes t = tracking_times(results);
  EXPECT_EQ(t.scans, 5u);
  EXPECT_NEAR(t.median_ms, 3.0, 1e-12);
  EXPECT_NEAR(t.p90_ms, 5.0, 1e-12);  // rank ceil(0.9 * 5) = 5
  EXPECT_NEAR(t.max_ms, 5.0, 1e-12);
  for (const double ms : {6.0, 7.0, 8.0, 9.0, 10.0}) add(ms, true, false);
  t = tracking_times(results);
  EXPECT_EQ(t.scans, 10u);
  EXPECT_NEAR(t.median_ms, 5.5, 1e-12);
  EXPECT_NEAR(t.p90_ms, 9.0, 1e-12);  // rank 9 of 10
  EXPECT_NEAR(t.max_ms, 10.0, 1e-12);
  EXPECT_EQ(to_json(t)["tracked_scans"].get<std::size_t>(), 10u);
}

TEST(Localization3dKitti, TheOddKeyFramesAreLocalisedInTheMapOfTheEvenOnes) {
  const EvenOdd& d = even_odd();
  ASSERT_EQ(d.map.keyframes.size(), d.mapped.size());
  Localizer3d localizer(d.map);
  std::vector<double> translation, rotation;
  std::size_t localised = 0, wrong = 0;
  double max_tracking_s = 0.0, tracking_sum_s = 0.0, odometry_sum_s = 0.0;
  std::vector<double> scan_s;  // whole add_scan calls of tracked scans
  std::size_t tracked = 0;
  for (std::size_t k = 1; k < d.clouds.size(); k += 2) {
    const Localization3dResult r = localizer.add_scan(d.clouds[k], d.frames.times_s[k]);
    if (!r.localised) {
      std::printf("key frame %zu not localised (odometry %s): %s\n", k, std::string(core::to_string(r.odometry_health)).c_str(), r.reason.c_str());
      continue;
    }
    ++localised;
    const PoseError e = error_of(d, k, r.T_map_sensor);
    translation.push_back(e.translation_m);
    rotation.push_back(e.rotation_deg);
    if (e.translation_m > 1.0 || e.rotation_deg > 2.0) ++wrong;
    if (!r.relocalised) {
      ++tracked;
      tracking_sum_s += r.tracking_s;
      odometry_sum_s += r.odometry_s;
      scan_s.push_back(r.total_s);
      max_tracking_s = std::max(max_tracking_s, r.tracking_s);
    }
  }
  const Localizer3dSummary& s = localizer.summary();
  std::printf("odd key frames: %zu of %zu localised (first at %zu), median %.2f cm %.3f deg, max %.2f cm %.3f deg; "
              "tracking %.1f ms mean %.1f ms max, odometry %.1f ms mean; %zu relocalisations; slowest global search %.0f ms, "
              "map built in %.2f s; per tracked scan %.1f ms median, %.1f ms mean\n",
              localised, s.scans, s.first_localised_scan.value_or(999), 100.0 * median(translation), median(rotation),
              100.0 * *std::max_element(translation.begin(), translation.end()),
              *std::max_element(rotation.begin(), rotation.end()), 1e3 * tracking_sum_s / static_cast<double>(std::max<std::size_t>(tracked, 1)),
              1e3 * max_tracking_s, 1e3 * odometry_sum_s / static_cast<double>(std::max<std::size_t>(tracked, 1)), s.relocalisations.size(),
              1e3 * s.max_search_s, s.setup_s, 1e3 * median(scan_s),
              1e3 * std::accumulate(scan_s.begin(), scan_s.end(), 0.0) / static_cast<double>(std::max<std::size_t>(scan_s.size(), 1)));
  EXPECT_EQ(wrong, 0u);
  EXPECT_LE(s.first_localised_scan.value_or(999), 2u) << "relocalised within 3 scans";
  EXPECT_EQ(localised + s.first_localised_scan.value_or(999), s.scans) << "every scan after the first localisation";
  EXPECT_LE(median(translation), 0.05);
  EXPECT_LE(median(rotation), 0.2);
}

TEST(Localization3dKitti, StartedWithoutAPriorAtTenKeyFramesItRelocalisesWithinThreeScans) {
  const EvenOdd& d = even_odd();
  int relocalised = 0;
  for (std::size_t start = 5; start + 6 < d.clouds.size(); start += 10) {
    Localizer3d localizer(d.map);
    std::size_t scans = 0;
    for (std::size_t k = start; k < start + 6 && !localizer.summary().first_localised_scan; k += 2, ++scans) {
      const Localization3dResult r = localizer.add_scan(d.clouds[k], d.frames.times_s[k]);
      if (!r.localised) continue;
      const PoseError e = error_of(d, k, r.T_map_sensor);
      std::printf("start at key frame %zu: relocalised at its scan %zu, off by %.2f cm %.3f deg; %.0f ms searching\n", start,
                  scans, 100.0 * e.translation_m, e.rotation_deg, 1e3 * localizer.summary().total_s);
      EXPECT_LT(e.translation_m, 0.3) << "start " << start;
      EXPECT_LT(e.rotation_deg, 1.0) << "start " << start;
      ++relocalised;
    }
    EXPECT_TRUE(localizer.summary().first_localised_scan.has_value()) << "start " << start << " not relocalised in 3 scans";
  }
  EXPECT_EQ(relocalised, 10);
}

}  // namespace
}  // namespace cairn::lidar3d
