#pragma once
/// \file
/// A pipeline's results as an MCAP file Foxglove shows out of the box (its well-known JSON
/// schemas, docs.foxglove.dev "Schemas"), so users look at cairn's output in the viewer they use
/// for their robot's data. Channels (all in frame `frame_id`, JSON-encoded):
///   /tf              foxglove.FrameTransform  frame_id -> body_frame_id at each pose's stamp
///   /pose            foxglove.PoseInFrame     the estimate at each stamp
///   /trajectory      foxglove.PosesInFrame    the whole trajectory (one message, at the first stamp)
///   /map             foxglove.PointCloud      the map's points (3D), one message at the first stamp
///   /grid            foxglove.Grid            the occupancy grid (2D), one message at the first stamp
///   /loop_closures   foxglove.SceneUpdate     accepted loop closures as line segments
///   /health          foxglove.Log             one entry per health change (info / warning / error)
/// Messages are written in log-time order; the file is what McapWriter writes (zstd chunks,
/// summary, indexes).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "cairn/core/se3.hpp"

namespace cairn::bag {

struct OccupancyGrid {
  double resolution_m = 0.05;
  std::size_t width = 0, height = 0;
  /// World position of cell (0, 0)'s corner; rows go along +y.
  Eigen::Vector2d origin_m = Eigen::Vector2d::Zero();
  /// Row-major from row 0, ROS's convention: 0..100 occupancy per cent, -1 unknown.
  std::vector<std::int8_t> cells;
};

struct FoxgloveResults {
  std::string frame_id = "map";
  std::string body_frame_id = "base_link";
  std::vector<std::int64_t> stamps_ns;
  std::vector<core::SE3> T_frame_body;  ///< one per stamp
  /// One per stamp, "ok", "degraded" or "lost" (empty: no health channel).
  std::vector<std::string> health;
  std::vector<Eigen::Vector3f> map_points;
  std::optional<OccupancyGrid> grid;
  /// Accepted loop closures, as the positions of their two ends in `frame_id`.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> loop_closures;
};

/// Writes `results` as MCAP to `out`. Throws std::invalid_argument when the poses and stamps (or
/// health) differ in number; std::runtime_error when the stream fails.
void write_foxglove_mcap(std::ostream& out, const FoxgloveResults& results);

/// write_foxglove_mcap into the file `path`, whole or not at all (io::write_output).
void write_foxglove_mcap(const std::string& path, const FoxgloveResults& results);

}  // namespace cairn::bag
