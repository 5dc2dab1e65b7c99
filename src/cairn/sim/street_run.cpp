#include "cairn/sim/street_run.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "cairn/io/output_file.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/sim/carmen_log.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;

/// SE(2) pose lifted to SE(3) at height z (rotation about z only).
core::SE3 lift(const core::SE2& T, double z) {
  return core::SE3(Quaternion(Eigen::AngleAxisd(T.angle(), Vector3::UnitZ())), Vector3(T.x(), T.y(), z));
}

/// Ground truth at any time between samples: T_k * Exp(alpha * Log(T_k^-1 T_k+1)), the
/// constant-twist interpolation (exact for the unicycle's arcs and lines within one sample).
core::SE2 truth_at(const std::vector<TrajectorySample>& truth, double time_s) {
  const double t0 = truth.front().stamp.seconds();
  const double dt = truth.size() > 1 ? truth[1].stamp.seconds() - t0 : 1.0;
  const double x = (time_s - t0) / dt;
  if (truth.size() < 2 || x <= 0.0) return truth.front().T_world_body;
  const auto k = std::min(static_cast<std::size_t>(std::floor(x)), truth.size() - 2);
  const double alpha = std::min(x - static_cast<double>(k), 1.0);
  const core::SE2& a = truth[k].T_world_body;
  const core::SE2& b = truth[k + 1].T_world_body;
  return a * core::SE2::exp(alpha * (a.inverse() * b).log());
}

std::string indexed(const char* folder, std::size_t i, const char* extension) {
  char name[64];
  std::snprintf(name, sizeof name, "%s/%06zu.%s", folder, i, extension);
  return name;
}

void write_floats(const std::string& path, const std::vector<float>& values) {
  io::write_output(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float)));
  });
}

}  // namespace

World footprint(const World3D& world) {
  World out;
  out.name = world.name;
  for (const auto& box : world.boxes) {
    if (box.min.z() < 2.2) out.add_rectangle(box.min.head<2>(), box.max.head<2>());
  }
  for (const auto& cylinder : world.cylinders) out.circles.push_back({cylinder.center, cylinder.radius_m});
  return out;
}

core::SE3 lidar_pose(const core::SE2& T_world_body, const Lidar3DOptions& lidar) {
  return lift(T_world_body, lidar.mount_height_m);
}

void simulate_street_sensors(const Scenario& scenario, std::uint64_t lidar_seed, std::uint64_t camera_seed,
                             SimulationResult& result) {
  result.world_3d = build_world_3d(scenario).world;
  const auto& truth = result.truth;
  const double mount = scenario.lidar3d.mount_height_m;
  const auto T_world_lidar_at = [&](double time_s) { return lift(truth_at(truth, time_s), mount); };
  Random lidar_random(lidar_seed);
  std::size_t rays = 0;
  std::size_t points = 0;
  for (std::size_t k : result.scan_samples) {
    result.clouds.push_back(
        spin_scan(result.world_3d, truth[k].stamp.seconds(), T_world_lidar_at, scenario.lidar3d, lidar_random));
    rays += static_cast<std::size_t>(scenario.lidar3d.rings * scenario.lidar3d.columns);
    points += result.clouds.back().size();
  }
  result.max_range_fraction = rays > 0 ? 1.0 - static_cast<double>(points) / static_cast<double>(rays) : 0.0;

  Random camera_random(camera_seed);
  const core::SE3 T_body_camera = scenario.camera.T_body_camera();
  const double period = truth.size() > 1 ? truth[1].stamp.seconds() - truth[0].stamp.seconds() : 1.0;
  const auto step = static_cast<std::size_t>(std::max(1.0, std::round(scenario.camera.period_s / period)));
  for (std::size_t k = 0; k < truth.size(); k += step) {
    const auto seen = observe_with_camera(result.world_3d, lift(truth[k].T_world_body, 0.0) * T_body_camera,
                                          truth[k].stamp, scenario.camera, camera_random);
    result.camera_observations.insert(result.camera_observations.end(), seen.begin(), seen.end());
  }
}

