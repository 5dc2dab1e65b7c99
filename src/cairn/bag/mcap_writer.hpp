#pragma once
/// \file
/// Writes MCAP files (https://mcap.dev/spec, major version 0) that Foxglove Studio and
/// @mcap/core's indexed reader open: messages in compressed chunks, a Message Index record per
/// channel after each chunk, and a summary section (Schema, Channel, Statistics and Chunk Index
/// records, one Summary Offset record per group) before the Footer, with every CRC filled in.
///
/// Layout written:
///   Magic, Header, { Chunk [Schema, Channel, Message...], Message Index... }..., Data End,
///   Schema..., Channel..., Statistics, Chunk Index..., Summary Offset..., Footer, Magic
/// Schema and Channel records go into the chunk open when they are added (so that a reader
/// scanning the file meets them before their messages) and again into the summary.

#include <cstddef>
#include <cstdint>
#include <map>
#include <ostream>
#include <span>
#include <string>
#include <vector>

namespace cairn::bag {

/// McapWriter::Options (declared here so that it can be a default argument).
struct McapWriterOptions {
  /// Header profile: "ros1", "ros2", or "" for none ("Header", registry "Well-known profiles").
  std::string profile = "";
  /// Header library: the writer's name, free-form.
  std::string library = "cairn";
  /// Chunk compression: "zstd", "lz4" (LZ4 frame) or "" (none).
  std::string compression = "zstd";
  /// A chunk is closed once its uncompressed records reach this many bytes (>= 1).
  std::size_t chunk_bytes = 1 << 20;
};

class McapWriter {
 public:
  using Options = McapWriterOptions;

  /// Writes the magic and the Header. Throws std::invalid_argument for bad options (an unknown
  /// compression, chunk_bytes 0), naming every problem.
  explicit McapWriter(std::ostream& out, Options options = {});
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Registers a schema ("Schema": name such as "sensor_msgs/msg/LaserScan", encoding such as
  /// "ros2msg", data the definition text) and returns its id (1, 2, ...).
  std::uint16_t add_schema(std::string name, std::string encoding, std::string data);
  /// Registers a channel on `topic` whose messages use `schema_id` (0: no schema, else an id
  /// add_schema returned) and `message_encoding` ("cdr", "ros1", "json", ...); returns its id
  /// (1, 2, ...).
  std::uint16_t add_channel(std::string topic, std::uint16_t schema_id, std::string message_encoding,
                            std::map<std::string, std::string> metadata = {});
  /// Appends one message to the open chunk, closing the chunk once it holds chunk_bytes. Times
  /// are nanoseconds since the Unix epoch; messages need not come in time order.
  void write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             std::span<const std::uint8_t> data);
  /// Writes the last chunk, Data End, the summary section, the Footer and the closing magic.
  /// Must be called once every message is written (the destructor does not: a file never
  /// finished has no summary, and readers recover only its complete chunks by a scan). Throws
  /// std::runtime_error when the stream has failed.
  void finish();

 private:
  struct MessageIndexEntry {
    std::uint64_t log_time_ns = 0;
    std::uint64_t offset = 0;  // in the chunk's uncompressed records
  };
  struct ChunkIndexEntry {
    std::uint64_t message_start_ns = 0;
    std::uint64_t message_end_ns = 0;
    std::uint64_t chunk_start_offset = 0;
    std::uint64_t chunk_length = 0;
    std::map<std::uint16_t, std::uint64_t> message_index_offsets;
    std::uint64_t message_index_length = 0;
    std::uint64_t compressed_size = 0;
    std::uint64_t uncompressed_size = 0;
  };

  void emit(std::span<const std::uint8_t> bytes);
  void emit_record(std::uint8_t opcode, const std::vector<std::uint8_t>& content);
  void flush_chunk();
  std::vector<std::uint8_t> compress(const std::vector<std::uint8_t>& records) const;
  void write_message_indexes(ChunkIndexEntry& index);
  void write_summary();
  void write_summary_group(std::uint8_t opcode, const std::vector<std::vector<std::uint8_t>>& records,
                           std::vector<std::uint8_t>& offsets);

  std::ostream& out_;
  Options options_;
  std::uint64_t position_ = 0;  // bytes written so far
  std::uint32_t crc_ = 0;       // CRC32 of the bytes written since the last reset
  bool finished_ = false;

  std::vector<std::vector<std::uint8_t>> schema_records_;   // content of each Schema record
  std::vector<std::vector<std::uint8_t>> channel_records_;  // content of each Channel record

  // The open chunk.
  std::vector<std::uint8_t> chunk_records_;
  std::map<std::uint16_t, std::vector<MessageIndexEntry>> chunk_message_indexes_;
  std::uint64_t chunk_start_ns_ = 0;
  std::uint64_t chunk_end_ns_ = 0;

  // For the summary.
  std::vector<ChunkIndexEntry> chunk_indexes_;
  std::vector<std::uint64_t> channel_message_counts_;  // by channel id - 1
  std::uint64_t message_count_ = 0;
  std::uint64_t message_start_ns_ = 0;
  std::uint64_t message_end_ns_ = 0;
};

}  // namespace cairn::bag
