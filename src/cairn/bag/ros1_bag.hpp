#pragma once
/// \file
/// The ROS 1 bag reader: a Container over a bag of format 2.0 (wiki.ros.org/Bags/Format/2.0), with
/// chunks stored plain or compressed with bz2 or lz4 (the LZ4 frame format roslz4 writes).
///
/// With its index (the bag header's index_pos and the connection and chunk info records there) the
/// bag is opened from the index alone; without one (a recording cut off, a truncated copy) its
/// records are scanned from the start as `rosbag reindex` would, whatever is whole is read, and
/// ContainerSummary::indexed is false. Messages stream in log-time order with at most the chunks
/// that overlap in time decompressed at once. Format 1.2 ("#ROSRECORD V1.2") is refused with the
/// command that converts it.

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "cairn/bag/container.hpp"

namespace cairn::bag {

/// Opens the ROS 1 bag (format 2.0) at `path` and reads its index, or, without a usable index,
/// scans its records. Throws io::ParseError ("byte N: expected ..., found ...") for an empty,
/// damaged or unsupported file (format 1.2, encrypted bags, unknown chunk compression).
std::unique_ptr<Container> open_ros1_bag(const std::string& path);

/// True when `first_bytes` (the start of a file) read "#ROSBAG V" (any version) or "#ROSRECORD V"
/// (format 1.2 and older), so that format detection sends every ROS 1 bag to open_ros1_bag, which
/// explains what it cannot read.
bool looks_like_ros1_bag(std::span<const std::uint8_t> first_bytes);

}  // namespace cairn::bag
