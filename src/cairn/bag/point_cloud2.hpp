#pragma once
/// \file
/// sensor_msgs/PointCloud2 into cairn's io::PointCloud, for any field layout and point step.
///
/// Fields by name (the names the common drivers write):
///   * x y z (required; FLOAT32 or FLOAT64);
///   * intensity: `intensity` (Velodyne, Ouster, Hesai, Livox), else `i`, else `reflectivity`;
///   * ring: `ring` (Velodyne, Ouster, Hesai), else `line` (Livox);
///   * per-point time, converted to seconds relative to the message's header stamp:
///     `time` (velodyne_pointcloud, LIO-SAM: FLOAT32 seconds relative to the stamp),
///     `t` (ouster_ros: UINT32 nanoseconds relative to the stamp),
///     `offset_time` (Livox: UINT32 nanoseconds relative to the stamp),
///     `timestamp` (Hesai, Robosense: FLOAT64 absolute seconds; livox_ros_driver2: FLOAT64 absolute
///     nanoseconds): absolute times are told apart by magnitude (> 1e15: nanoseconds, > 1e8:
///     seconds since the epoch) and made relative to the stamp; smaller values are taken as
///     seconds relative to the stamp.
/// Any other field is skipped by its offset. Big-endian clouds are byte-swapped. Points with a
/// non-finite coordinate are dropped and counted (organised clouds mark missing returns so).
/// A layout that cannot hold its points (point_step smaller than a field's end, data shorter
/// than width x height x point_step, a datatype outside 1..8) throws std::runtime_error saying so.

#include <cstddef>
#include <cstdint>
#include <string>

#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/value.hpp"
#include "cairn/io/point_cloud.hpp"

namespace cairn::bag {

struct PointCloud2Report {
  Header header;
  std::size_t dropped_non_finite = 0;
  /// The names of the fields read as intensity, ring and time ("" when absent).
  std::string intensity_field, ring_field, time_field;
};

/// Decodes a sensor_msgs/PointCloud2 value.
io::PointCloud to_point_cloud(const Value& message, PointCloud2Report* report = nullptr);

}  // namespace cairn::bag
