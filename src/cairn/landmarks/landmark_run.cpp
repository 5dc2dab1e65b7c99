#include "cairn/landmarks/landmark_run.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "cairn/core/so2.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::landmarks {
namespace {

std::vector<std::string_view> csv_fields(const io::TextReader& reader, std::size_t expected, std::string_view header) {
  auto fields = io::split_fields(reader.line(), ',');
  if (fields.size() != expected) {
    throw io::ParseError(reader.path(), reader.line_number(),
                         "expected " + std::to_string(expected) + " comma-separated fields (" + std::string(header) +
                             "), found " + std::to_string(fields.size()));
  }
  return fields;
}

// Skips blank lines and '#' comments; refuses a missing or wrong header.
void expect_header(io::TextReader& reader, std::string_view header) {
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    if (reader.line() != header) {
      throw io::ParseError(reader.path(), reader.line_number(),
                           "expected the header '" + std::string(header) + "', found " + io::quote_token(reader.line()));
    }
    return;
  }
  throw io::ParseError(reader.path(), reader.line_number(), "expected the header '" + std::string(header) + "', found an empty file");
}

TimedPose to_timed_pose(core::Timestamp time, const core::SE2& T_world_body) {
  return {time, Vector3(T_world_body.x(), T_world_body.y(), T_world_body.angle())};
}

}  // namespace

std::map<std::int64_t, Vector2> read_landmark_map(const std::string& path) {
  io::TextReader reader(path);
  constexpr std::string_view kHeader = "id,x_m,y_m";
  expect_header(reader, kHeader);
  std::map<std::int64_t, Vector2> map;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    const auto f = csv_fields(reader, 3, kHeader);
    const std::int64_t id = io::parse_id(reader, f[0], "the landmark id");
    const Vector2 p(io::parse_double(reader, f[1], "x_m"), io::parse_double(reader, f[2], "y_m"));
    if (!map.emplace(id, p).second) {
      throw io::ParseError(path, reader.line_number(), "landmark id " + std::to_string(id) + " appears twice");
    }
  }
  return map;
}

std::vector<Observation> read_landmark_observations(const std::string& path,
                                                    const std::map<std::int64_t, Vector2>* known_ids) {
  io::TextReader reader(path);
  constexpr std::string_view kHeader = "time_s,landmark_id,range_m,bearing_rad";
  expect_header(reader, kHeader);
  std::vector<Observation> observations;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    const auto f = csv_fields(reader, 4, kHeader);
    Observation o;
    o.line = reader.line_number();
    const auto time = core::Timestamp::parse_seconds(f[0]);
    if (!time) {
      throw io::ParseError(path, o.line, "expected a time in seconds for time_s, found " + io::quote_token(f[0]));
    }
    o.time = *time;
    o.landmark_id = io::parse_id(reader, f[1], "landmark_id");
    o.range_m = io::parse_double(reader, f[2], "range_m");
    o.bearing_rad = io::parse_double(reader, f[3], "bearing_rad");
    if (!(o.range_m > 0.0)) {
      throw io::ParseError(path, o.line, "expected range_m > 0, found " + io::quote_token(f[2]));
    }
    if (std::abs(o.bearing_rad) > std::numbers::pi + 1e-9) {
      throw io::ParseError(path, o.line, "expected bearing_rad in [-pi, pi], found " + io::quote_token(f[3]));
    }
    if (known_ids != nullptr && known_ids->count(o.landmark_id) == 0) {
      throw io::ParseError(path, o.line,
                           "landmark_id " + std::to_string(o.landmark_id) + " is not in the landmark map (landmarks.csv)");
    }
    if (!observations.empty() && o.time < observations.back().time) {
      throw io::ParseError(path, o.line, "time_s goes backwards (previous line has a later time)");
    }
    observations.push_back(o);
  }
  return observations;
}

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
  if (fs::exists(map_path)) run.true_landmarks = read_landmark_map(map_path);

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

  run.observations = read_landmark_observations(observations_path, run.true_landmarks.empty() ? nullptr : &run.true_landmarks);
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
