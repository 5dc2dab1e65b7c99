#include "cairn/bag/point_cloud_stream.hpp"

#include <stdexcept>

#include "cairn/bag/topic_choice.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {

PointCloudStream::PointCloudStream(const std::string& path, const std::string& topic)
    : bag_(Bag::open(path)),
      topic_(choose_topic(bag_, topic, {{"sensor_msgs/PointCloud2"}, "point cloud", "--cloud-topic"})),
      decoder_(bag_) {
  std::string why;
  if (!decoder_.can_decode(topic_, &why)) {
    throw io::ParseError(path, 0, "topic " + bag_.topics()[topic_].name + " cannot be decoded: " + why);
  }
  stream_ = bag_.read({topic_});
}

bool PointCloudStream::next(io::PointCloud* cloud, std::int64_t* stamp_ns, PointCloud2Report* report) {
  BagMessage message;
  if (!stream_->next(&message)) return false;
  PointCloud2Report local;
  PointCloud2Report& r = report != nullptr ? *report : local;
  try {
    *cloud = to_point_cloud(decoder_.decode(message), &r);
  } catch (const io::ParseError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw io::ParseError(bag_.path(), 0, topic() + " message at " + std::to_string(message.message.log_time_ns) +
                                             " ns: " + e.what());
  }
  *stamp_ns = r.header.stamp_ns;
  return true;
}

}  // namespace cairn::bag
