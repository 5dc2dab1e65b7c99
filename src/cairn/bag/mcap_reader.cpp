#include "cairn/bag/mcap_reader.hpp"

#include "cairn/bag/mcap_format.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <queue>
#include <system_error>
#include <utility>
#include <vector>

#include "cairn/bag/byte_cursor.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/io/parse_error.hpp"

// Section names in comments ("Chunk", "Footer", "Serialization") are those of the MCAP
// specification, https://mcap.dev/spec (foxglove/mcap website/docs/spec/index.md).

namespace cairn::bag {
namespace {

namespace op = mcap::op;
using mcap::crc32_of;
using mcap::kMagic;

constexpr std::uint64_t kMagicBytes = kMagic.size();
// "Records": <opcode u8><content length u64><content>.
constexpr std::uint64_t kRecordPrefixBytes = 9;
// "Footer": summary_start u64, summary_offset_start u64, summary_crc u32 (never extended).
constexpr std::uint64_t kFooterContentBytes = 20;
constexpr std::uint64_t kFooterRecordBytes = kRecordPrefixBytes + kFooterContentBytes;
// A compressed chunk is decompressed whole; refuse to allocate more than this for one.
constexpr std::uint64_t kMaxDecompressedChunkBytes = std::uint64_t{1} << 30;
// The most an output byte count can exceed its input: zstd blocks hold at most 128 KiB behind a
// 3-byte header; an LZ4 sequence adds at most 255 bytes of match per input byte.
constexpr std::uint64_t kZstdMaxRatio = 1 << 16;
constexpr std::uint64_t kLz4MaxRatio = 256;
// Messages written outside chunks are grouped into runs of about this many bytes, each merged
// like a chunk (so an unchunked file is not held in memory whole).
constexpr std::uint64_t kLooseRunBytes = std::uint64_t{4} << 20;

const char* record_name(std::uint8_t opcode) {
  switch (opcode) {
    case op::kHeader: return "Header record";
    case op::kFooter: return "Footer record";
    case op::kSchema: return "Schema record";
    case op::kChannel: return "Channel record";
    case op::kMessage: return "Message record";
    case op::kChunk: return "Chunk record";
    case op::kMessageIndex: return "Message Index record";
    case op::kChunkIndex: return "Chunk Index record";
    case op::kAttachment: return "Attachment record";
    case op::kAttachmentIndex: return "Attachment Index record";
    case op::kStatistics: return "Statistics record";
    case op::kMetadata: return "Metadata record";
    case op::kMetadataIndex: return "Metadata Index record";
    case op::kSummaryOffset: return "Summary Offset record";
    case op::kDataEnd: return "Data End record";
    default: return "record of unknown opcode";
  }
}

std::string hex(std::uint64_t value, int digits) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text = "0x";
  for (int i = digits - 1; i >= 0; --i) text.push_back(kDigits[(value >> (4 * i)) & 0xFu]);
  return text;
}

std::string at_byte(std::uint64_t offset) { return "byte " + std::to_string(offset); }

std::string count_of(std::uint64_t n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

std::string attachments_and_metadata(std::uint64_t attachments, std::uint64_t metadata) {
  return "the file holds " + count_of(attachments, "Attachment record") + " and " + count_of(metadata, "Metadata record") +
         " (not exposed by cairn)";
}


// ---------------------------------------------------------------------------------------------
// The file: random-access reads that are checked against its size before anything is allocated.

class McapFile {
 public:
  explicit McapFile(std::string path);
  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }
  bool fits(std::uint64_t offset, std::uint64_t n) const { return offset <= size_ && n <= size_ - offset; }
  /// Bytes [offset, offset + n). Throws when they are not all in the file.
  std::vector<std::uint8_t> read(std::uint64_t offset, std::uint64_t n, const char* what);
  [[noreturn]] void fail(std::uint64_t offset, const std::string& detail) const {
    throw io::ParseError(path_, 0, at_byte(offset) + ": " + detail);
  }

 private:
  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
};

McapFile::McapFile(std::string path) : path_(std::move(path)) {
  std::error_code error;
  const auto status = std::filesystem::status(path_, error);
  if (!std::filesystem::exists(status)) throw io::ParseError(path_, 0, "cannot open: no such file");
  if (!std::filesystem::is_regular_file(status)) throw io::ParseError(path_, 0, "cannot open: not a regular file");
  size_ = std::filesystem::file_size(path_, error);
  if (error) throw io::ParseError(path_, 0, "cannot open: " + error.message());
  in_.open(path_, std::ios::binary);
  if (!in_) throw io::ParseError(path_, 0, "cannot open for reading");
}

std::vector<std::uint8_t> McapFile::read(std::uint64_t offset, std::uint64_t n, const char* what) {
  if (!fits(offset, n)) {
    fail(offset, std::string(what) + " needs " + std::to_string(n) + " bytes, but the file ends at byte " +
                     std::to_string(size_));
  }
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(n));
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(offset));
  in_.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(n));
  if (static_cast<std::uint64_t>(in_.gcount()) != n) fail(offset, "read failed (was the file changed?)");
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// Records and their fields ("Serialization"). Each parser reads one record's content; fields a
// newer writer appends at the end are ignored ("Records may be extended by adding new fields").

/// One record inside a buffer: `offset` is where its opcode is (absolute in the file, or relative
/// to the decompressed records of a chunk), `content` its content bytes.
struct RecordView {
  std::uint8_t opcode = 0;
  std::uint64_t offset = 0;
  std::span<const std::uint8_t> content;
  std::uint64_t content_offset() const { return offset + kRecordPrefixBytes; }
  ByteCursor cursor(std::string_view file) const { return ByteCursor(content, file, content_offset()); }
};

/// Calls `visit(RecordView)` for each record of `cursor`, to its end.
template <typename Visit>
void for_each_record(ByteCursor& cursor, Visit&& visit) {
  while (!cursor.at_end()) {
    RecordView record;
    record.offset = cursor.offset();
    record.opcode = cursor.u8("record opcode");
    if (record.opcode == 0) cursor.fail_at(record.offset, "expected a record opcode, found 0x00 (invalid in MCAP)");
    const std::uint64_t length = cursor.u64("record content length");
    record.content = cursor.bytes(length, record_name(record.opcode));
    visit(record);
  }
}

std::string read_string(ByteCursor& cursor, const char* what) {
  const std::uint32_t length = cursor.u32(what);
  return std::string(cursor.string(length, what));
}

/// A cursor over the next `n` bytes of `cursor` (a Map, an Array, a length-prefixed field).
ByteCursor sub_cursor(ByteCursor& cursor, std::uint64_t n, std::string_view file, const char* what) {
  const std::uint64_t at = cursor.offset();
  return ByteCursor(cursor.bytes(n, what), file, at);
}

/// A "Timestamp" (u64 nanoseconds) as cairn's int64 nanoseconds.
std::int64_t read_time(ByteCursor& cursor, const char* what) {
  const std::uint64_t at = cursor.offset();
  const std::uint64_t time = cursor.u64(what);
  if (time > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
    cursor.fail_at(at, std::string("expected a ") + what + " below 2^63 ns, found " + std::to_string(time));
  }
  return static_cast<std::int64_t>(time);
}

