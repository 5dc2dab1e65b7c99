#include "cairn/bag/mcap_writer.hpp"

#include "cairn/bag/mcap_format.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>
#include <utility>

#include "cairn/core/assert.hpp"

// Section names in comments ("Chunk", "Footer", "Serialization") are those of the MCAP
// specification, https://mcap.dev/spec (foxglove/mcap website/docs/spec/index.md).

namespace cairn::bag {
namespace {

namespace op = mcap::op;
using mcap::crc32_of;
using mcap::kMagic;

// "Message": channel_id u16, sequence u32, log_time u64, publish_time u64, then the data.
constexpr std::uint64_t kMessageFixedBytes = 2 + 4 + 8 + 8;

// "Serialization": little-endian fixed-width integers, u32-length-prefixed strings.
void put_u8(std::vector<std::uint8_t>& out, std::uint8_t value) { out.push_back(value); }
void put_u16(std::vector<std::uint8_t>& out, std::uint16_t value) {
  for (int i = 0; i < 2; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}
void put_bytes(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> bytes) {
  out.insert(out.end(), bytes.begin(), bytes.end());
}
void put_string(std::vector<std::uint8_t>& out, const std::string& text) {
  CAIRN_ASSERT(text.size() <= std::numeric_limits<std::uint32_t>::max(), "MCAP strings hold at most 4 GiB");
  put_u32(out, static_cast<std::uint32_t>(text.size()));
  out.insert(out.end(), text.begin(), text.end());
}
/// "Map<K, V>": a u32 byte length, then the entries.
void put_map_bytes(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& entries) {
  CAIRN_ASSERT(entries.size() <= std::numeric_limits<std::uint32_t>::max(), "MCAP maps hold at most 4 GiB");
  put_u32(out, static_cast<std::uint32_t>(entries.size()));
  put_bytes(out, entries);
}
void put_record(std::vector<std::uint8_t>& out, std::uint8_t opcode, const std::vector<std::uint8_t>& content) {
  put_u8(out, opcode);
  put_u64(out, content.size());
  put_bytes(out, content);
}
void put_u16_u64_map(std::vector<std::uint8_t>& out, const std::map<std::uint16_t, std::uint64_t>& map) {
  std::vector<std::uint8_t> entries;
  for (const auto& [key, value] : map) {
    put_u16(entries, key);
    put_u64(entries, value);
  }
  put_map_bytes(out, entries);
}


void validate(const McapWriterOptions& options) {
  std::string problems;
  if (options.compression != "" && options.compression != "zstd" && options.compression != "lz4") {
    problems += "compression \"" + options.compression + "\" is not one of \"zstd\", \"lz4\", \"\"; ";
  }
  if (options.chunk_bytes == 0) problems += "chunk_bytes must be at least 1; ";
  if (!problems.empty()) throw std::invalid_argument("McapWriter options: " + problems.substr(0, problems.size() - 2));
}

}  // namespace

McapWriter::McapWriter(std::ostream& out, Options options) : out_(out), options_(std::move(options)) {
  validate(options_);
  emit(kMagic);
  std::vector<std::uint8_t> header;  // "Header": profile, library
  put_string(header, options_.profile);
  put_string(header, options_.library);
  emit_record(op::kHeader, header);
}

std::uint16_t McapWriter::add_schema(std::string name, std::string encoding, std::string data) {
  CAIRN_ASSERT(!finished_, "McapWriter::add_schema after finish()");
  CAIRN_ASSERT(schema_records_.size() < std::numeric_limits<std::uint16_t>::max(), "MCAP allows 65535 schemas");
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);  // "Schema": id 0 is invalid
  std::vector<std::uint8_t> content;
  put_u16(content, id);
  put_string(content, name);
  put_string(content, encoding);
  put_string(content, data);  // uint32 length-prefixed bytes
  put_record(chunk_records_, op::kSchema, content);
  schema_records_.push_back(std::move(content));
  return id;
}

std::uint16_t McapWriter::add_channel(std::string topic, std::uint16_t schema_id, std::string message_encoding,
                                      std::map<std::string, std::string> metadata) {
  CAIRN_ASSERT(!finished_, "McapWriter::add_channel after finish()");
  CAIRN_ASSERT(schema_id <= schema_records_.size(), "McapWriter::add_channel: schema_id is not one add_schema returned");
  CAIRN_ASSERT(channel_records_.size() < std::numeric_limits<std::uint16_t>::max(), "MCAP allows 65535 channels");
  const auto id = static_cast<std::uint16_t>(channel_records_.size() + 1);
  std::vector<std::uint8_t> content;  // "Channel": id, schema_id, topic, message_encoding, metadata
  put_u16(content, id);
  put_u16(content, schema_id);
  put_string(content, topic);
  put_string(content, message_encoding);
  std::vector<std::uint8_t> entries;
  for (const auto& [key, value] : metadata) {
    put_string(entries, key);
    put_string(entries, value);
  }
  put_map_bytes(content, entries);
  put_record(chunk_records_, op::kChannel, content);
  channel_records_.push_back(std::move(content));
  channel_message_counts_.push_back(0);
  return id;
}

void McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                       std::span<const std::uint8_t> data) {
  CAIRN_ASSERT(!finished_, "McapWriter::write after finish()");
  CAIRN_ASSERT(channel_id >= 1 && channel_id <= channel_records_.size(),
               "McapWriter::write: channel_id is not one add_channel returned");
  std::uint64_t& channel_count = channel_message_counts_[channel_id - 1];
  const bool first_in_chunk = chunk_message_indexes_.empty();  // an entry exists only once a message does
  chunk_message_indexes_[channel_id].push_back({log_time_ns, chunk_records_.size()});  // "Message Index": offset in the uncompressed records
  put_u8(chunk_records_, op::kMessage);
  put_u64(chunk_records_, kMessageFixedBytes + data.size());
  put_u16(chunk_records_, channel_id);
  put_u32(chunk_records_, static_cast<std::uint32_t>(channel_count));  // sequence: recorded by the recorder
  put_u64(chunk_records_, log_time_ns);
  put_u64(chunk_records_, publish_time_ns);
  put_bytes(chunk_records_, data);
  chunk_start_ns_ = first_in_chunk ? log_time_ns : std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = first_in_chunk ? log_time_ns : std::max(chunk_end_ns_, log_time_ns);
  message_start_ns_ = message_count_ == 0 ? log_time_ns : std::min(message_start_ns_, log_time_ns);
  message_end_ns_ = message_count_ == 0 ? log_time_ns : std::max(message_end_ns_, log_time_ns);
  ++channel_count;
  ++message_count_;
  if (chunk_records_.size() >= options_.chunk_bytes) flush_chunk();
}

