// Read throughput of cairn's bag readers: opens a bag (ROS 1, MCAP, rosbag2), streams every
// message in time order and, with --decode, decodes each into a Value tree (the layouts the bag
// carries); with --points, PointCloud2 messages further into io::PointCloud (what `cairn slam3d
// BAG` does per scan). Prints one JSON line: messages, payload bytes, seconds, MB/s.
// Run by bench/bag_read_vs_rosbag.py beside python3-rosbag on the same files (docs/benchmarks.md).

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/message_schema.hpp"
#include "cairn/bag/point_cloud2.hpp"
#include "cairn/io/parse_error.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_bag_read BAG [--decode] [--points]\n");
    return 2;
  }
  bool decode = false, points = false;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--decode") == 0) decode = true;
    if (std::strcmp(argv[i], "--points") == 0) decode = points = true;
  }
  try {
    const auto start = std::chrono::steady_clock::now();
    cairn::bag::Bag bag = cairn::bag::Bag::open(argv[1]);
    cairn::bag::MessageDecoder decoder(bag);
    std::vector<bool> is_cloud(bag.topics().size());
    for (std::size_t t = 0; t < is_cloud.size(); ++t) is_cloud[t] = decoder.type(t) == "sensor_msgs/PointCloud2";
    const auto stream = bag.read();
    cairn::bag::BagMessage message;
    std::size_t messages = 0, bytes = 0, cloud_points = 0;
    while (stream->next(&message)) {
      ++messages;
      bytes += message.message.data.size();
      if (!decode) continue;
      const cairn::bag::Value value = decoder.decode(message);
      if (points && is_cloud[message.topic]) cloud_points += cairn::bag::to_point_cloud(value).size();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("{\"messages\": %zu, \"payload_bytes\": %zu, \"points\": %zu, \"seconds\": %.4f, \"mb_per_s\": %.1f}\n",
                messages, bytes, cloud_points, seconds, static_cast<double>(bytes) / 1e6 / seconds);
  } catch (const cairn::io::ParseError& e) {
    std::fprintf(stderr, "bench_bag_read: %s\n", e.what());
    return 1;
  }
  return 0;
}