/// "Map<string, string>": validated and dropped (channel and metadata maps are not exposed).
void skip_string_map(ByteCursor& cursor, std::string_view file, const char* what) {
  ByteCursor entries = sub_cursor(cursor, cursor.u32(what), file, what);
  while (!entries.at_end()) {
    entries.skip(entries.u32("map key length"), "map key");
    entries.skip(entries.u32("map value length"), "map value");
  }
}

/// "Map<uint16, uint64>".
std::map<std::uint16_t, std::uint64_t> read_u16_u64_map(ByteCursor& cursor, std::string_view file, const char* what) {
  ByteCursor entries = sub_cursor(cursor, cursor.u32(what), file, what);
  std::map<std::uint16_t, std::uint64_t> map;
  while (!entries.at_end()) {
    const std::uint16_t key = entries.u16("map key");
    map[key] = entries.u64("map value");
  }
  return map;
}

struct HeaderRecord {
  std::string profile;
  std::string library;
};

struct SchemaRecord {
  std::uint16_t id = 0;
  std::string name;
  std::string encoding;
  std::string data;
  std::uint64_t offset = 0;
};

struct ChannelRecord {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;
  std::uint64_t offset = 0;
};

struct MessageRecord {
  std::uint16_t channel_id = 0;
  std::int64_t log_time_ns = 0;
  std::span<const std::uint8_t> data;
};

struct ChunkRecord {
  std::int64_t message_start_ns = 0;
  std::int64_t message_end_ns = 0;
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;
  std::string compression;
  std::span<const std::uint8_t> records;
  std::uint64_t records_offset = 0;
};

struct ChunkIndexRecord {
  std::int64_t message_start_ns = 0;
  std::int64_t message_end_ns = 0;
  std::uint64_t chunk_start_offset = 0;
  std::uint64_t chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0;
  std::uint64_t uncompressed_size = 0;
  std::uint64_t offset = 0;  // of this Chunk Index record
};

struct StatisticsRecord {
  std::uint64_t message_count = 0;
  std::uint32_t attachment_count = 0;
  std::uint32_t metadata_count = 0;
  std::uint32_t chunk_count = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
  std::uint64_t offset = 0;
};

struct FooterRecord {
  std::uint64_t summary_start = 0;
  std::uint64_t summary_offset_start = 0;
  std::uint32_t summary_crc = 0;
};

// "Header (op=0x01)".
HeaderRecord parse_header(ByteCursor& cursor) {
  HeaderRecord header;
  header.profile = read_string(cursor, "Header profile");
  header.library = read_string(cursor, "Header library");
  return header;
}

// "Schema (op=0x03)": data is uint32 length-prefixed bytes.
SchemaRecord parse_schema(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  SchemaRecord schema;
  schema.offset = record.offset;
  schema.id = cursor.u16("Schema id");
  schema.name = read_string(cursor, "Schema name");
  schema.encoding = read_string(cursor, "Schema encoding");
  schema.data = read_string(cursor, "Schema data");
  return schema;
}

// "Channel (op=0x04)".
ChannelRecord parse_channel(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  ChannelRecord channel;
  channel.offset = record.offset;
  channel.id = cursor.u16("Channel id");
  channel.schema_id = cursor.u16("Channel schema_id");
  channel.topic = read_string(cursor, "Channel topic");
  channel.message_encoding = read_string(cursor, "Channel message_encoding");
  skip_string_map(cursor, file, "Channel metadata");
  return channel;
}

// "Message (op=0x05)": the data is the rest of the record.
MessageRecord parse_message(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  MessageRecord message;
  message.channel_id = cursor.u16("Message channel_id");
  cursor.skip(4, "Message sequence");
  message.log_time_ns = read_time(cursor, "Message log_time");
  cursor.skip(8, "Message publish_time");
  message.data = cursor.bytes(cursor.remaining(), "Message data");
  return message;
}

// "Chunk (op=0x06)": records are uint64 length-prefixed bytes.
ChunkRecord parse_chunk(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  ChunkRecord chunk;
  chunk.message_start_ns = read_time(cursor, "Chunk message_start_time");
  chunk.message_end_ns = read_time(cursor, "Chunk message_end_time");
  chunk.uncompressed_size = cursor.u64("Chunk uncompressed_size");
  chunk.uncompressed_crc = cursor.u32("Chunk uncompressed_crc");
  chunk.compression = read_string(cursor, "Chunk compression");
  const std::uint64_t length = cursor.u64("Chunk records length");
  chunk.records_offset = cursor.offset();
  chunk.records = cursor.bytes(length, "Chunk records");
  return chunk;
}

// "Chunk Index (op=0x08)".
ChunkIndexRecord parse_chunk_index(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  ChunkIndexRecord index;
  index.offset = record.offset;
  index.message_start_ns = read_time(cursor, "Chunk Index message_start_time");
  index.message_end_ns = read_time(cursor, "Chunk Index message_end_time");
  index.chunk_start_offset = cursor.u64("Chunk Index chunk_start_offset");
  index.chunk_length = cursor.u64("Chunk Index chunk_length");
  index.message_index_offsets = read_u16_u64_map(cursor, file, "Chunk Index message_index_offsets");
  index.message_index_length = cursor.u64("Chunk Index message_index_length");
  index.compression = read_string(cursor, "Chunk Index compression");
  index.compressed_size = cursor.u64("Chunk Index compressed_size");
  index.uncompressed_size = cursor.u64("Chunk Index uncompressed_size");
  return index;
}

// "Statistics (op=0x0B)".
StatisticsRecord parse_statistics(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  StatisticsRecord statistics;
  statistics.offset = record.offset;
  statistics.message_count = cursor.u64("Statistics message_count");
  cursor.skip(2 + 4, "Statistics schema_count, channel_count");
  statistics.attachment_count = cursor.u32("Statistics attachment_count");
  statistics.metadata_count = cursor.u32("Statistics metadata_count");
  statistics.chunk_count = cursor.u32("Statistics chunk_count");
  read_time(cursor, "Statistics message_start_time");
  read_time(cursor, "Statistics message_end_time");
  statistics.channel_message_counts = read_u16_u64_map(cursor, file, "Statistics channel_message_counts");
  return statistics;
}

// "Attachment (op=0x09)": crc is the CRC32 of every field before it (0: not available).
void check_attachment(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  read_time(cursor, "Attachment log_time");
  read_time(cursor, "Attachment create_time");
  read_string(cursor, "Attachment name");
  read_string(cursor, "Attachment media_type");
  cursor.skip(cursor.u64("Attachment data length"), "Attachment data");
  const std::size_t covered = cursor.position();
  const std::uint32_t stored = cursor.u32("Attachment crc");
  const std::uint32_t computed = crc32_of(record.content.first(covered));
  if (stored != 0 && stored != computed) {
    cursor.fail_at(record.offset, "Attachment crc " + hex(stored, 8) + " does not match its content (" +
                                      hex(computed, 8) + ")");
  }
}

// "Metadata (op=0x0C)": name and Map<string, string>, validated only.
void check_metadata(const RecordView& record, std::string_view file) {
  ByteCursor cursor = record.cursor(file);
  read_string(cursor, "Metadata name");
  skip_string_map(cursor, file, "Metadata metadata");
}

// "Footer (op=0x02)".
FooterRecord parse_footer(ByteCursor& cursor) {
  FooterRecord footer;
  footer.summary_start = cursor.u64("Footer summary_start");
  footer.summary_offset_start = cursor.u64("Footer summary_offset_start");
  footer.summary_crc = cursor.u32("Footer summary_crc");
  return footer;
}

