#pragma once
/// \file
/// `cairn vslam --mcap FILE`: every frame's camera pose with its tracking health and the map
/// points as an MCAP file Foxglove shows (bag/foxglove_results.hpp), written whole or not at all.

#include <string>

#include "cairn/vslam/outputs.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::vslam {

/// The poses are VisualSlam::trajectory()'s (what trajectory.tum holds), at the frames' stamps.
void write_foxglove_mcap(const std::string& path, const VisualSlam& slam, const RunRecord& run);

}  // namespace cairn::vslam
