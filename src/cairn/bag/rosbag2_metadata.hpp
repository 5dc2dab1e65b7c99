#pragma once
/// \file
/// A rosbag2 folder's metadata.yaml (rosbag2_storage/src/rosbag2_storage/yaml.hpp, versions 1-9):
/// the storage plugin and the storage files, in order. Only what reading needs; counts and times
/// come from the storage files themselves.

#include <string>
#include <vector>

namespace cairn::bag {

struct Rosbag2Metadata {
  int version = 0;
  std::string storage_identifier;  ///< "sqlite3" or "mcap"
  /// Absolute or folder-relative paths of the storage files, in metadata order.
  std::vector<std::string> files;
  std::string compression_format;  ///< "" or "zstd"
  std::string compression_mode;    ///< "", "FILE" or "MESSAGE"
};

/// Reads `folder`/metadata.yaml. Throws io::ParseError naming the file and what is missing.
/// A bag compressed by rosbag2 (per file or per message) is refused, naming the compression and
/// `ros2 bag convert` / `zstd -d` as the way to decompress it.
Rosbag2Metadata read_rosbag2_metadata(const std::string& folder);

}  // namespace cairn::bag
