#pragma once
/// \file
/// The landmark CSV files: a landmark map and range-bearing observations, written by
/// `cairn simulate landmarks` and read by `cairn landmarks`. Plain CSV with one header line.
///
/// landmarks.csv (the true map, world frame):
///   id,x_m,y_m
///   0,12.5,-3.25
/// landmark_observations.csv (what the range-bearing sensor reported):
///   time_s,landmark_id,range_m,bearing_rad
///   12.300000,0,4.0312,-0.2231
/// time_s is written as the CARMEN log's ipc_timestamp (6 decimals), so observations and scans
/// taken at the same instant carry the same text; numbers are the shortest text that reads
/// back to the same double; bearing is from the body x axis, counter-clockwise, in (-pi, pi].
///
/// Reading skips blank lines and '#' comments. Strictness (every refusal is a ParseError naming
/// file and line): a missing or wrong header, a wrong number of fields, a number that is not
/// finite, a negative or non-integer id, an id twice in the map; in observations a range that is
/// not > 0, a bearing outside [-pi, pi], an id absent from the known ids (when given),
/// times going backwards.

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "cairn/core/time.hpp"
#include "cairn/core/types.hpp"

namespace cairn::io {

/// A landmark of the map (a line of landmarks.csv), world frame.
struct LandmarkPosition {
  std::int64_t id = 0;
  double x_m = 0.0;
  double y_m = 0.0;
};

/// A range-bearing observation (a line of landmark_observations.csv).
struct LandmarkObservation {
  core::Timestamp time;
  /// The landmark's identity as the sensor reported it (known association uses it; unknown
  /// association uses it only to score the associations afterwards). Never negative in a file;
  /// landmarks::kSpuriousId (-1) marks clutter made in memory.
  std::int64_t landmark_id = 0;
  double range_m = 0.0;
  double bearing_rad = 0.0;
  /// Line in the observation file (0 when made in memory).
  std::size_t line = 0;
};

/// Reads landmarks.csv: positions by id. Throws ParseError naming file and line.
std::map<std::int64_t, Vector2> read_landmark_map(const std::string& path);

/// Reads landmark_observations.csv, in file order. When `known_ids` is given, an id not in it is
/// refused. Throws ParseError naming file and line.
std::vector<LandmarkObservation> read_landmark_observations(const std::string& path,
                                                            const std::map<std::int64_t, Vector2>* known_ids = nullptr);

/// Write landmarks.csv and landmark_observations.csv atomically (write_output), records in the
/// order given; `line` is not written. Precondition: observation times >= 0. Throw ParseError
/// when the file cannot be written.
void write_landmark_map(const std::string& path, const std::vector<LandmarkPosition>& landmarks);
void write_landmark_observations(const std::string& path, const std::vector<LandmarkObservation>& observations);

}  // namespace cairn::io
