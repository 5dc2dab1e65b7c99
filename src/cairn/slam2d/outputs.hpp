#pragma once
/// \file
/// What `cairn slam2d` writes, each file whole or not at all (written to a temporary name and
/// renamed):
///  - map.pgm + map.yaml: the occupancy grid in the ROS map_server convention (P5, 254 free,
///    0 occupied, 205 unknown; YAML with resolution, origin of the lower-left pixel,
///    occupied_thresh 0.65, free_thresh 0.196, negate 0);
///  - map.png: the map with the trajectory coloured by health, accepted loop closures, and where
///    map segments began and merged;
///  - trajectory.tum: every scan's laser pose, sorted by time (a repeated stamp keeps the first);
///  - scans.csv: per scan in log order: time, pose, health, match inlier fraction, degeneracy,
///    standard deviations of the local match (sqrt of the covariance diagonal), keyframe flag,
///    map segment;
///  - graph.g2o: the keyframe pose graph with optimised vertices;
///  - corrected.clf: the log's laser records as FLASER lines with the corrected pose in the
///    x y theta fields and the odometry kept in odom_x odom_y odom_theta (what the Freiburg
///    evaluator reads);
///  - report.json (written by the command): summary, timings, loop candidates, health events.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/eval/matrix_trajectory.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/slam2d/slam.hpp"

namespace cairn::slam2d {

struct OutputFiles {
  std::string map_pgm, map_yaml, map_png, trajectory, scans, graph, corrected_log, report;
  /// Every path above.
  std::vector<std::string> all() const { return {map_pgm, map_yaml, map_png, trajectory, scans, graph, corrected_log, report}; }
};

/// The files of a run in `directory` (write_outputs writes all but the report).
OutputFiles output_files(const std::string& directory);

/// The scans' poses sorted by time, repeated stamps dropped (the first kept).
io::Trajectory to_trajectory(const Slam2d& slam);
eval::MatrixTrajectory to_matrix_trajectory(const Slam2d& slam);

/// Writes every file but the report into `directory`; `scans_used` = scans fed from `log`.
OutputFiles write_outputs(const Slam2d& slam, const io::CarmenLog& log, std::size_t scans_used,
                          const std::string& directory, const Slam2dOptions& options);

/// Map files alone (PGM + YAML, PNG).
void write_map_pgm(const ProbabilityGrid& grid, const std::string& pgm_path, const std::string& yaml_path);
/// Map segments on the picture: where each began (a ring and its label, red when it stayed
/// unmerged) and the matches that merged segments (thick violet lines).
struct SegmentMarks {
  struct Start {
    Eigen::Vector2d position = Eigen::Vector2d::Zero();
    std::string label;
    bool merged = true;
  };
  std::vector<Start> starts;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> merges;
};
/// The segments of a run (nothing when it kept one segment).
SegmentMarks segment_marks(const Slam2d& slam, const std::vector<ScanResult>& trajectory);

void write_map_png(const ProbabilityGrid& grid, const std::vector<ScanResult>& trajectory,
                   const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& loops, const std::string& path,
                   const SegmentMarks& segments = {});

/// The run's report (summary, options in effect, loop candidates, health events).
nlohmann::json report_json(const Slam2d& slam, const Slam2dOptions& options);

/// The health events as report.json lists them (time, scan, from, to, reason): slam2d's and
/// localize2d's reports.
nlohmann::json health_events_json(const std::vector<HealthEvent>& events);

}  // namespace cairn::slam2d