// ---------------------------------------------------------------------------------------------
// Chunk decompression ("Chunk": compression "" / "zstd" / "lz4", registry "Well-known
// compression formats"; lz4 means the LZ4 frame format).

/// One chunk's records, uncompressed. For compression "" they are borrowed from the record bytes
/// and `records_base` is their file offset; decompressed records have offsets relative to their
/// start (records_base 0), and errors in them are reported "at decompressed byte K".
struct DecodedChunk {
  std::vector<std::uint8_t> record;
  std::unique_ptr<std::uint8_t[]> decompressed;
  std::span<const std::uint8_t> records;
  std::uint64_t records_base = 0;
  std::uint64_t offset = 0;  // of the Chunk record
  ChunkRecord header;
  bool compressed() const { return !header.compression.empty(); }
};

bool is_supported_compression(const std::string& compression) {
  return compression.empty() || compression == "zstd" || compression == "lz4";
}

std::string unsupported_compression(const std::string& compression) {
  return "chunk compression \"" + compression + "\" is not supported (cairn reads \"\", \"zstd\" and \"lz4\")";
}

std::string compression_label(const std::string& compression) {
  return compression.empty() ? "none" : compression;
}

/// Refuses, before allocating, an uncompressed_size no valid chunk of this size can have.
void check_uncompressed_size(const McapFile& file, const DecodedChunk& chunk) {
  const ChunkRecord& header = chunk.header;
  const std::uint64_t compressed = header.records.size();
  const std::uint64_t ratio = header.compression == "zstd" ? kZstdMaxRatio : kLz4MaxRatio;
  const std::uint64_t bound = std::min(kMaxDecompressedChunkBytes, compressed * ratio + 1024);
  if (header.uncompressed_size > bound) {
    file.fail(chunk.offset, "Chunk uncompressed_size " + std::to_string(header.uncompressed_size) + " is beyond " +
                                std::to_string(bound) + " (the most " + std::to_string(compressed) + " " +
                                header.compression + " bytes can hold, capped at 1 GiB)");
  }
  if (header.compression != "zstd") return;
  // A single zstd frame usually declares its content size: it must agree.
  const auto declared = ZSTD_getFrameContentSize(header.records.data(), header.records.size());
  if (declared == ZSTD_CONTENTSIZE_ERROR) file.fail(header.records_offset, "expected a zstd frame in the Chunk records");
  const std::size_t first_frame = ZSTD_findFrameCompressedSize(header.records.data(), header.records.size());
  const bool single_frame = !ZSTD_isError(first_frame) && first_frame == header.records.size();
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN && (declared > header.uncompressed_size ||
                                                (single_frame && declared != header.uncompressed_size))) {
    file.fail(chunk.offset, "Chunk uncompressed_size " + std::to_string(header.uncompressed_size) +
                                " disagrees with its zstd frame (" + std::to_string(declared) + " bytes)");
  }
}

void decompress_zstd(const McapFile& file, const DecodedChunk& chunk, std::span<std::uint8_t> out) {
  const auto& in = chunk.header.records;
  const std::size_t got = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
  if (ZSTD_isError(got)) file.fail(chunk.offset, std::string("zstd chunk: ") + ZSTD_getErrorName(got));
  if (got != out.size()) {
    file.fail(chunk.offset, "zstd chunk decompressed to " + std::to_string(got) + " bytes, uncompressed_size says " +
                                std::to_string(out.size()));
  }
}

void decompress_lz4(const McapFile& file, const DecodedChunk& chunk, std::span<std::uint8_t> out) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) file.fail(chunk.offset, "lz4: out of memory");
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> context(raw, &LZ4F_freeDecompressionContext);
  const auto& in = chunk.header.records;
  std::size_t in_at = 0;
  std::size_t out_at = 0;
  while (in_at < in.size()) {
    std::size_t in_size = in.size() - in_at;
    std::size_t out_size = out.size() - out_at;
    const std::size_t hint = LZ4F_decompress(context.get(), out.data() + out_at, &out_size, in.data() + in_at,
                                             &in_size, nullptr);
    if (LZ4F_isError(hint)) file.fail(chunk.offset, std::string("lz4 chunk: ") + LZ4F_getErrorName(hint));
    in_at += in_size;
    out_at += out_size;
    if (in_size == 0 && out_size == 0) break;  // no progress: the output is full
  }
  if (in_at != in.size() || out_at != out.size()) {
    file.fail(chunk.offset, "lz4 chunk decompressed to " + std::to_string(out_at) + "+ bytes from " +
                                std::to_string(in_at) + " of " + std::to_string(in.size()) +
                                " input bytes, uncompressed_size says " + std::to_string(out.size()));
  }
}

/// Parses the Chunk record `record` (read from `offset`), decompresses and CRC-checks its records.
std::shared_ptr<DecodedChunk> decode_chunk(const McapFile& file, std::vector<std::uint8_t> record, std::uint64_t offset) {
  auto chunk = std::make_shared<DecodedChunk>();
  chunk->record = std::move(record);
  chunk->offset = offset;
  ByteCursor cursor(chunk->record, file.path(), offset);
  RecordView view;
  view.offset = offset;
  view.opcode = cursor.u8("record opcode");
  const std::uint64_t length = cursor.u64("record content length");
  if (view.opcode != op::kChunk || length != cursor.remaining()) {
    file.fail(offset, "expected a Chunk record of " + std::to_string(cursor.remaining()) + " content bytes, found a " +
                          record_name(view.opcode) + " of " + std::to_string(length));
  }
  view.content = cursor.bytes(length, "Chunk record");
  chunk->header = parse_chunk(view, file.path());
  const ChunkRecord& header = chunk->header;
  if (!is_supported_compression(header.compression)) file.fail(offset, unsupported_compression(header.compression));
  if (header.compression.empty()) {
    if (header.uncompressed_size != header.records.size()) {
      file.fail(offset, "uncompressed Chunk has " + std::to_string(header.records.size()) +
                            " record bytes, uncompressed_size says " + std::to_string(header.uncompressed_size));
    }
    chunk->records = header.records;
    chunk->records_base = header.records_offset;
  } else {
    check_uncompressed_size(file, *chunk);
    const auto size = static_cast<std::size_t>(header.uncompressed_size);
    chunk->decompressed = std::make_unique_for_overwrite<std::uint8_t[]>(size);
    const std::span<std::uint8_t> out(chunk->decompressed.get(), size);
    if (header.compression == "zstd") decompress_zstd(file, *chunk, out);
    else decompress_lz4(file, *chunk, out);
    chunk->records = out;
  }
  const std::uint32_t crc = crc32_of(chunk->records);
  if (header.uncompressed_crc != 0 && header.uncompressed_crc != crc) {
    file.fail(offset, "Chunk uncompressed_crc " + hex(header.uncompressed_crc, 8) + " does not match its records (" +
                          hex(crc, 8) + ")");
  }
  return chunk;
}

/// Visits the records of a decoded chunk; errors inside compressed records name the chunk.
template <typename Visit>
void for_each_chunk_record(const McapFile& file, const DecodedChunk& chunk, Visit&& visit) {
  try {
    ByteCursor cursor(chunk.records, file.path(), chunk.records_base);
    for_each_record(cursor, visit);
  } catch (const io::ParseError& error) {
    if (!chunk.compressed()) throw;
    file.fail(chunk.offset, "in the " + chunk.header.compression + " Chunk starting here, at decompressed " +
                                error.detail());
  }
}

