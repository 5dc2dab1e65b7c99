// Cost of the IMU in 3D LiDAR SLAM (issue 38's speed targets): per-scan time of LidarSlam alone and
// of LidarInertialSlam on the same simulated scans (KITTI-sized with lidar3d.model=hdl64), runs
// alternating, loop closure off so that only odometry and fusion are timed; and the cost of
// preintegrating the simulated 200 Hz IMU in 0.1 s pieces (as the fusion does) as a share of real
// time. Prints one JSON object. Results in docs/benchmarks.md.
//
//   bench_lidar_inertial [SCENARIO=street-3d] [--model hdl64|vlp16] [--runs 3] [--scans N] [--seed 1]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "cairn/core/timer.hpp"
#include "cairn/inertial/preintegration.hpp"
#include "cairn/lidar3d/lidar_inertial_slam.hpp"
#include "cairn/sim/manifest.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/sim/street_run.hpp"

namespace {

using namespace cairn;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct Timing {
  std::vector<double> per_scan_s;
  std::vector<double> fusion_s;
};

Timing run(const sim::Scenario& scenario, const sim::SimulationResult& s, const std::vector<io::PointCloud>& clouds,
           bool with_imu) {
  lidar3d::LidarSlamOptions options;
  options.loop_closure = false;
  if (with_imu) options.odometry.registration.remap_degenerate_directions = true;
  lidar3d::LidarSlam slam(options);
  lidar3d::InertialFusionOptions fusion_options;
  fusion_options.noise = scenario.imu.noise;
  fusion_options.T_imu_lidar = sim::lidar_pose(core::SE2(), scenario.lidar3d);
  lidar3d::LidarInertialSlam lio(slam, fusion_options);
  if (with_imu) {
    for (const auto& sample : s.imu.samples) lio.add_imu(sample);
  }
  Timing t;
  for (std::size_t k = 0; k < clouds.size(); ++k) {
    const double time_s = s.truth[s.scan_samples[k]].stamp.seconds();
    const auto start = core::Clock::now();
    if (with_imu) {
      const lidar3d::LidarInertialScan scan = lio.add_scan(clouds[k], time_s);
      if (scan.inertial) t.fusion_s.push_back(scan.inertial->solve_s);
    } else {
      slam.add_scan(clouds[k], time_s);
    }
    t.per_scan_s.push_back(core::seconds_since(start));
  }
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  std::string name = "street-3d", model = "hdl64";
  int runs = 3;
  long max_scans = 0;
  unsigned long seed = 1;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--model") == 0 && has_value) {
      model = argv[++i];
    } else if (std::strcmp(argv[i], "--runs") == 0 && has_value) {
      runs = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--scans") == 0 && has_value) {
      max_scans = std::atol(argv[++i]);
    } else if (std::strcmp(argv[i], "--seed") == 0 && has_value) {
      seed = std::strtoul(argv[++i], nullptr, 10);
    } else {
      name = argv[i];
    }
  }
  const auto made = sim::make_scenario(name);
  if (!made) {
    std::fprintf(stderr, "bench_lidar_inertial: unknown scenario %s\n", name.c_str());
    return 2;
  }
  sim::Scenario scenario = *made;
  for (const std::string& problem : sim::apply_assignments(scenario, {"lidar3d.model=" + model})) {
    std::fprintf(stderr, "bench_lidar_inertial: %s\n", problem.c_str());
    return 2;
  }
  const sim::SimulationResult s = sim::simulate(scenario, seed);
  std::vector<io::PointCloud> clouds;
  std::size_t points = 0;
  for (std::size_t k = 0; k < s.clouds.size() && (max_scans == 0 || static_cast<long>(k) < max_scans); ++k) {
    io::PointCloud cloud;
    for (const sim::LidarPoint& p : s.clouds[k]) {
      cloud.points.push_back(p.position.cast<float>());
      cloud.time_s.push_back(static_cast<float>(p.time_offset_s));
      cloud.ring.push_back(static_cast<std::uint16_t>(p.ring));
    }
    points += cloud.points.size();
    clouds.push_back(std::move(cloud));
  }
  std::vector<double> lidar_medians, lio_medians, fusion_medians;
  for (int r = 0; r < runs; ++r) {
    // Alternate which goes first, so that a slow phase of the machine hits both.
    for (const bool with_imu : {r % 2 == 1, r % 2 == 0}) {
      const Timing t = run(scenario, s, clouds, with_imu);
      (with_imu ? lio_medians : lidar_medians).push_back(median(t.per_scan_s));
      if (with_imu) fusion_medians.push_back(median(t.fusion_s));
    }
  }
  // Preintegration alone: every IMU sample, in 0.1 s pieces, ten times.
  const auto& imu = s.imu.samples;
  const auto pre_start = core::Clock::now();
  std::size_t pieces = 0;
  for (int repeat = 0; repeat < 10; ++repeat) {
    for (std::size_t k = 0; k + 20 < imu.size(); k += 20) {
      inertial::PreintegratedImu pim(scenario.imu.noise, inertial::ImuBias{});
      inertial::integrate_interval(imu, imu[k].stamp, imu[k + 20].stamp, pim);
      ++pieces;
    }
  }
  const double pre_s = core::seconds_since(pre_start);
  const double imu_seconds = 10.0 * (imu.back().stamp.seconds() - imu.front().stamp.seconds());
  std::printf("{\"scenario\": \"%s\", \"model\": \"%s\", \"scans\": %zu, \"mean_points_per_scan\": %.0f, \"runs\": %d, "
              "\"lidar_only_median_ms\": %.2f, \"lidar_inertial_median_ms\": %.2f, \"ratio\": %.3f, "
              "\"fusion_solve_median_ms\": %.3f, \"imu_samples\": %zu, \"preintegration_s_per_imu_s\": %.3g, "
              "\"preintegration_share_of_real_time_percent\": %.4f}\n",
              name.c_str(), model.c_str(), clouds.size(), static_cast<double>(points) / static_cast<double>(clouds.size()), runs,
              1e3 * median(lidar_medians), 1e3 * median(lio_medians), median(lio_medians) / median(lidar_medians),
              1e3 * median(fusion_medians), imu.size(), pre_s / imu_seconds, 100.0 * pre_s / imu_seconds);
  (void)pieces;
  return 0;
}
