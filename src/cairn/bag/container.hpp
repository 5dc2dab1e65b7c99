#pragma once
/// \file
/// One view of every bag container cairn reads: ROS 1 bags (format 2.0), MCAP files and rosbag2
/// SQLite3 databases. A container lists its connections (one topic with one type and one
/// serialisation) and streams its messages in time order, one chunk in memory at a time, so a
/// multi-GB bag is read in memory bounded by its largest chunk, not by its size.
///
/// The serialised bytes are not decoded here: bag/message_schema.hpp parses the definitions the
/// container carries and bag/deserialize.hpp walks the bytes (ROS 1 or CDR).
///
/// Errors: a damaged container throws io::ParseError(file, 0, "byte N: <what was expected>, found
/// <what was found>"); repairs a reader makes on purpose (a malformed old index, a missing index
/// rebuilt by a scan, a record of an unknown kind skipped) are counted in ContainerSummary::notes.

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cairn::bag {

/// One topic of one file as the container declares it (a ROS 1 connection record, an MCAP
/// channel with its schema, a rosbag2 topics row with its message definition).
struct Connection {
  /// The container's own id (ROS 1 conn, MCAP channel id, rosbag2 topic id).
  std::uint32_t id = 0;
  std::string topic;
  /// As the container spells it: "sensor_msgs/LaserScan" (ROS 1), "sensor_msgs/msg/LaserScan" (ROS 2).
  std::string type;
  /// How the payload is serialised: "ros1" or "cdr" (others are listed, never decoded).
  std::string encoding;
  /// The message definition text the container carries (ROS 1 message_definition, MCAP schema
  /// data, rosbag2 message_definitions row); empty when it carries none.
  std::string definition;
  /// The definition's dialect: "ros1msg", "ros2msg", "ros2idl", or "" when there is none.
  std::string definition_encoding;
  /// ROS 1 md5sum of the type ("" elsewhere).
  std::string md5sum;
};

/// One serialised message. `data` points into the reader's current chunk: it stays valid until
/// the next call of MessageStream::next().
struct Message {
  /// Index into Container::connections() (not the container's own id).
  std::size_t connection = 0;
  /// Receive (log) time, nanoseconds since the Unix epoch.
  std::int64_t log_time_ns = 0;
  std::span<const std::uint8_t> data;
  /// When set, owns the bytes `data` points into (a decompressed chunk): holding a copy keeps
  /// them valid after next(), so a decoded image or cloud can refer to them without a copy.
  std::shared_ptr<const void> owner;
  /// Where the record starts in its file (for error messages), or, inside a compressed chunk, the
  /// offset of that chunk.
  std::uint64_t file_offset = 0;
};

/// Pulls messages, in log-time order (ties in file order), of the connections it was opened for.
class MessageStream {
 public:
  virtual ~MessageStream() = default;
  /// Fills `message` and returns true, or returns false at the end. Throws io::ParseError.
  virtual bool next(Message* message) = 0;
};

/// Per-connection counts, from the index or summary when the file has one, else from a scan.
struct ConnectionStatistics {
  std::uint64_t messages = 0;
  std::int64_t first_ns = 0;  ///< log time of the first message (0 when there is none)
  std::int64_t last_ns = 0;   ///< log time of the last message
};

struct ContainerSummary {
  /// "ROS 1 bag 2.0", "MCAP", "rosbag2 SQLite3".
  std::string format;
  /// For MCAP: the header's profile ("ros1", "ros2", ...); "" otherwise.
  std::string profile;
  std::uint64_t file_bytes = 0;
  /// Parallel to Container::connections().
  std::vector<ConnectionStatistics> connections;
  /// Number of chunks by compression: "none", "bz2", "lz4", "zstd" (empty map: no chunks).
  std::map<std::string, std::uint64_t> chunks;
  /// True when the counts above came from the file's index or summary section, false when the
  /// reader had to scan the records (a bag cut off before its index was written).
  bool indexed = false;
  /// Repairs and skips, one sentence each ("IndexData data_len disagrees with count in 3 records
  /// (old rosbag bug): count trusted").
  std::vector<std::string> notes;
};

/// An open container file. Not thread-safe; streams opened from it read the file independently.
class Container {
 public:
  virtual ~Container() = default;
  virtual const std::string& path() const = 0;
  virtual const std::vector<Connection>& connections() const = 0;
  virtual const ContainerSummary& summary() const = 0;
  /// Messages of the connections whose index (into connections()) has `wanted[i]` true; an empty
  /// `wanted` means all. In log-time order.
  virtual std::unique_ptr<MessageStream> messages(const std::vector<bool>& wanted = {}) = 0;
};

}  // namespace cairn::bag
