#pragma once
/// \file
/// Landmark map and observation files: plain CSV with one header line.
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

#include <string>
#include <vector>

#include "cairn/sim/landmark_sensor.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// Both throw io::ParseError when the file cannot be written; both write atomically.
void write_landmark_map(const std::string& path, const std::vector<Landmark>& landmarks);
void write_landmark_observations(const std::string& path, const std::vector<LandmarkObservation>& observations);

}  // namespace cairn::sim