// ---------------------------------------------------------------------------------------------
// The index both ways of opening build: connections, statistics, and the blocks messages are
// merged from.

/// A chunk, or a run of messages written outside chunks, with the log-time range of its messages.
struct Block {
  std::uint64_t offset = 0;  // of the Chunk record, or of the run's first record
  std::uint64_t length = 0;  // bytes in the file
  bool is_chunk = false;
  std::string compression;   // of a chunk, as its index or header names it
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
  std::vector<std::uint16_t> channel_ids;  // channels with messages in it, sorted
};

struct McapIndex {
  std::string path;
  std::vector<Connection> connections;             // in channel id order
  std::map<std::uint16_t, std::size_t> connection_of_channel;
  ContainerSummary summary;
  std::vector<Block> blocks;                       // with messages, by (start_ns, offset)
  std::uint64_t counts_offset = 0;                 // where summary's counts came from (for errors)
};

/// Schemas and channels seen so far, with the spec's rules: a channel's schema comes first, two
/// records with one id are identical, schema id 0 is ignored.
class Catalog {
 public:
  void add_schema(const McapFile& file, SchemaRecord schema, std::vector<std::string>& notes);
  void add_channel(const McapFile& file, ChannelRecord channel);
  bool has_channel(std::uint16_t id) const { return channels_.count(id) != 0; }
  const std::map<std::uint16_t, ChannelRecord>& channels() const { return channels_; }
  /// Fills index.connections and index.connection_of_channel.
  void make_connections(McapIndex& index) const;

 private:
  std::map<std::uint16_t, SchemaRecord> schemas_;
  std::map<std::uint16_t, ChannelRecord> channels_;
  bool noted_schema_zero_ = false;
};

void Catalog::add_schema(const McapFile& file, SchemaRecord schema, std::vector<std::string>& notes) {
  if (schema.id == 0) {  // "Schema": "A Schema record with an id of zero is invalid and should be ignored"
    if (!noted_schema_zero_) notes.push_back("ignored Schema records with id 0 (invalid per the spec)");
    noted_schema_zero_ = true;
    return;
  }
  const auto [it, inserted] = schemas_.emplace(schema.id, schema);
  const SchemaRecord& known = it->second;
  if (!inserted && (known.name != schema.name || known.encoding != schema.encoding || known.data != schema.data)) {
    file.fail(schema.offset, "Schema id " + std::to_string(schema.id) + " redefined with different content (first at " +
                                 at_byte(known.offset) + ")");
  }
}

void Catalog::add_channel(const McapFile& file, ChannelRecord channel) {
  if (channel.schema_id != 0 && schemas_.count(channel.schema_id) == 0) {
    file.fail(channel.offset, "Channel " + std::to_string(channel.id) + " (" + channel.topic + ") refers to schema id " +
                                  std::to_string(channel.schema_id) + ", which no Schema record defines before it");
  }
  const auto [it, inserted] = channels_.emplace(channel.id, channel);
  const ChannelRecord& known = it->second;
  if (!inserted && (known.topic != channel.topic || known.schema_id != channel.schema_id ||
                    known.message_encoding != channel.message_encoding)) {
    file.fail(channel.offset, "Channel id " + std::to_string(channel.id) + " redefined as " + channel.topic +
                                  " (first defined at " + at_byte(known.offset) + " as " + known.topic + ")");
  }
}

void Catalog::make_connections(McapIndex& index) const {
  for (const auto& [id, channel] : channels_) {
    Connection connection;
    connection.id = id;
    connection.topic = channel.topic;
    connection.encoding = channel.message_encoding;
    if (channel.schema_id != 0) {
      const SchemaRecord& schema = schemas_.at(channel.schema_id);
      connection.type = schema.name;
      connection.definition = schema.data;
      connection.definition_encoding = schema.encoding;
    }
    index.connection_of_channel[id] = index.connections.size();
    index.connections.push_back(std::move(connection));
  }
  index.summary.connections.assign(index.connections.size(), ConnectionStatistics{});
}

void sort_blocks(std::vector<Block>& blocks) {
  std::erase_if(blocks, [](const Block& block) { return block.channel_ids.empty(); });
  std::sort(blocks.begin(), blocks.end(), [](const Block& a, const Block& b) {
    return a.start_ns != b.start_ns ? a.start_ns < b.start_ns : a.offset < b.offset;
  });
}

/// "Chunk": message_start_time and message_end_time bound every log_time in the chunk; the merge
/// relies on it. `record_offset` is where the Message record starts.
void check_message_time(const McapFile& file, const MessageRecord& message, const Block& block,
                        std::uint64_t record_offset) {
  if (message.log_time_ns < block.start_ns || message.log_time_ns > block.end_ns) {
    file.fail(record_offset, "Message log_time " + std::to_string(message.log_time_ns) + " is outside its chunk's range [" +
                                 std::to_string(block.start_ns) + ", " + std::to_string(block.end_ns) + "]");
  }
}

// ---------------------------------------------------------------------------------------------
// Opening from the summary section ("Summary Section", "Footer", "Chunk Index", "Statistics").

struct SummarySection {
  std::uint64_t start = 0;  // Footer.summary_start: also where the data section has ended
  std::vector<SchemaRecord> schemas;
  std::vector<ChannelRecord> channels;
  std::vector<ChunkIndexRecord> chunk_indexes;
  std::optional<StatisticsRecord> statistics;
};

/// The Footer before the trailing magic, or nullopt when the file does not end in the magic (cut
/// off, or still being written).
std::optional<FooterRecord> read_footer(McapFile& file, std::uint64_t data_start) {
  if (file.size() < data_start + kFooterRecordBytes + kMagicBytes) return std::nullopt;
  const std::uint64_t footer_offset = file.size() - kMagicBytes - kFooterRecordBytes;
  const auto tail = file.read(footer_offset, kFooterRecordBytes + kMagicBytes, "Footer and magic");
  if (!std::equal(kMagic.begin(), kMagic.end(), tail.begin() + kFooterRecordBytes)) return std::nullopt;
  ByteCursor cursor(tail, file.path(), footer_offset);
  const std::uint8_t opcode = cursor.u8("Footer opcode");
  const std::uint64_t length = cursor.u64("Footer length");
  if (opcode != op::kFooter || length != kFooterContentBytes) {
    file.fail(footer_offset, "expected the Footer record (opcode 0x02, length 20) before the trailing magic, found opcode " +
                                 hex(opcode, 2) + " length " + std::to_string(length));
  }
  return parse_footer(cursor);
}

