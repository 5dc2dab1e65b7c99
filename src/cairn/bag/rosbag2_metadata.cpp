#include "cairn/bag/rosbag2_metadata.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "cairn/io/parse_error.hpp"

namespace cairn::bag {

Rosbag2Metadata read_rosbag2_metadata(const std::string& folder) {
  const std::string path = (std::filesystem::path(folder) / "metadata.yaml").string();
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw io::ParseError(path, 0, "cannot open: a rosbag2 folder holds a metadata.yaml");
  } catch (const YAML::Exception& e) {
    throw io::ParseError(path, static_cast<std::size_t>(e.mark.line + 1), "not valid YAML: " + e.msg);
  }
  const YAML::Node info = root["rosbag2_bagfile_information"];
  if (!info || !info.IsMap()) throw io::ParseError(path, 0, "expected a 'rosbag2_bagfile_information' map");
  Rosbag2Metadata metadata;
  try {
    metadata.version = info["version"] ? info["version"].as<int>() : 0;
    metadata.storage_identifier = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
    metadata.compression_format = info["compression_format"] ? info["compression_format"].as<std::string>() : "";
    metadata.compression_mode = info["compression_mode"] ? info["compression_mode"].as<std::string>() : "";
    const YAML::Node files = info["relative_file_paths"];
    if (!files || !files.IsSequence() || files.size() == 0) {
      throw io::ParseError(path, 0, "expected a non-empty 'relative_file_paths' list");
    }
    for (const YAML::Node& file : files) {
      metadata.files.push_back((std::filesystem::path(folder) / file.as<std::string>()).string());
    }
  } catch (const YAML::Exception& e) {
    throw io::ParseError(path, static_cast<std::size_t>(e.mark.line + 1), "unexpected value: " + e.msg);
  }
  if (!metadata.compression_format.empty()) {
    throw io::ParseError(path, 0, "the bag is compressed by rosbag2 (" + metadata.compression_format + ", mode " +
                                      metadata.compression_mode +
                                      "), which cairn does not read: decompress it first (`ros2 bag convert`, or "
                                      "`zstd -d` on each file for mode FILE)");
  }
  return metadata;
}

}  // namespace cairn::bag
