#pragma once
/// \file
/// Reads the scans of a ScanSequence in order: point-cloud files (io/point_cloud.hpp) with the
/// sequence's times, or a bag's PointCloud2 topic streamed one message at a time with each
/// message's header stamp as its time (seconds = stamp_ns / 1e9, correctly rounded, as a times
/// table written to nanoseconds would read).

#include <cstddef>
#include <memory>

#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"

namespace cairn::bag {
class PointCloudStream;
}

namespace cairn::lidar3d {

class ScanReader {
 public:
  explicit ScanReader(ScanSequence& sequence);
  ~ScanReader();
  ScanReader(const ScanReader&) = delete;
  ScanReader& operator=(const ScanReader&) = delete;

  /// Scan `k` of the sequence; from a bag, `k` must follow the previous call's. Sets
  /// sequence.times_s[k] for a bag. Throws io::ParseError for a scan that cannot be read.
  io::PointCloud read(std::size_t k);

 private:
  ScanSequence& sequence_;
  std::unique_ptr<bag::PointCloudStream> stream_;
  std::size_t next_ = 0;
};

}  // namespace cairn::lidar3d
