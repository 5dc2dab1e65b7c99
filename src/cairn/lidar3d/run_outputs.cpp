#include "cairn/lidar3d/run_outputs.hpp"

#include <ostream>
#include <stdexcept>
#include <string>

#include "cairn/io/json_text.hpp"
#include "cairn/lidar3d/gnss_outputs.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/viz/render.hpp"

namespace cairn::lidar3d {
namespace {

// inertial_states.csv and inertial.png.
void write_inertial_outputs(io::OutputDirectory& out, const InertialRun& inertial) {
  io::write_output(out.staging_path("inertial_states.csv"), [&](std::ostream& o) { write_inertial_states_csv(o, inertial); });
  const viz::RenderResult png = viz::render(inertial_figure(inertial), viz::ImageFormat::kPng);
  if (!png.ok) throw std::runtime_error("cannot draw inertial.png: " + png.message);
  io::write_output(out.staging_path("inertial.png"), [&](std::ostream& o) { o << png.bytes; });
}

}  // namespace

std::optional<TrajectoryErrors> write_run_outputs(io::OutputDirectory& out, const SlamRunInputs& inputs,
                                                  const ScanSequence& sequence, const LidarSlam& slam, const SlamRun& run,
                                                  const std::vector<core::SE3>& ground_truth, int picture_px,
                                                  double wall_time_s, bool interrupted, const InertialRun* inertial) {
  io::Trajectory trajectory;
  for (const OdometryScanResult& r : run.scans()) {
    trajectory.stamps.push_back(core::Timestamp::from_seconds(r.time_s));
    trajectory.poses.push_back(r.T_world_sensor);
  }
  io::write_output(out.staging_path("trajectory.tum"), [&](std::ostream& o) { io::write_tum(o, trajectory); });
  io::write_output(out.staging_path("trajectory.kitti"), [&](std::ostream& o) { io::write_kitti(o, trajectory); });
  const std::vector<Eigen::Vector3f> map_points = run.global_map().points();
  io::write_output(out.staging_path("map.ply"), [&](std::ostream& o) {
    io::write_ply(o, map_points, "cairn slam3d map, voxel " + std::to_string(run.map_voxel_m()) + " m, world frame = first scan");
  });
  if (run.dynamic_options()) {
    io::write_output(out.staging_path("dynamic.ply"), [&](std::ostream& o) {
      io::write_ply(o, run.dynamic_points(), "cairn slam3d: points seen on something that moved, left out of map.ply");
    });
  }
  const std::vector<unsigned char> png =
      render_top_down(map_points, run.scans(), run.ground_truth_of_scans(ground_truth), picture_px);
  io::write_output(out.staging_path("map.png"), [&](std::ostream& o) {
    o.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });

  if (inertial != nullptr) write_inertial_outputs(out, *inertial);
  if (slam.gnss() != nullptr) {
    io::write_output(out.staging_path("gnss_fixes.csv"), [&](std::ostream& o) { write_gnss_fixes_csv(o, *slam.gnss()); });
    if (slam.gnss()->aligned()) {
      io::write_output(out.staging_path("trajectory_enu.tum"),
                       [&](std::ostream& o) { io::write_tum(o, enu_trajectory(*slam.gnss(), trajectory)); });
    }
  }

  const std::optional<TrajectoryErrors> errors = run.errors_against(ground_truth);
  const nlohmann::json report = report_json(inputs, sequence, slam, run, wall_time_s, interrupted, errors, inertial);
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  out.commit();
  return errors;
}

}  // namespace cairn::lidar3d
