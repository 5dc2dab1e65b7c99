#pragma once
/// \file
/// The input of a landmark SLAM run: odometry, range-bearing observations and (optionally) the
/// ground truth, read from a `cairn simulate landmarks --out DIR` directory:
///
///   DIR/log.clf                     CARMEN log: the ODOM records (dead reckoning T_odom_body)
///   DIR/landmark_observations.csv   time_s,landmark_id,range_m,bearing_rad
///   DIR/landmarks.csv               id,x_m,y_m (optional: the true map, for errors and NEES)
///   DIR/ground_truth.tum            T_world_body (optional: for ATE and NEES)
///
/// The world frame of the estimate is the odometry frame at the first ODOM record, which the
/// simulator makes equal to its world frame, so estimates and ground truth are compared without
/// alignment.
///
/// The two CSV files are read by io/landmark_csv.hpp, which documents their format and
/// strictness. Strictness here (every refusal is an io::ParseError naming file and line): a
/// missing directory or required file, ODOM times not increasing or an infinite motion between
/// them, no ODOM record, no observation, an observation id absent from landmarks.csv (when that
/// file exists), an observation outside the odometry's time span.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/time.hpp"
#include "cairn/core/types.hpp"
#include "cairn/io/landmark_csv.hpp"

namespace cairn::landmarks {

/// Marks an observation that no landmark produced (injected clutter, see clutter.hpp).
inline constexpr std::int64_t kSpuriousId = -1;

/// A range-bearing observation: time, landmark_id (or kSpuriousId), range_m, bearing_rad, line.
using Observation = io::LandmarkObservation;

struct TimedPose {
  core::Timestamp time;
  /// T_world_body as (x, y, theta).
  Vector3 pose = Vector3::Zero();
};

struct LandmarkRun {
  /// Dead reckoning T_odom_body, strictly increasing in time.
  std::vector<TimedPose> odometry;
  /// Observations in time order.
  std::vector<Observation> observations;
  /// The true landmark positions by id (empty when unknown).
  std::map<std::int64_t, Vector2> true_landmarks;
  /// Ground truth (empty when unknown), strictly increasing in time.
  std::vector<TimedPose> ground_truth;
  /// Where it came from, for reports.
  std::string source;
};

/// Reads the files above from `directory`. Throws io::ParseError naming file and line.
LandmarkRun read_landmark_run(const std::string& directory);

/// The two CSV readers, io::read_landmark_observations and io::read_landmark_map.
using io::read_landmark_map;
using io::read_landmark_observations;

/// Dead reckoning at `time`, linearly interpolated between the bracketing records (angle along
/// the shorter arc); nullopt outside the span.
std::optional<Vector3> odometry_at(const std::vector<TimedPose>& odometry, core::Timestamp time);

}  // namespace cairn::landmarks
