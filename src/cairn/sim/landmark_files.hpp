#pragma once
/// \file
/// The simulator's landmarks.csv and landmark_observations.csv: its landmarks and observations
/// converted to io's records and written by io/landmark_csv.hpp, which documents the format.

#include <string>
#include <vector>

#include "cairn/sim/landmark_sensor.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// Both throw io::ParseError when the file cannot be written; both write atomically.
void write_landmark_map(const std::string& path, const std::vector<Landmark>& landmarks);
void write_landmark_observations(const std::string& path, const std::vector<LandmarkObservation>& observations);

}  // namespace cairn::sim