void McapWriter::finish() {
  if (finished_) return;
  flush_chunk();
  std::vector<std::uint8_t> data_end;  // "Data End": CRC32 of every byte before this record
  put_u32(data_end, crc_);
  emit_record(op::kDataEnd, data_end);
  write_summary();
  emit(kMagic);
  finished_ = true;
  out_.flush();
  if (!out_) throw std::runtime_error("McapWriter: writing the MCAP stream failed");
}

void McapWriter::emit(std::span<const std::uint8_t> bytes) {
  out_.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  position_ += bytes.size();
  crc_ = crc32_of(bytes, crc_);
}

void McapWriter::emit_record(std::uint8_t opcode, const std::vector<std::uint8_t>& content) {
  std::vector<std::uint8_t> prefix;
  put_u8(prefix, opcode);
  put_u64(prefix, content.size());
  emit(prefix);
  emit(content);
}

std::vector<std::uint8_t> McapWriter::compress(const std::vector<std::uint8_t>& records) const {
  std::vector<std::uint8_t> out;
  if (options_.compression == "zstd") {
    out.resize(ZSTD_compressBound(records.size()));
    const std::size_t size = ZSTD_compress(out.data(), out.size(), records.data(), records.size(), ZSTD_CLEVEL_DEFAULT);
    if (ZSTD_isError(size)) throw std::runtime_error(std::string("McapWriter: zstd: ") + ZSTD_getErrorName(size));
    out.resize(size);
  } else {  // "lz4": the LZ4 frame format, declaring its content size
    LZ4F_preferences_t preferences{};
    preferences.frameInfo.contentSize = records.size();
    out.resize(LZ4F_compressFrameBound(records.size(), &preferences));
    const std::size_t size = LZ4F_compressFrame(out.data(), out.size(), records.data(), records.size(), &preferences);
    if (LZ4F_isError(size)) throw std::runtime_error(std::string("McapWriter: lz4: ") + LZ4F_getErrorName(size));
    out.resize(size);
  }
  return out;
}

