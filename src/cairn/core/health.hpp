#pragma once
/// \file
/// The health every pipeline reports per measurement (slam2d per scan, lidar3d per scan, vslam per
/// frame), one enum for all: `ok` (the measurement constrained the pose well), `degraded` (it
/// constrained it poorly or in part: a degenerate direction, few inliers, a prior carrying the
/// rest), `lost` (the front end could not place it; a new map segment starts, and the segment
/// merges back when a verified match joins it). Each pipeline's docs say when it reports which.

#include <string_view>

namespace cairn::core {

enum class Health { kOk, kDegraded, kLost };

/// "ok", "degraded" or "lost" (the words report.json, scans.csv and frames.csv use).
constexpr std::string_view to_string(Health health) {
  switch (health) {
    case Health::kOk: return "ok";
    case Health::kDegraded: return "degraded";
    case Health::kLost: return "lost";
  }
  return "?";
}

}  // namespace cairn::core
