#pragma once
/// \file
/// The body the container fuzz targets share (fuzz_ros1_bag, fuzz_mcap, fuzz_rosbag2_sqlite): the
/// input written to a file with the container's extension and opened with bag::Bag::open; every
/// topic listed, every message streamed and decoded with the layouts the file carries
/// (bag::MessageDecoder), and the types cairn knows through their typed decoders. Any input must end
/// in an io::ParseError (the container, a message's bytes) or, from a typed decoder, a
/// std::runtime_error; another exception, a crash, a hang or a sanitizer report is a bug. A stream
/// that ends normally must have handed out its messages in log-time order, as many per topic as the
/// file said; decoded values kept while the stream goes on must not change (their byte arrays may
/// refer to a chunk: Message::owner).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/point_cloud2.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag::fuzz {


inline void require(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "bag fuzz target: %s\n", what);
    std::abort();
  }
}

/// The typed decoder of a type cairn knows (normalised name); others stay Value trees.
inline void decode_typed(const std::string& type, const Value& value) {
  if (type == "sensor_msgs/LaserScan") (void)to_laser_scan(value);
  else if (type == "sensor_msgs/Imu") (void)to_imu(value);
  else if (type == "sensor_msgs/NavSatFix") (void)to_nav_sat_fix(value);
  else if (type == "sensor_msgs/Image") (void)to_image(value);
  else if (type == "sensor_msgs/CompressedImage") (void)to_compressed_image(value);
  else if (type == "sensor_msgs/CameraInfo") (void)to_camera_info(value);
  else if (type == "sensor_msgs/PointCloud2") (void)to_point_cloud(value);
  else if (type == "nav_msgs/Odometry") (void)to_odometry(value);
  else if (type == "geometry_msgs/PoseStamped") (void)to_pose_stamped(value);
  else if (type == "geometry_msgs/TransformStamped") (void)to_transform_stamped(value);
  else if (type == "tf2_msgs/TFMessage" || type == "tf/tfMessage") (void)to_tf_message(value);
}

/// A hash of every byte and number of a decoded value.
inline std::uint64_t checksum(const Value& value) {
  std::uint64_t sum = static_cast<std::uint64_t>(value.kind());
  switch (value.kind()) {
    case Value::Kind::kString:
    case Value::Kind::kBytes:
      for (const char c : value.text()) sum = sum * 31 + static_cast<unsigned char>(c);
      break;
    case Value::Kind::kArray:
    case Value::Kind::kMessage:
      for (const Value& item : value.items()) sum = sum * 31 + checksum(item);
      break;
    case Value::Kind::kInt: sum = sum * 31 + static_cast<std::uint64_t>(value.as_int()); break;
    case Value::Kind::kBool:
    case Value::Kind::kUInt: sum = sum * 31 + value.as_uint(); break;
    case Value::Kind::kFloat: break;  // NaN payloads need not survive a copy
  }
  return sum;
}

/// Decoded values kept while the stream goes on: byte arrays that refer to a chunk
/// (Message::owner) must stay valid and unchanged after next() and after the stream ends.
class KeptValues {
 public:
  void add(Value value) {
    if (kept_.size() >= 64) return;
    const std::uint64_t sum = checksum(value);
    kept_.emplace_back(std::move(value), sum);
  }
  void check() const {
    for (const auto& [value, sum] : kept_) require(checksum(value) == sum, "a decoded value changed after next()");
  }

 private:
  std::vector<std::pair<Value, std::uint64_t>> kept_;
};

inline void decode_message(MessageDecoder& decoder, const std::string& type, const BagMessage& message, KeptValues& kept) {
  try {
    Value value = decoder.decode(message);
    decode_typed(type, value);
    kept.add(std::move(value));
  } catch (const io::ParseError&) {
    // A message whose bytes do not match its layout.
  } catch (const std::runtime_error&) {
    // A typed decoder missing a field its type must have.
  }
}

inline void stream_all(Bag& bag, MessageDecoder& decoder, const std::vector<std::string>& types, KeptValues& kept) {
  const std::size_t topic_count = bag.topics().size();
  const auto stream = bag.read();
  std::vector<std::uint64_t> seen(topic_count, 0);
  std::int64_t last_ns = std::numeric_limits<std::int64_t>::min();
  BagMessage message;
  while (stream->next(&message)) {
    require(message.topic < topic_count, "a message of a topic the bag does not list");
    require(message.message.log_time_ns >= last_ns, "messages out of log-time order");
    last_ns = message.message.log_time_ns;
    ++seen[message.topic];
    decode_message(decoder, types[message.topic], message, kept);
  }
  for (std::size_t t = 0; t < topic_count; ++t) {
    require(seen[t] == bag.topics()[t].messages, "a topic streamed another count than the bag lists");
  }
}

inline void read_bag(const std::string& path) {
  Bag bag = Bag::open(path);
  MessageDecoder decoder(bag);
  std::vector<std::string> types;
  for (std::size_t t = 0; t < bag.topics().size(); ++t) {
    std::string why;
    (void)decoder.can_decode(t, &why);
    types.push_back(decoder.type(t));
  }
  KeptValues kept;
  try {
    stream_all(bag, decoder, types, kept);
  } catch (const io::ParseError&) {
    kept.check();
    throw;
  }
  kept.check();
}

/// Writes the input to a per-process file `<name>_<pid><extension>` and reads it as a bag.
inline int fuzz_bag_input(const std::uint8_t* data, std::size_t size, const std::string& name, const std::string& extension) {
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("cairn_" + name + "_" + std::to_string(::getpid()) + extension)).string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    read_bag(path);
  } catch (const io::ParseError&) {
    // Expected for a damaged file.
  }
  return 0;
}

}  // namespace cairn::bag::fuzz
