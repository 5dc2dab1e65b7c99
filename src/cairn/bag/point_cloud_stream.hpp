#pragma once
/// \file
/// The sensor_msgs/PointCloud2 messages of one bag topic, one scan at a time in log-time order,
/// for `cairn slam3d BAG`: each decoded into io::PointCloud (bag/point_cloud2.hpp) with its header
/// stamp as the scan time. Only the current message is held in memory.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/point_cloud2.hpp"
#include "cairn/io/point_cloud.hpp"

namespace cairn::bag {

class PointCloudStream {
 public:
  /// Opens `path` and the PointCloud2 topic `topic` ("" = the only one). Throws io::ParseError.
  PointCloudStream(const std::string& path, const std::string& topic);
  PointCloudStream(const PointCloudStream&) = delete;  // the decoder refers to bag_
  PointCloudStream& operator=(const PointCloudStream&) = delete;

  /// Messages on the topic (from the bag's index or summary).
  std::size_t size() const { return static_cast<std::size_t>(bag_.topics()[topic_].messages); }
  const std::string& topic() const { return bag_.topics()[topic_].name; }
  const Bag& bag() const { return bag_; }

  /// The next scan and its header stamp, or false at the end. A message that does not decode as a
  /// point cloud throws io::ParseError naming the bag, topic and message time.
  bool next(io::PointCloud* cloud, std::int64_t* stamp_ns, PointCloud2Report* report = nullptr);

 private:
  Bag bag_;
  std::size_t topic_ = 0;
  MessageDecoder decoder_;
  std::unique_ptr<BagStream> stream_;
};

}  // namespace cairn::bag