/// Reads the summary (and summary offset) sections, checking Footer.summary_crc when non-zero.
SummarySection read_summary_section(McapFile& file, const FooterRecord& footer, std::uint64_t data_start) {
  const std::uint64_t footer_offset = file.size() - kMagicBytes - kFooterRecordBytes;
  if (footer.summary_start < data_start || footer.summary_start > footer_offset) {
    file.fail(footer_offset, "Footer summary_start " + std::to_string(footer.summary_start) + " is outside the file's records [" +
                                 std::to_string(data_start) + ", " + std::to_string(footer_offset) + "]");
  }
  if (footer.summary_offset_start != 0 &&
      (footer.summary_offset_start < footer.summary_start || footer.summary_offset_start > footer_offset)) {
    file.fail(footer_offset, "Footer summary_offset_start " + std::to_string(footer.summary_offset_start) +
                                 " is outside the summary section");
  }
  // "Footer": summary_crc covers the summary section up to and including summary_offset_start.
  const auto bytes = file.read(footer.summary_start, footer_offset + kRecordPrefixBytes + 16 - footer.summary_start, "summary section");
  const std::uint32_t crc = crc32_of(bytes);
  if (footer.summary_crc != 0 && footer.summary_crc != crc) {
    file.fail(footer_offset, "Footer summary_crc " + hex(footer.summary_crc, 8) + " does not match the summary section (" +
                                 hex(crc, 8) + ")");
  }
  SummarySection section;
  section.start = footer.summary_start;
  ByteCursor cursor(std::span<const std::uint8_t>(bytes).first(static_cast<std::size_t>(footer_offset - footer.summary_start)), file.path(),
                    footer.summary_start);
  for_each_record(cursor, [&](const RecordView& record) {
    switch (record.opcode) {
      case op::kSchema: section.schemas.push_back(parse_schema(record, file.path())); break;
      case op::kChannel: section.channels.push_back(parse_channel(record, file.path())); break;
      case op::kChunkIndex: section.chunk_indexes.push_back(parse_chunk_index(record, file.path())); break;
      case op::kStatistics: section.statistics = parse_statistics(record, file.path()); break;
      case op::kHeader: case op::kFooter: case op::kMessage: case op::kChunk: case op::kDataEnd:
        file.fail(record.offset, std::string("a ") + record_name(record.opcode) + " is not allowed in the summary section");
      default: break;  // indexes of attachments and metadata, summary offsets, unknown opcodes
    }
  });
  return section;
}

/// Checks every Chunk Index against the data section [data_start, section.start): in bounds, not
/// overlapping, a compression cairn reads, message indexes after their chunk.
void check_chunk_indexes(const McapFile& file, SummarySection& section, std::uint64_t data_start) {
  auto& indexes = section.chunk_indexes;
  std::sort(indexes.begin(), indexes.end(),
            [](const ChunkIndexRecord& a, const ChunkIndexRecord& b) { return a.chunk_start_offset < b.chunk_start_offset; });
  std::uint64_t previous_end = data_start;
  for (const ChunkIndexRecord& index : indexes) {
    const std::uint64_t data_end = section.start;
    if (index.chunk_start_offset < previous_end || index.chunk_start_offset > data_end ||
        index.chunk_length < kRecordPrefixBytes || index.chunk_length > data_end - index.chunk_start_offset) {
      file.fail(index.offset, "Chunk Index points at bytes [" + std::to_string(index.chunk_start_offset) + ", +" +
                                  std::to_string(index.chunk_length) + "), outside the data section or overlapping another chunk");
    }
    previous_end = index.chunk_start_offset + index.chunk_length;
    if (!is_supported_compression(index.compression)) file.fail(index.offset, unsupported_compression(index.compression));
    if (index.message_start_ns > index.message_end_ns) {
      file.fail(index.offset, "Chunk Index message_start_time is after its message_end_time");
    }
    for (const auto& [channel, offset] : index.message_index_offsets) {
      if (offset < previous_end || offset >= data_end) {
        file.fail(index.offset, "Chunk Index places the Message Index of channel " + std::to_string(channel) + " at byte " +
                                    std::to_string(offset) + ", outside the bytes after its chunk");
      }
    }
  }
}

/// Why the summary cannot stand in for a scan, or "" when it can.
std::string summary_unusable_reason(const SummarySection& section) {
  if (!section.statistics) return "the summary section has no Statistics record";
  const StatisticsRecord& statistics = *section.statistics;
  if (section.chunk_indexes.size() != statistics.chunk_count) {
    return "the summary has " + std::to_string(section.chunk_indexes.size()) + " Chunk Index records for " +
           std::to_string(statistics.chunk_count) + " chunks";
  }
  if (statistics.message_count == 0) return "";
  if (statistics.chunk_count == 0) return "the messages are outside chunks (not indexed)";
  if (statistics.channel_message_counts.empty()) return "the Statistics record has no per-channel message counts";
  std::uint64_t sum = 0;
  for (const auto& [channel, count] : statistics.channel_message_counts) sum += count;
  if (sum != statistics.message_count) return "the per-channel message counts do not add up to message_count";
  for (const ChunkIndexRecord& index : section.chunk_indexes) {
    if (index.message_index_offsets.empty() && (index.message_start_ns != 0 || index.message_end_ns != 0)) {
      return "the Chunk Index at byte " + std::to_string(index.offset) + " has no Message Index offsets";
    }
  }
  return "";
}

/// The log-time range of the channel's entries in one "Message Index" record, or nullopt when it
/// lists none.
std::optional<std::pair<std::int64_t, std::int64_t>> message_index_range(McapFile& file, std::uint64_t offset,
                                                                         std::uint16_t channel, std::uint64_t data_end) {
  const auto prefix = file.read(offset, kRecordPrefixBytes, "Message Index record");
  ByteCursor head(prefix, file.path(), offset);
  const std::uint8_t opcode = head.u8("record opcode");
  const std::uint64_t length = head.u64("record content length");
  if (opcode != op::kMessageIndex || offset + kRecordPrefixBytes > data_end || length > data_end - offset - kRecordPrefixBytes) {
    file.fail(offset, "expected the Message Index record of channel " + std::to_string(channel) + " within the data section, found a " +
                          record_name(opcode) + " of " + std::to_string(length) + " bytes");
  }
  const auto content = file.read(offset + kRecordPrefixBytes, length, "Message Index record");
  ByteCursor cursor(content, file.path(), offset + kRecordPrefixBytes);
  if (cursor.u16("Message Index channel_id") != channel) file.fail(offset, "Message Index of another channel than its Chunk Index says");
  const std::uint32_t bytes = cursor.u32("Message Index records length");
  if (bytes % 16 != 0) file.fail(offset, "Message Index records length " + std::to_string(bytes) + " is not a multiple of 16");
  ByteCursor entries = sub_cursor(cursor, bytes, file.path(), "Message Index records");
  std::optional<std::pair<std::int64_t, std::int64_t>> range;
  while (!entries.at_end()) {
    const std::int64_t time = read_time(entries, "Message Index log_time");
    entries.skip(8, "Message Index offset");
    if (!range) range = std::make_pair(time, time);
    range->first = std::min(range->first, time);
    range->second = std::max(range->second, time);
  }
  return range;
}

/// First and last log time of `channel`, from the Message Index records of only the chunks that
/// can hold them: by message_start_time until a chunk starts after the earliest time found, and
/// by message_end_time (descending) until one ends before the latest.
void channel_times(McapFile& file, const SummarySection& section, std::uint16_t channel, ConnectionStatistics& stats) {
  std::vector<const ChunkIndexRecord*> holding;
  for (const ChunkIndexRecord& index : section.chunk_indexes) {
    if (index.message_index_offsets.count(channel) != 0) holding.push_back(&index);
  }
  std::optional<std::int64_t> first;
  std::optional<std::int64_t> last;
  std::sort(holding.begin(), holding.end(), [](auto* a, auto* b) { return a->message_start_ns < b->message_start_ns; });
  for (const ChunkIndexRecord* index : holding) {
    if (first && index->message_start_ns > *first) break;
    const auto range = message_index_range(file, index->message_index_offsets.at(channel), channel, section.start);
    if (range) first = std::min(first.value_or(range->first), range->first);
  }
  std::sort(holding.begin(), holding.end(), [](auto* a, auto* b) { return a->message_end_ns > b->message_end_ns; });
  for (const ChunkIndexRecord* index : holding) {
    if (last && index->message_end_ns < *last) break;
    const auto range = message_index_range(file, index->message_index_offsets.at(channel), channel, section.start);
    if (range) last = std::max(last.value_or(range->second), range->second);
  }
  if (!first || !last) {
    file.fail(section.statistics->offset, "Statistics counts " + std::to_string(stats.messages) + " messages on channel " +
                                              std::to_string(channel) + ", but no Message Index lists any");
  }
  stats.first_ns = *first;
  stats.last_ns = *last;
}