std::vector<std::string> write_street_outputs(const SimulationResult& result, const Scenario& scenario,
                                              const std::string& directory) {
  std::vector<std::string> files;
  auto path_of = [&](const std::string& name) {
    files.push_back(name);
    return (fs::path(directory) / name).string();
  };
  const bool pcd = scenario.lidar3d_format == "pcd";
  if (pcd) {
    fs::create_directories(fs::path(directory) / "scans");
  } else {
    for (const char* folder : {"velodyne", "velodyne_times"}) fs::create_directories(fs::path(directory) / folder);
  }
  for (std::size_t i = 0; i < result.clouds.size(); ++i) {
    if (pcd) {
      io::PointCloud cloud;
      cloud.points.reserve(result.clouds[i].size());
      for (const auto& p : result.clouds[i]) {
        cloud.points.push_back(p.position.cast<float>());
        cloud.intensity.push_back(0.0F);
        cloud.ring.push_back(static_cast<std::uint16_t>(p.ring));
        cloud.time_s.push_back(static_cast<float>(p.time_offset_s));
      }
      io::write_output(path_of(indexed("scans", i, "pcd")), [&](std::ostream& out) { io::write_pcd(out, cloud); });
      continue;
    }
    std::vector<float> xyzi;
    std::vector<float> times;
    xyzi.reserve(4 * result.clouds[i].size());
    times.reserve(result.clouds[i].size());
    for (const auto& p : result.clouds[i]) {
      xyzi.insert(xyzi.end(), {static_cast<float>(p.position.x()), static_cast<float>(p.position.y()),
                               static_cast<float>(p.position.z()), 0.0F});
      times.push_back(static_cast<float>(p.time_offset_s));
    }
    write_floats(path_of(indexed("velodyne", i, "bin")), xyzi);
    write_floats(path_of(indexed("velodyne_times", i, "bin")), times);
  }

  const double mount = scenario.lidar3d.mount_height_m;
  io::Trajectory truth;
  io::Trajectory odometry;
  io::Trajectory kitti;
  // KITTI layout: poses relative to the first scan (KITTI's convention); PCD: in the world frame.
  const core::SE3 T_lidar0_world =
      pcd ? core::SE3() : lift(result.truth[result.scan_samples.front()].T_world_body, mount).inverse();
  for (std::size_t k : result.scan_samples) {
    const core::SE3 T_world_lidar = lift(result.truth[k].T_world_body, mount);
    truth.stamps.push_back(result.truth[k].stamp);
    truth.poses.push_back(T_world_lidar);
    odometry.stamps.push_back(result.truth[k].stamp);
    odometry.poses.push_back(lift(result.odometry.poses[k], mount));
    kitti.stamps.push_back(result.truth[k].stamp);
    kitti.poses.push_back(T_lidar0_world * T_world_lidar);
  }
  io::write_tum(path_of("ground_truth.tum"), truth);
  io::write_tum(path_of("odometry.tum"), odometry);
  const std::string poses_path = path_of("poses.txt");
  io::write_kitti(poses_path, kitti, path_of("times.txt"));

  io::write_output(path_of("camera_observations.csv"), [&](std::ostream& out) {
    out << "time_s,landmark_id,u_px,v_px\n";
    std::string line;
    for (const auto& o : result.camera_observations) {
      line = format_carmen_time(o.stamp) + ',' + std::to_string(o.landmark_id) + ',';
      io::append_number(line, o.u_px);
      line += ',';
      io::append_number(line, o.v_px);
      line += '\n';
      out << line;
    }
  });
  io::write_output(path_of("world_3d.txt"), [&](std::ostream& out) {
    out << "# cairn world '" << result.world_3d.name << "': GROUND z=0 | BOX min_x min_y min_z max_x max_y max_z | "
        << "CYLINDER cx cy radius z_min z_max (vertical) | LANDMARK id x y z (metres, world frame, z up)\n";
    if (!result.world_3d.moving_boxes.empty()) {
      out << "# MOVING_BOX length width height speed_mps phase_m x0 y0 x1 y1 ...: a box driving around the closed "
             "path, at time t its centre phase + speed t metres along it, its length along the current edge\n";
    }
    if (result.world_3d.ground) out << "GROUND\n";
    std::string line;
    auto emit = [&](const std::string& head, std::initializer_list<double> values) {
      line = head;
      for (double v : values) {
        line += ' ';
        io::append_number(line, v);
      }
      line += '\n';
      out << line;
    };
    for (const auto& b : result.world_3d.boxes) emit("BOX", {b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z()});
    for (const auto& c : result.world_3d.cylinders) emit("CYLINDER", {c.center.x(), c.center.y(), c.radius_m, c.z_min_m, c.z_max_m});
    for (const auto& l : result.world_3d.landmarks) {
      emit("LANDMARK " + std::to_string(l.id), {l.position.x(), l.position.y(), l.position.z()});
    }
    for (const auto& m : result.world_3d.moving_boxes) {
      line = "MOVING_BOX";
      for (double v : {m.length_m, m.width_m, m.height_m, m.speed_mps, m.phase_m}) {
        line += ' ';
        io::append_number(line, v);
      }
      for (const auto& p : m.path) {
        for (double v : {p.x(), p.y()}) {
          line += ' ';
          io::append_number(line, v);
        }
      }
      line += '\n';
      out << line;
    }
  });
  io::write_output(path_of("loops.txt"), [&](std::ostream& out) {
    out << "# true loop closures: scans i < j whose LiDAR positions (poses.txt) are at most ";
    std::string number;
    io::append_number(number, scenario.loop_truth.max_distance_m);
    out << number << " m apart and whose times differ by at least ";
    number.clear();
    io::append_number(number, scenario.loop_truth.min_separation_s);
    out << number << " s\n# i j distance_m heading_difference_deg (0: same direction, 180: reverse) time_difference_s\n";
    char text[128];
    for (const auto& loop : result.true_loops) {
      std::snprintf(text, sizeof text, "%zu %zu %.3f %.1f %.1f\n", loop.earlier, loop.later, loop.distance_m,
                    loop.heading_difference_rad * 180.0 / std::numbers::pi, loop.time_difference_s);
      out << text;
    }
  });
  return files;
}

}  // namespace cairn::sim
