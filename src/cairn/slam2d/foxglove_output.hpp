#pragma once
/// \file
/// `cairn slam2d --mcap FILE`: the run's trajectory (every scan's laser pose), health changes,
/// occupancy grid and accepted loop closures as an MCAP file Foxglove shows
/// (bag/foxglove_results.hpp), written whole or not at all.

#include <string>

#include "cairn/slam2d/slam.hpp"

namespace cairn::slam2d {

/// The grid is rendered at options.output_map_resolution_m, as map.pgm is.
void write_foxglove_mcap(const std::string& path, const Slam2d& slam, const Slam2dOptions& options);

}  // namespace cairn::slam2d
