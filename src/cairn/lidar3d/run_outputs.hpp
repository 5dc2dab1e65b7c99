#pragma once
/// \file
/// Every file of a `cairn slam3d` run, written into an io::OutputDirectory and committed
/// together (docs/lidar3d.md): trajectory.tum and trajectory.kitti (every processed scan's sensor
/// pose at its stamp), map.ply (the global map), map.png (render_top_down, with the aligned ground
/// truth when there is one) and report.json (report.hpp); with an IMU also inertial_states.csv and
/// inertial.png (inertial_outputs.hpp).

#include <optional>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/lidar3d/inertial_outputs.hpp"
#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/report.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"

namespace cairn::lidar3d {

/// Writes the files of `run` (after SlamRun::finish, at least one processed scan) into `out` and
/// commits it. `ground_truth`: one pose per scan of `sequence`, or none; `picture_px`: longer side
/// of map.png; `wall_time_s` and `interrupted` as report_json takes them; `inertial` the run's IMU
/// (after InertialRun::finish) or null. Returns the errors
/// against the ground truth that the report holds (SlamRun::errors_against). Throws what the
/// writers and evaluate_trajectory throw, before the commit.
std::optional<TrajectoryErrors> write_run_outputs(io::OutputDirectory& out, const SlamRunInputs& inputs,
                                                  const ScanSequence& sequence, const LidarSlam& slam, const SlamRun& run,
                                                  const std::vector<core::SE3>& ground_truth, int picture_px,
                                                  double wall_time_s, bool interrupted,
                                                  const InertialRun* inertial = nullptr);

}  // namespace cairn::lidar3d