/// Per-channel counts (Statistics.channel_message_counts) and times (Message Indexes).
void statistics_from_summary(McapFile& file, const SummarySection& section, McapIndex& index) {
  for (const auto& [channel, count] : section.statistics->channel_message_counts) {
    const auto it = index.connection_of_channel.find(channel);
    if (it == index.connection_of_channel.end()) {
      file.fail(section.statistics->offset, "Statistics counts messages on channel id " + std::to_string(channel) +
                                                ", which no Channel record in the summary defines");
    }
    ConnectionStatistics& stats = index.summary.connections[it->second];
    stats.messages = count;
    if (count != 0) channel_times(file, section, channel, stats);
  }
}

/// The blocks (one per chunk) and the chunk counts by compression, from the Chunk Indexes.
void blocks_from_summary(const McapFile& file, const SummarySection& section, McapIndex& index) {
  for (const ChunkIndexRecord& chunk : section.chunk_indexes) {
    Block block;
    block.offset = chunk.chunk_start_offset;
    block.length = chunk.chunk_length;
    block.is_chunk = true;
    block.compression = chunk.compression;
    block.start_ns = chunk.message_start_ns;
    block.end_ns = chunk.message_end_ns;
    for (const auto& [channel, offset] : chunk.message_index_offsets) {
      if (index.connection_of_channel.count(channel) == 0) {
        file.fail(chunk.offset, "Chunk Index lists messages on channel id " + std::to_string(channel) +
                                    ", which no Channel record in the summary defines");
      }
      block.channel_ids.push_back(channel);
    }
    index.summary.chunks[compression_label(chunk.compression)] += 1;
    index.blocks.push_back(std::move(block));
  }
}

