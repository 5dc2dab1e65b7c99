#include "cairn/landmarks/landmark_run.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "cairn/core/so2.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/landmark_csv.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::landmarks {
namespace {

TimedPose to_timed_pose(core::Timestamp time, const core::SE2& T_world_body) {
  return {time, Vector3(T_world_body.x(), T_world_body.y(), T_world_body.angle())};
}

}  // namespace

std::optional<Vector3> odometry_at(const std::vector<TimedPose>& odometry, core::Timestamp time) {
  if (odometry.empty() || time < odometry.front().time || odometry.back().time < time) return std::nullopt;
  const auto it = std::lower_bound(odometry.begin(), odometry.end(), time,
                                   [](const TimedPose& p, core::Timestamp t) { return p.time < t; });
  if (it->time == time) return it->pose;
  const TimedPose& b = *it;
  const TimedPose& a = *(it - 1);
  const double s = (time.seconds() - a.time.seconds()) / (b.time.seconds() - a.time.seconds());
  Vector3 pose = a.pose + s * (b.pose - a.pose);
  pose.z() = core::wrap_angle(a.pose.z() + s * core::wrap_angle(b.pose.z() - a.pose.z()));
  return pose;
}

LandmarkRun read_landmark_run(const std::string& directory) {
  namespace fs = std::filesystem;
  LandmarkRun run;
  run.source = directory;
  const fs::path dir(directory);
  if (!fs::is_directory(dir)) {
    throw io::ParseError(directory, 0,
                         "expected a directory written by `cairn simulate landmarks --out DIR` (log.clf, "
                         "landmark_observations.csv), found no such directory");
  }
  const std::string log_path = (dir / "log.clf").string();
  const std::string observations_path = (dir / "landmark_observations.csv").string();
  for (const auto& required : {log_path, observations_path}) {
    if (!fs::exists(required)) throw io::ParseError(required, 0, "expected this file, found none");
  }
  const std::string map_path = (dir / "landmarks.csv").string();
  if (fs::exists(map_path)) run.true_landmarks = io::read_landmark_map(map_path);

  const io::CarmenLog log = io::read_carmen_log(log_path);
  for (const io::OdometryRecord& record : log.odometry) {
    if (!run.odometry.empty() && !(run.odometry.back().time < record.time)) {
      throw io::ParseError(log_path, record.line, "ODOM times must increase strictly");
    }
    run.odometry.push_back(to_timed_pose(record.time, record.T_odom_robot));
    // Finite numbers can still make an infinite motion (-1e308 then 1e308): every filter and
    // graph downstream would carry NaN into "ok"-looking results.
    if (run.odometry.size() >= 2 && !(run.odometry.back().pose - run.odometry[run.odometry.size() - 2].pose).allFinite()) {
      throw io::ParseError(log_path, record.line, "the motion from the previous ODOM record is not a finite number of metres");
    }
  }
  if (run.odometry.empty()) throw io::ParseError(log_path, 0, "expected ODOM records, found none");

  run.observations = io::read_landmark_observations(observations_path, run.true_landmarks.empty() ? nullptr : &run.true_landmarks);
  // Steps are made at observation times: without observations the run would be one pose that
  // ignores every odometry record, and its error would read 0.
  if (run.observations.empty()) {
    throw io::ParseError(observations_path, 0,
                         "holds no observation (" + std::to_string(run.odometry.size()) +
                             " odometry records in log.clf): a landmark SLAM run needs observations");
  }
  for (const Observation& o : run.observations) {
    if (o.time < run.odometry.front().time || run.odometry.back().time < o.time) {
      throw io::ParseError(observations_path, o.line, "observation time is outside the odometry's time span in " + log_path);
    }
  }

  const std::string truth_path = (dir / "ground_truth.tum").string();
  if (fs::exists(truth_path)) {
    const io::Trajectory truth = io::read_tum(truth_path);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const core::SE3& T = truth.poses[i];
      const double yaw = std::atan2(T.so3().matrix()(1, 0), T.so3().matrix()(0, 0));
      run.ground_truth.push_back({truth.stamps[i], Vector3(T.translation().x(), T.translation().y(), yaw)});
    }
  }
  return run;
}

}  // namespace cairn::landmarks
