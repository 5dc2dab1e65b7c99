#pragma once
/// \file
/// rosbag2's SQLite3 storage (`.db3`, rosbag2_storage_default_plugins/sqlite3): tables `topics`
/// (id, name, type, serialization_format, ...), `messages` (topic_id, timestamp in ns, data) and,
/// from ROS 2 Iron on, `message_definitions` (topic_type, encoding, encoded_message_definition).
/// Read through Debian's libsqlite3, opened read-only and immutable (nothing is written beside the
/// file). Messages stream in timestamp order (the `timestamp_idx` rosbag2 creates), ties by row id.

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "cairn/bag/container.hpp"

namespace cairn::bag {

/// Opens a rosbag2 SQLite3 file. Throws io::ParseError when it is not an SQLite database or lacks
/// rosbag2's tables.
std::unique_ptr<Container> open_sqlite_bag(const std::string& path);

/// True when `first_bytes` start with SQLite's magic "SQLite format 3\0".
bool looks_like_sqlite(std::span<const std::uint8_t> first_bytes);

}  // namespace cairn::bag