/// Opens from the summary section; returns false (with a note saying why) when the file has none
/// that can stand in for a scan.
bool index_from_summary(McapFile& file, std::uint64_t data_start, McapIndex& index) {
  auto& notes = index.summary.notes;
  const std::optional<FooterRecord> footer = read_footer(file, data_start);
  if (!footer) {
    notes.push_back("no Footer and trailing magic: the file was cut off (or is still being written); read by a scan");
    return false;
  }
  if (footer->summary_start == 0) {
    notes.push_back("no summary section (Footer summary_start 0): counts and times from a scan of the records");
    return false;
  }
  SummarySection section = read_summary_section(file, *footer, data_start);
  check_chunk_indexes(file, section, data_start);
  const std::string reason = summary_unusable_reason(section);
  if (!reason.empty()) {
    notes.push_back("summary section not used (" + reason + "): counts and times from a scan of the records");
    return false;
  }
  Catalog catalog;
  for (SchemaRecord& schema : section.schemas) catalog.add_schema(file, std::move(schema), notes);
  for (ChannelRecord& channel : section.channels) catalog.add_channel(file, std::move(channel));
  catalog.make_connections(index);
  statistics_from_summary(file, section, index);
  blocks_from_summary(file, section, index);
  const StatisticsRecord& statistics = *section.statistics;
  index.counts_offset = statistics.offset;
  notes.push_back("opened from the summary section: " + count_of(section.chunk_indexes.size(), "Chunk Index record") +
                  " and Statistics; per-channel first/last log times from the Message Index records");
  if (statistics.attachment_count + statistics.metadata_count != 0) {
    notes.push_back(attachments_and_metadata(statistics.attachment_count, statistics.metadata_count));
  }
  index.summary.indexed = true;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Opening by a scan of the data section, record by record ("Data Section", "Use of chunk records").

class LinearScan {
 public:
  LinearScan(McapFile& file, McapIndex& index, std::uint64_t data_start, std::uint32_t start_crc, bool complete)
      : file_(file), index_(index), offset_(data_start), data_crc_(start_crc), complete_(complete) {}
  /// Reads records until Data End, the Footer, or the end of the file.
  void run();

 private:
  bool scan_next();
  bool stop_at_end_of_file();
  void on_record(const RecordView& record);
  void on_chunk(std::vector<std::uint8_t> bytes);
  void on_loose_message(const RecordView& record);
  void count_message(const MessageRecord& message, std::uint64_t record_offset);
  void close_loose_run();
  void check_data_end(const RecordView& record);
  void finish();

  McapFile& file_;
  McapIndex& index_;
  std::uint64_t offset_;
  std::uint32_t data_crc_;
  bool complete_;
  Catalog catalog_;
  std::map<std::uint16_t, ConnectionStatistics> statistics_;
  std::optional<Block> loose_;
  std::uint64_t attachments_ = 0;
  std::uint64_t metadata_ = 0;
  std::uint64_t unknown_ = 0;
};

void LinearScan::run() {
  while (scan_next()) {
  }
  finish();
}

// False at the end of the data section.
bool LinearScan::scan_next() {
  if (!file_.fits(offset_, kRecordPrefixBytes)) return stop_at_end_of_file();
  const auto prefix = file_.read(offset_, kRecordPrefixBytes, "record");
  ByteCursor head(prefix, file_.path(), offset_);
  const std::uint8_t opcode = head.u8("record opcode");
  const std::uint64_t length = head.u64("record content length");
  if (opcode == 0) file_.fail(offset_, "expected a record opcode, found 0x00 (invalid in MCAP)");
  if (!file_.fits(offset_ + kRecordPrefixBytes, length)) return stop_at_end_of_file();
  if (opcode == op::kFooter) {
    index_.summary.notes.push_back("no Data End record before the Footer");
    return false;
  }
  auto bytes = file_.read(offset_, kRecordPrefixBytes + length, record_name(opcode));
  RecordView record{opcode, offset_, std::span<const std::uint8_t>(bytes).subspan(kRecordPrefixBytes)};
  if (opcode == op::kDataEnd) {
    check_data_end(record);
    return false;
  }
  data_crc_ = crc32_of(bytes, data_crc_);
  if (opcode == op::kChunk) on_chunk(std::move(bytes));
  else on_record(record);
  offset_ += kRecordPrefixBytes + length;
  return true;
}

// The file ends before the record at offset_ does (or exactly at it).
bool LinearScan::stop_at_end_of_file() {
  if (complete_) file_.fail(offset_, "record runs past the end of the data section (file of " + std::to_string(file_.size()) + " bytes)");
  if (offset_ == file_.size()) {
    index_.summary.notes.push_back("file ends at byte " + std::to_string(offset_) + " after a whole record, without Data End or Footer");
  } else {
    index_.summary.notes.push_back("file ends inside a record at byte " + std::to_string(file_.size()) + " (the record starting at byte " +
                                   std::to_string(offset_) + "): the whole records before it were read");
  }
  return false;
}

void LinearScan::on_record(const RecordView& record) {
  const std::string_view path = file_.path();
  if (record.opcode != op::kMessage && record.opcode != op::kSchema && record.opcode != op::kChannel) close_loose_run();
  switch (record.opcode) {
    case op::kSchema: catalog_.add_schema(file_, parse_schema(record, path), index_.summary.notes); break;
    case op::kChannel: catalog_.add_channel(file_, parse_channel(record, path)); break;
    case op::kMessage: on_loose_message(record); break;
    case op::kAttachment: check_attachment(record, path); ++attachments_; break;
    case op::kMetadata: check_metadata(record, path); ++metadata_; break;
    case op::kHeader: file_.fail(record.offset, "a second Header record");
    case op::kMessageIndex: case op::kChunkIndex: case op::kAttachmentIndex: case op::kStatistics:
    case op::kMetadataIndex: case op::kSummaryOffset: break;  // indexes: rebuilt by this scan
    default: ++unknown_; break;  // "Records": unknown opcodes are skipped by their length
  }
}

void LinearScan::count_message(const MessageRecord& message, std::uint64_t record_offset) {
  if (!catalog_.has_channel(message.channel_id)) {
    file_.fail(record_offset, "Message on channel id " + std::to_string(message.channel_id) +
                                  ", which no earlier Channel record defines");
  }
  ConnectionStatistics& stats = statistics_[message.channel_id];
  if (stats.messages == 0 || message.log_time_ns < stats.first_ns) stats.first_ns = message.log_time_ns;
  if (stats.messages == 0 || message.log_time_ns > stats.last_ns) stats.last_ns = message.log_time_ns;
  ++stats.messages;
}

void LinearScan::on_loose_message(const RecordView& record) {
  const MessageRecord message = parse_message(record, file_.path());
  count_message(message, record.offset);
  const std::uint64_t end = record.content_offset() + record.content.size();
  if (loose_ && end - loose_->offset > kLooseRunBytes) close_loose_run();
  if (!loose_) {
    loose_.emplace();
    loose_->offset = record.offset;
    loose_->start_ns = loose_->end_ns = message.log_time_ns;
  }
  loose_->length = end - loose_->offset;
  loose_->start_ns = std::min(loose_->start_ns, message.log_time_ns);
  loose_->end_ns = std::max(loose_->end_ns, message.log_time_ns);
  auto& ids = loose_->channel_ids;
  const auto at = std::lower_bound(ids.begin(), ids.end(), message.channel_id);
  if (at == ids.end() || *at != message.channel_id) ids.insert(at, message.channel_id);
}

void LinearScan::close_loose_run() {
  if (loose_) index_.blocks.push_back(std::move(*loose_));
  loose_.reset();
}

void LinearScan::on_chunk(std::vector<std::uint8_t> bytes) {
  close_loose_run();
  Block block;
  block.offset = offset_;
  block.length = bytes.size();
  block.is_chunk = true;
  const auto chunk = decode_chunk(file_, std::move(bytes), offset_);
  block.compression = chunk->header.compression;
  block.start_ns = chunk->header.message_start_ns;
  block.end_ns = chunk->header.message_end_ns;
  std::vector<std::uint16_t> channels;
  std::vector<MessageRecord> messages;
  for_each_chunk_record(file_, *chunk, [&](const RecordView& record) {
    switch (record.opcode) {
      case op::kSchema: catalog_.add_schema(file_, parse_schema(record, file_.path()), index_.summary.notes); break;
      case op::kChannel: catalog_.add_channel(file_, parse_channel(record, file_.path())); break;
      case op::kMessage: {
        const MessageRecord message = parse_message(record, file_.path());
        count_message(message, record.offset);
        check_message_time(file_, message, block, record.offset);
        channels.push_back(message.channel_id);
        break;
      }
      default: ++unknown_; break;  // "Chunk": only Schema, Channel and Message belong here
    }
  });
  std::sort(channels.begin(), channels.end());
  channels.erase(std::unique(channels.begin(), channels.end()), channels.end());
  block.channel_ids = std::move(channels);
  index_.summary.chunks[compression_label(block.compression)] += 1;
  index_.blocks.push_back(std::move(block));
}

// "Data End": data_section_crc covers every byte from the start of the file up to this record.
void LinearScan::check_data_end(const RecordView& record) {
  ByteCursor cursor = record.cursor(file_.path());
  const std::uint32_t stored = cursor.u32("Data End data_section_crc");
  if (stored != 0 && stored != data_crc_) {
    file_.fail(record.offset, "Data End data_section_crc " + hex(stored, 8) + " does not match the data section (" +
                                  hex(data_crc_, 8) + ")");
  }
}

void LinearScan::finish() {
  close_loose_run();
  catalog_.make_connections(index_);
  for (const auto& [channel, stats] : statistics_) {
    index_.summary.connections[index_.connection_of_channel.at(channel)] = stats;
  }
  auto& notes = index_.summary.notes;
  if (attachments_ + metadata_ != 0) {
    notes.push_back(attachments_and_metadata(attachments_, metadata_));
  }
  if (unknown_ != 0) notes.push_back("skipped " + count_of(unknown_, "record") + " of unknown or misplaced opcodes");
  index_.summary.indexed = false;
}

// ---------------------------------------------------------------------------------------------
// The message stream: a k-way merge over the blocks, in order of their first log time.

class McapMessageStream final : public MessageStream {
 public:
  McapMessageStream(std::shared_ptr<const McapIndex> index, const std::vector<bool>& wanted);
  bool next(Message* message) override;

 private:
  struct Pending {
    std::int64_t log_time_ns = 0;
    std::uint64_t block_offset = 0;   // with record_offset: file order, for ties
    std::uint64_t record_offset = 0;
    std::size_t connection = 0;
    std::span<const std::uint8_t> data;
    std::uint64_t file_offset = 0;
    std::shared_ptr<const void> holder;  // keeps the block's bytes alive
  };
  struct Later {
    bool operator()(const Pending& a, const Pending& b) const {
      if (a.log_time_ns != b.log_time_ns) return a.log_time_ns > b.log_time_ns;
      if (a.block_offset != b.block_offset) return a.block_offset > b.block_offset;
      return a.record_offset > b.record_offset;
    }
  };

  void load_due_blocks();
  void check_counts() const;
  bool wants(const Block& block) const;
  void load_chunk(const Block& block);
  void load_loose_run(const Block& block);
  void push_message(const RecordView& record, const Block& block, std::shared_ptr<const void> holder,
                    std::uint64_t file_offset);

  std::shared_ptr<const McapIndex> index_;
  McapFile file_;
  std::vector<bool> wanted_;  // by connection index; empty: all
  std::size_t next_block_ = 0;
  std::priority_queue<Pending, std::vector<Pending>, Later> pending_;
  std::shared_ptr<const void> current_;  // the bytes of the message last returned
  std::vector<std::uint64_t> emitted_;    // messages returned, by connection
};

McapMessageStream::McapMessageStream(std::shared_ptr<const McapIndex> index, const std::vector<bool>& wanted)
    : index_(std::move(index)), file_(index_->path), wanted_(wanted), emitted_(index_->connections.size(), 0) {}

bool McapMessageStream::next(Message* message) {
  load_due_blocks();
  if (pending_.empty()) {
    current_.reset();
    check_counts();
    return false;
  }
  Pending top = pending_.top();
  pending_.pop();
  current_ = std::move(top.holder);
  message->connection = top.connection;
  message->log_time_ns = top.log_time_ns;
  message->data = top.data;
  message->owner = current_;
  message->file_offset = top.file_offset;
  ++emitted_[top.connection];
  return true;
}

// A record damaged inside a chunk without a CRC can turn a Message into a record of unknown kind,
// which is skipped: the counts the file was opened with catch that at the end.
void McapMessageStream::check_counts() const {
  for (std::size_t i = 0; i < emitted_.size(); ++i) {
    if (!wanted_.empty() && !wanted_[i]) continue;
    const std::uint64_t expected = index_->summary.connections[i].messages;
    if (emitted_[i] != expected) {
      file_.fail(index_->counts_offset, std::string(index_->summary.indexed ? "the Statistics record" : "the scan at open") +
                                            " counts " + std::to_string(expected) + " messages on " + index_->connections[i].topic +
                                            ", the chunks hold " + std::to_string(emitted_[i]) +
                                            " (a record inside a chunk is damaged or of an unknown kind)");
    }
  }
}

// Every block that can hold a message at or before the earliest pending one is loaded first: the
// blocks are sorted by start_ns, so the ones left all start later.
void McapMessageStream::load_due_blocks() {
  const auto& blocks = index_->blocks;
  while (next_block_ < blocks.size()) {
    const Block& block = blocks[next_block_];
    if (!pending_.empty() && block.start_ns > pending_.top().log_time_ns) break;
    ++next_block_;
    if (!wants(block)) continue;
    if (block.is_chunk) load_chunk(block);
    else load_loose_run(block);
  }
}

bool McapMessageStream::wants(const Block& block) const {
  if (wanted_.empty()) return true;
  return std::any_of(block.channel_ids.begin(), block.channel_ids.end(),
                     [&](std::uint16_t id) { return wanted_[index_->connection_of_channel.at(id)]; });
}

void McapMessageStream::load_chunk(const Block& block) {
  std::shared_ptr<const DecodedChunk> chunk = decode_chunk(file_, file_.read(block.offset, block.length, "Chunk record"), block.offset);
  if (chunk->header.compression != block.compression) {
    file_.fail(block.offset, "Chunk compression \"" + chunk->header.compression + "\" disagrees with its Chunk Index (\"" +
                                 block.compression + "\")");
  }
  for_each_chunk_record(file_, *chunk, [&](const RecordView& record) {
    if (record.opcode != op::kMessage) return;
    push_message(record, block, chunk, chunk->compressed() ? block.offset : record.offset);
  });
}

void McapMessageStream::load_loose_run(const Block& block) {
  auto bytes = std::make_shared<const std::vector<std::uint8_t>>(file_.read(block.offset, block.length, "messages"));
  ByteCursor cursor(*bytes, file_.path(), block.offset);
  for_each_record(cursor, [&](const RecordView& record) {
    if (record.opcode != op::kMessage) return;
    push_message(record, block, bytes, record.offset);
  });
}

// Errors name record.offset: absolute, or relative to decompressed records (then
// for_each_chunk_record names the chunk).
void McapMessageStream::push_message(const RecordView& record, const Block& block, std::shared_ptr<const void> holder,
                                     std::uint64_t file_offset) {
  const MessageRecord message = parse_message(record, file_.path());
  const auto it = index_->connection_of_channel.find(message.channel_id);
  if (it == index_->connection_of_channel.end()) {
    file_.fail(record.offset, "Message on channel id " + std::to_string(message.channel_id) + ", which no Channel record defines");
  }
  check_message_time(file_, message, block, record.offset);
  if (!std::binary_search(block.channel_ids.begin(), block.channel_ids.end(), message.channel_id)) {
    file_.fail(record.offset, "Message on channel id " + std::to_string(message.channel_id) +
                                  ", which the Chunk Index does not list for this chunk");
  }
  if (!wanted_.empty() && !wanted_[it->second]) return;
  pending_.push(Pending{message.log_time_ns, block.offset, record.offset, it->second, message.data, file_offset,
                        std::move(holder)});
}

// ---------------------------------------------------------------------------------------------

class McapContainer final : public Container {
 public:
  explicit McapContainer(std::shared_ptr<const McapIndex> index) : index_(std::move(index)) {}
  const std::string& path() const override { return index_->path; }
  const std::vector<Connection>& connections() const override { return index_->connections; }
  const ContainerSummary& summary() const override { return index_->summary; }
  std::unique_ptr<MessageStream> messages(const std::vector<bool>& wanted) override {
    CAIRN_ASSERT(wanted.empty() || wanted.size() == index_->connections.size(),
                 "Container::messages: `wanted` must be empty or have one entry per connection");
    return std::make_unique<McapMessageStream>(index_, wanted);
  }

 private:
  std::shared_ptr<const McapIndex> index_;
};

/// "Magic" then "Header": returns the header and the offset of the first data section record.
std::uint64_t read_magic_and_header(McapFile& file, HeaderRecord& header, std::uint32_t& crc) {
  if (file.size() == 0) file.fail(0, "expected the MCAP magic 0x89 \"MCAP0\\r\\n\", found an empty file");
  if (file.size() < kMagicBytes + kRecordPrefixBytes) {
    file.fail(0, "expected the MCAP magic and a Header record, found only " + std::to_string(file.size()) + " bytes");
  }
  const auto start = file.read(0, kMagicBytes + kRecordPrefixBytes, "magic and Header");
  if (!looks_like_mcap(start)) file.fail(0, "expected the MCAP magic 0x89 \"MCAP0\\r\\n\", found other bytes");
  if (start[5] != '0') {
    file.fail(5, std::string("MCAP major version '") + static_cast<char>(start[5]) + "' is not supported (cairn reads version '0')");
  }
  ByteCursor head(std::span<const std::uint8_t>(start).subspan(kMagicBytes), file.path(), kMagicBytes);
  const std::uint8_t opcode = head.u8("Header opcode");
  const std::uint64_t length = head.u64("Header length");
  if (opcode != op::kHeader) file.fail(kMagicBytes, "expected the Header record (opcode 0x01), found opcode " + hex(opcode, 2));
  const auto content = file.read(kMagicBytes + kRecordPrefixBytes, length, "Header record");
  ByteCursor cursor(content, file.path(), kMagicBytes + kRecordPrefixBytes);
  header = parse_header(cursor);
  crc = crc32_of(content, crc32_of(start));
  return kMagicBytes + kRecordPrefixBytes + length;
}

}  // namespace

bool looks_like_mcap(std::span<const std::uint8_t> first_bytes) {
  if (first_bytes.size() < kMagicBytes) return false;
  for (std::size_t i = 0; i < kMagicBytes; ++i) {
    if (i != 5 && first_bytes[i] != kMagic[i]) return false;  // byte 5: the major version
  }
  return true;
}

std::unique_ptr<Container> open_mcap(const std::string& path) {
  McapFile file(path);
  auto index = std::make_shared<McapIndex>();
  index->path = path;
  index->summary.format = "MCAP";
  index->summary.file_bytes = file.size();
  HeaderRecord header;
  std::uint32_t crc = 0;
  const std::uint64_t data_start = read_magic_and_header(file, header, crc);
  index->summary.profile = header.profile;
  if (!index_from_summary(file, data_start, *index)) {
    const bool complete = read_footer(file, data_start).has_value();
    LinearScan(file, *index, data_start, crc, complete).run();
    index->counts_offset = data_start;
  }
  sort_blocks(index->blocks);
  return std::make_unique<McapContainer>(std::move(index));
}

}  // namespace cairn::bag
