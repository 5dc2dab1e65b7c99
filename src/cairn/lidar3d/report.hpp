#pragma once
/// \file
/// report.json of a `cairn slam3d` run (docs/lidar3d.md): the input (scans listed, processed,
/// skipped), the options in effect, a summary (health counts, map segments and points), the
/// health events, loop closure (counts, times, every candidate with its decision), time per scan
/// by stage, the errors against a ground truth when there is one, every scan's record, and with an
/// IMU its "inertial" section (inertial_outputs.hpp).

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cairn/lidar3d/inertial_outputs.hpp"
#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"

namespace cairn::lidar3d {

/// A pose as report.json writes it: {"t": [x, y, z], "q_xyzw": [x, y, z, w]}.
nlohmann::json pose_json(const core::SE3& T);

/// What the run was asked for, as the report records it.
struct SlamRunInputs {
  std::vector<std::string> scans;  ///< the scan folder or files as given
  std::string times_file;          ///< empty: none (times made up)
  std::string preset;              ///< preset_options name the options started from
  std::string ground_truth_file;   ///< empty: none
};

/// The report of `run` of `slam` over `sequence`, after SlamRun::finish and with at least one
/// processed scan; `wall_time_s` from the start of the run to the global map; `interrupted` when
/// it was cut short; `errors` against the ground truth (SlamRun::errors_against), if any;
/// `inertial`: the run's IMU (after InertialRun::finish), or null for a LiDAR-only run, whose report
/// has neither the "inertial" section nor the options' `imu` section.
nlohmann::json report_json(const SlamRunInputs& inputs, const ScanSequence& sequence, const LidarSlam& slam,
                           const SlamRun& run, double wall_time_s, bool interrupted,
                           const std::optional<TrajectoryErrors>& errors, const InertialRun* inertial = nullptr);

}  // namespace cairn::lidar3d
