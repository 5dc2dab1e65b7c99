#include "cairn/lidar3d/scan_reader.hpp"

#include <stdexcept>

#include "cairn/bag/point_cloud_stream.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::lidar3d {

ScanReader::ScanReader(ScanSequence& sequence) : sequence_(sequence) {
  if (!sequence_.bag.empty()) {
    stream_ = std::make_unique<bag::PointCloudStream>(sequence_.bag, sequence_.bag_topic);
    sequence_.times_s.assign(sequence_.files.size(), 0.0);
  }
}

ScanReader::~ScanReader() = default;

io::PointCloud ScanReader::read(std::size_t k) {
  if (!stream_) return io::read_point_cloud(sequence_.files.at(k));
  if (k != next_) throw std::logic_error("ScanReader: bag scans are read in order");
  io::PointCloud cloud;
  std::int64_t stamp_ns = 0;
  if (!stream_->next(&cloud, &stamp_ns)) {
    throw io::ParseError(sequence_.bag, 0, "topic " + sequence_.bag_topic + " ended after " + std::to_string(k) + " scans");
  }
  ++next_;
  sequence_.times_s.at(k) = static_cast<double>(stamp_ns) / 1e9;
  return cloud;
}

}  // namespace cairn::lidar3d