// "Chunk", then its "Message Index" records; remembers its "Chunk Index" for the summary.
void McapWriter::flush_chunk() {
  if (chunk_records_.empty()) return;
  ChunkIndexEntry index;
  const bool has_messages = !chunk_message_indexes_.empty();
  index.message_start_ns = has_messages ? chunk_start_ns_ : 0;  // "Zero if the chunk has no messages"
  index.message_end_ns = has_messages ? chunk_end_ns_ : 0;
  index.uncompressed_size = chunk_records_.size();
  std::vector<std::uint8_t> content;
  put_u64(content, index.message_start_ns);
  put_u64(content, index.message_end_ns);
  put_u64(content, index.uncompressed_size);
  put_u32(content, crc32_of(chunk_records_));  // uncompressed_crc
  put_string(content, options_.compression);
  if (options_.compression.empty()) {
    index.compressed_size = chunk_records_.size();
    put_u64(content, index.compressed_size);
    put_bytes(content, chunk_records_);
  } else {
    const std::vector<std::uint8_t> compressed = compress(chunk_records_);
    index.compressed_size = compressed.size();
    put_u64(content, index.compressed_size);
    put_bytes(content, compressed);
  }
  index.chunk_start_offset = position_;
  emit_record(op::kChunk, content);
  index.chunk_length = position_ - index.chunk_start_offset;
  write_message_indexes(index);
  chunk_indexes_.push_back(std::move(index));
  chunk_records_.clear();
  chunk_message_indexes_.clear();
}

// "Message Index": one per channel with messages in the chunk, right after it.
void McapWriter::write_message_indexes(ChunkIndexEntry& index) {
  const std::uint64_t start = position_;
  for (const auto& [channel_id, entries] : chunk_message_indexes_) {
    std::vector<std::uint8_t> content;
    put_u16(content, channel_id);
    std::vector<std::uint8_t> array;  // Array<Tuple<Timestamp, uint64>>
    for (const MessageIndexEntry& entry : entries) {
      put_u64(array, entry.log_time_ns);
      put_u64(array, entry.offset);
    }
    put_map_bytes(content, array);
    index.message_index_offsets[channel_id] = position_;
    emit_record(op::kMessageIndex, content);
  }
  index.message_index_length = position_ - start;
}

void McapWriter::write_summary_group(std::uint8_t opcode, const std::vector<std::vector<std::uint8_t>>& records,
                                     std::vector<std::uint8_t>& offsets) {
  if (records.empty()) return;
  const std::uint64_t start = position_;
  for (const auto& content : records) emit_record(opcode, content);
  std::vector<std::uint8_t> offset;  // "Summary Offset": group_opcode, group_start, group_length
  put_u8(offset, opcode);
  put_u64(offset, start);
  put_u64(offset, position_ - start);
  put_record(offsets, op::kSummaryOffset, offset);
}

// "Summary Section" (records grouped by opcode), "Summary Offset Section", "Footer".
void McapWriter::write_summary() {
  std::vector<std::uint8_t> statistics;  // "Statistics"
  put_u64(statistics, message_count_);
  put_u16(statistics, static_cast<std::uint16_t>(schema_records_.size()));
  put_u32(statistics, static_cast<std::uint32_t>(channel_records_.size()));
  put_u32(statistics, 0);  // attachment_count
  put_u32(statistics, 0);  // metadata_count
  put_u32(statistics, static_cast<std::uint32_t>(chunk_indexes_.size()));
  put_u64(statistics, message_start_ns_);
  put_u64(statistics, message_end_ns_);
  std::map<std::uint16_t, std::uint64_t> counts;
  for (std::size_t i = 0; i < channel_message_counts_.size(); ++i) counts[static_cast<std::uint16_t>(i + 1)] = channel_message_counts_[i];
  put_u16_u64_map(statistics, counts);

  std::vector<std::vector<std::uint8_t>> chunk_indexes;  // "Chunk Index"
  for (const ChunkIndexEntry& index : chunk_indexes_) {
    std::vector<std::uint8_t>& content = chunk_indexes.emplace_back();
    put_u64(content, index.message_start_ns);
    put_u64(content, index.message_end_ns);
    put_u64(content, index.chunk_start_offset);
    put_u64(content, index.chunk_length);
    put_u16_u64_map(content, index.message_index_offsets);
    put_u64(content, index.message_index_length);
    put_string(content, options_.compression);
    put_u64(content, index.compressed_size);
    put_u64(content, index.uncompressed_size);
  }

  const std::uint64_t summary_start = position_;
  crc_ = 0;  // "Footer": summary_crc covers the summary section through summary_offset_start
  std::vector<std::uint8_t> offsets;
  write_summary_group(op::kSchema, schema_records_, offsets);
  write_summary_group(op::kChannel, channel_records_, offsets);
  write_summary_group(op::kStatistics, {statistics}, offsets);
  write_summary_group(op::kChunkIndex, chunk_indexes, offsets);
  const std::uint64_t summary_offset_start = position_;
  emit(offsets);
  std::vector<std::uint8_t> footer;
  put_u8(footer, op::kFooter);
  put_u64(footer, 8 + 8 + 4);
  put_u64(footer, summary_start);
  put_u64(footer, summary_offset_start);
  emit(footer);
  std::vector<std::uint8_t> summary_crc;
  put_u32(summary_crc, crc_);
  emit(summary_crc);
}

}  // namespace cairn::bag
