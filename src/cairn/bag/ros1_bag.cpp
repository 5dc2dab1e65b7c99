#include "cairn/bag/ros1_bag.hpp"

#include <bzlib.h>
#include <lz4frame.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <fstream>
#include <iterator>
#include <list>
#include <map>
#include <memory>
#include <optional>
#include <queue>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "cairn/bag/byte_cursor.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/io/input_file.hpp"
#include "cairn/io/parse_error.hpp"

// Section names in comments refer to the format specification, wiki.ros.org/Bags/Format/2.0.
// Behaviour beyond it follows rosbag itself (ros/ros_comm tools/rosbag_storage/src/bag.cpp and
// tools/rosbag/src/rosbag/bag.py): which index to trust, how a bag without one is reindexed.

namespace cairn::bag {
namespace {

using Bytes = std::vector<std::uint8_t>;
using ByteView = std::span<const std::uint8_t>;

// "Format": the version line that precedes the records.
constexpr std::string_view kVersionLine = "#ROSBAG V2.0\n";
constexpr std::string_view kAnyVersionPrefix = "#ROSBAG V";
constexpr std::string_view kOldRecordPrefix = "#ROSRECORD V";
constexpr std::string_view kFormat12Line = "#ROSRECORD V1.2";

// The op field of each record type, as the spec's record sections ("Bag header", "Chunk", ...) give it.
enum class Op : std::uint8_t {
  message_data = 0x02,
  bag_header = 0x03,
  index_data = 0x04,
  chunk = 0x05,
  chunk_info = 0x06,
  connection = 0x07,
};

// "Index data" version 1: each entry is time (sec, nsec: 8 bytes) and offset (4 bytes).
constexpr std::uint64_t kIndexEntryBytes = 12;
// "Chunk info": each entry is conn (4 bytes) and count (4 bytes).
constexpr std::uint64_t kChunkInfoEntryBytes = 8;
// Message data records found outside any chunk (a chunk never closed) are read in blocks of
// about this size, so that such a bag is also streamed in bounded memory.
constexpr std::uint64_t kLooseBlockBytes = std::uint64_t{16} << 20;
constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;

[[noreturn]] void fail(std::string_view file, std::uint64_t offset, const std::string& detail) {
  throw io::ParseError(std::string(file), 0, "byte " + std::to_string(offset) + ": " + detail);
}

/// `text` quoted for an error message: non-printable bytes escaped, long text cut.
std::string quoted(std::string_view text, std::size_t max_chars = 40) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size() && i < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      out += "\\n";
    } else if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0x0f];
    }
  }
  if (text.size() > max_chars) out += "...";
  return out + "\"";
}

std::string_view as_text(ByteView bytes) { return {reinterpret_cast<const char*>(bytes.data()), bytes.size()}; }

std::uint32_t load_u32(const std::uint8_t* bytes) {
  std::uint32_t value = 0;
  std::memcpy(&value, bytes, sizeof value);  // little-endian hosts only, as ByteCursor
  return value;
}

/// "Message data": a time is sec then nsec, two little-endian uint32.
std::int64_t time_to_ns(const std::uint8_t* bytes) {
  return static_cast<std::int64_t>(load_u32(bytes)) * kNanosecondsPerSecond + load_u32(bytes + 4);
}

/// "a chunk record", "an index data record".
std::string with_article(const std::string& noun) {
  const bool vowel = !noun.empty() && std::string_view("aeiou").find(noun[0]) != std::string_view::npos;
  return (vowel ? "an " : "a ") + noun;
}

std::string op_name(std::uint8_t op) {
  switch (static_cast<Op>(op)) {
    case Op::message_data: return "message data";
    case Op::bag_header: return "bag header";
    case Op::index_data: return "index data";
    case Op::chunk: return "chunk";
    case Op::chunk_info: return "chunk info";
    case Op::connection: return "connection";
  }
  return "unknown (op " + std::to_string(op) + ")";
}

// ---------------------------------------------------------------------------------------------
// The file.

/// Random access to the bag's bytes. Every read is checked against the file's size first, so a
/// length read from the file never allocates more than the file holds.
class BagFile {
 public:
  explicit BagFile(const std::string& path) : path_(path), stream_(path, std::ios::binary) {
    if (!stream_) throw io::ParseError(path, 0, "cannot open file");
    stream_.seekg(0, std::ios::end);
    const std::streamoff end = stream_.tellg();
    if (end < 0) throw io::ParseError(path, 0, "cannot seek in the file: a ROS bag needs random access");
    size_ = static_cast<std::uint64_t>(end);
  }

  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }
  bool fits(std::uint64_t offset, std::uint64_t bytes) const { return offset <= size_ && bytes <= size_ - offset; }

  /// The `bytes` bytes at `offset`; throws when the file ends before them.
  Bytes read(std::uint64_t offset, std::uint64_t bytes, const char* what) {
    Bytes out;
    read_into(offset, bytes, what, &out);
    return out;
  }

  /// As read(), into `out`, whose memory is reused (a recycled chunk buffer: no fresh pages).
  void read_into(std::uint64_t offset, std::uint64_t bytes, const char* what, Bytes* buffer) {
    if (!fits(offset, bytes)) {
      fail(path_, offset, std::string(what) + " needs " + std::to_string(bytes) + " bytes, the " +
                              std::to_string(size_) + "-byte file ends before them");
    }
    Bytes& out = *buffer;
    out.resize(static_cast<std::size_t>(bytes));
    stream_.clear();
    stream_.seekg(static_cast<std::streamoff>(offset));
    stream_.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(bytes));
    if (!stream_) fail(path_, offset, std::string("read error in ") + what);
  }

 private:
  std::string path_;
  std::ifstream stream_;
  std::uint64_t size_ = 0;
};

// ---------------------------------------------------------------------------------------------
// "Headers": <field_len><name>=<value>..., each field_len counting name, '=' and value.

struct Field {
  std::string_view name;
  ByteView value;
  std::uint64_t offset = 0;  ///< absolute offset of the field's length
};

/// The fields of one header, as views into the bytes parsed (which must outlive them).
class RecordFields {
 public:
  /// Splits `bytes`, which start at absolute offset `base`. `record_offset` and `kind` ("record
  /// header", "connection header") name the header in errors.
  void parse(ByteView bytes, std::uint64_t base, std::string_view file, std::uint64_t record_offset,
             std::string_view kind) {
    fields_.clear();
    file_ = file;
    record_offset_ = record_offset;
    kind_ = kind;
    ByteCursor cursor(bytes, file, base);
    while (!cursor.at_end()) {
      const std::uint64_t offset = cursor.offset();
      const std::uint32_t length = cursor.u32("header field length");
      const ByteView text = cursor.bytes(length, "header field");
      const std::size_t equals = as_text(text).find('=');
      if (equals == std::string_view::npos) {
        fail(file, offset, "header field without '=': expected name=value, found " + quoted(as_text(text)));
      }
      fields_.push_back({as_text(text.first(equals)), text.subspan(equals + 1), offset});
    }
  }

  /// The field `name`; the last one when it repeats (as ros::Header's map keeps it).
  const Field* find(std::string_view name) const {
    for (auto it = fields_.rbegin(); it != fields_.rend(); ++it) {
      if (it->name == name) return &*it;
    }
    return nullptr;
  }
  std::uint8_t op() const { return fixed("op", 1)[0]; }
  std::uint32_t u32(std::string_view name) const { return load_u32(fixed(name, 4).data()); }
  std::uint64_t u64(std::string_view name) const {
    std::uint64_t value = 0;
    std::memcpy(&value, fixed(name, 8).data(), sizeof value);
    return value;
  }
  std::int64_t time_ns(std::string_view name) const { return time_to_ns(fixed(name, 8).data()); }
  std::string text(std::string_view name) const { return std::string(as_text(require(name).value)); }

 private:
  const Field& require(std::string_view name) const {
    const Field* field = find(name);
    if (field == nullptr) fail(file_, record_offset_, describe() + " has no '" + std::string(name) + "' field");
    return *field;
  }
  ByteView fixed(std::string_view name, std::size_t size) const {
    const Field& field = require(name);
    if (field.value.size() != size) {
      fail(file_, field.offset, "field '" + std::string(name) + "' of the " + describe() + ": expected " +
                                    std::to_string(size) + " bytes, found " + std::to_string(field.value.size()));
    }
    return field.value;
  }
  std::string describe() const {
    const Field* op_field = kind_ == "record header" ? find("op") : nullptr;
    if (op_field != nullptr && op_field->value.size() == 1) return op_name(op_field->value[0]) + " record";
    return std::string(kind_);
  }

  std::vector<Field> fields_;
  std::string_view file_;
  std::uint64_t record_offset_ = 0;
  std::string_view kind_;
};

// ---------------------------------------------------------------------------------------------
// "Records": <header_len><header><data_len><data>.

/// A record read from the file: its framing and header; its data stays in the file until asked for.
struct FileRecord {
  std::uint64_t offset = 0;
  std::uint64_t data_offset = 0;
  std::uint32_t data_len = 0;
  std::uint8_t op = 0;
  Bytes header;  ///< the bytes `fields` points into (a moved vector keeps its buffer)
  RecordFields fields;
  std::uint64_t data_end() const { return data_offset + data_len; }
};

/// The record at `offset`, or std::nullopt when the file ends inside its header or data_len (a
/// truncated file). Throws when the header is malformed.
std::optional<FileRecord> try_read_record(BagFile& file, std::uint64_t offset) {
  if (!file.fits(offset, 4)) return std::nullopt;
  const std::uint32_t header_len = load_u32(file.read(offset, 4, "record header_len").data());
  if (!file.fits(offset + 4, std::uint64_t{header_len} + 4)) return std::nullopt;
  FileRecord record;
  record.offset = offset;
  record.header = file.read(offset + 4, std::uint64_t{header_len} + 4, "record header");
  record.data_len = load_u32(record.header.data() + header_len);
  record.header.resize(header_len);
  record.fields.parse(record.header, offset + 4, file.path(), offset, "record header");
  record.op = record.fields.op();
  record.data_offset = offset + 8 + header_len;
  return record;
}

/// The record at `offset`, which must be a `what` (op `expected`) and lie in the file.
FileRecord read_record(BagFile& file, std::uint64_t offset, Op expected, const std::string& what) {
  std::optional<FileRecord> record = try_read_record(file, offset);
  if (!record) {
    fail(file.path(), offset, "expected " + with_article(what) + ", the " + std::to_string(file.size()) + "-byte file ends inside it");
  }
  if (record->op != static_cast<std::uint8_t>(expected)) {
    fail(file.path(), offset, "expected " + with_article(what) + ", found " + with_article(op_name(record->op) + " record"));
  }
  return std::move(*record);
}

Bytes read_data(BagFile& file, const FileRecord& record) {
  return file.read(record.data_offset, record.data_len, (op_name(record.op) + " record data").c_str());
}

/// Records packed in memory: the data of a chunk ("Chunk").
class RecordWalker {
 public:
  RecordWalker(ByteView bytes, std::string_view file, std::uint64_t base)
      : cursor_(bytes, file, base), file_(file) {}

  /// Reads the next record; false at the end of the bytes.
  bool next() {
    if (cursor_.at_end()) return false;
    position_ = cursor_.position();
    const std::uint64_t record_offset = cursor_.offset();
    const std::uint32_t header_len = cursor_.u32("record header_len");
    const std::uint64_t header_offset = cursor_.offset();
    fields_.parse(cursor_.bytes(header_len, "record header"), header_offset, file_, record_offset, "record header");
    op_ = fields_.op();
    const std::uint32_t data_len = cursor_.u32("record data_len");
    data_position_ = cursor_.position();
    data_offset_ = cursor_.offset();
    data_ = cursor_.bytes(data_len, "record data");
    return true;
  }
  std::uint8_t op() const { return op_; }
  const RecordFields& fields() const { return fields_; }
  ByteView data() const { return data_; }
  std::uint64_t position() const { return position_; }            ///< of the record, in the bytes
  std::uint64_t data_position() const { return data_position_; }  ///< of its data, in the bytes
  std::uint64_t data_offset() const { return data_offset_; }      ///< of its data, with the base

 private:
  ByteCursor cursor_;
  std::string_view file_;
  RecordFields fields_;
  std::uint8_t op_ = 0;
  ByteView data_;
  std::uint64_t position_ = 0;
  std::uint64_t data_position_ = 0;
  std::uint64_t data_offset_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Blocks: what the stream decompresses and sorts as a unit.

/// A chunk ("Chunk"), or a run of message data records written outside any chunk (after the
/// header of a chunk that was never closed: rosbag writes a chunk's records straight to the file
/// and fills in its header when the chunk closes). A run reads like an uncompressed chunk.
struct Block {
  std::uint64_t record_offset = 0;  ///< the chunk record, or the run's first record: file order
  std::uint64_t data_offset = 0;
  std::uint64_t data_bytes = 0;
  std::uint64_t size = 0;  ///< decompressed bytes ("Chunk": the size field)
  std::string compression = "none";
  std::int64_t start_ns = 0;  ///< earliest and latest message time ("Chunk info")
  std::int64_t end_ns = 0;
  std::map<std::uint32_t, std::uint64_t> counts;  ///< messages per connection id

  bool compressed() const { return compression != "none"; }
  /// Message::file_offset of the record at `position` of the (decompressed) data.
  std::uint64_t message_offset(std::uint64_t position) const {
    return compressed() ? record_offset : data_offset + position;
  }
  void add(std::uint32_t connection_id, std::int64_t time_ns) {
    if (counts.empty()) start_ns = end_ns = time_ns;
    start_ns = std::min(start_ns, time_ns);
    end_ns = std::max(end_ns, time_ns);
    ++counts[connection_id];
  }
};

bool supported_compression(std::string_view compression) {
  return compression == "none" || compression == "bz2" || compression == "lz4";
}

/// The Block of a chunk record (complete in the file); checks what can be checked before reading it.
Block chunk_block(const FileRecord& record, std::string_view file) {
  Block block;
  block.record_offset = record.offset;
  block.data_offset = record.data_offset;
  block.data_bytes = record.data_len;
  block.size = record.fields.u32("size");
  block.compression = record.fields.text("compression");
  if (!supported_compression(block.compression)) {
    fail(file, record.offset, "chunk compression " + quoted(block.compression) +
                                  " is not supported: expected none, bz2 or lz4");
  }
  // A compressed chunk is decompressed whole: refuse to allocate more than 1 GiB for one, as the
  // MCAP reader does (rosbag writes chunks of 768 KiB by default).
  if (block.compressed() && block.size > (std::uint64_t{1} << 30)) {
    fail(file, record.offset, block.compression + " chunk: its size field says " + std::to_string(block.size) +
                                  " bytes uncompressed, more than the 1 GiB cairn decompresses at once");
  }
  if (!block.compressed() && block.size != block.data_bytes) {
    fail(file, record.offset, "uncompressed chunk: its size field says " + std::to_string(block.size) +
                                  " bytes, its data_len " + std::to_string(block.data_bytes));
  }
  return block;
}

// ---------------------------------------------------------------------------------------------
// "Chunk": compression none, bz2 (libbz2) or lz4 (roslz4 writes the LZ4 frame format).

/// Room for a decoder's output, grown on demand up to one byte more than the chunk's size field
/// (so an overrun shows), so that a size field that lies costs only what the data really expands to.
class OutputBuffer {
 public:
  /// `recycled`: memory to reuse (its contents are overwritten), or empty.
  OutputBuffer(std::uint64_t limit, std::uint64_t input_bytes, Bytes recycled = {})
      : limit_(limit), bytes_(std::move(recycled)) {
    bytes_.resize(static_cast<std::size_t>(std::min(limit + 1, std::max<std::uint64_t>(4 * input_bytes, 1 << 16))));
  }
  /// Makes room for more output; false once the output exceeds the limit.
  bool grow() {
    if (produced_ > limit_) return false;
    if (produced_ == bytes_.size()) {
      bytes_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(limit_ + 1, 2 * std::uint64_t{bytes_.size()})));
    }
    return true;
  }
  std::uint8_t* free_begin() { return bytes_.data() + produced_; }
  std::size_t free_bytes() const { return bytes_.size() - produced_; }
  void advance(std::size_t bytes) { produced_ += bytes; }
  std::size_t produced() const { return produced_; }
  Bytes take() {
    bytes_.resize(produced_);
    return std::move(bytes_);
  }

 private:
  std::uint64_t limit_;
  Bytes bytes_;
  std::size_t produced_ = 0;
};

struct ChunkSite {
  std::string_view file;
  const Block& block;
  [[noreturn]] void fail_here(const std::string& detail) const {
    fail(file, block.record_offset, block.compression + " chunk: " + detail);
  }
  /// "Chunk": size is the length of the decompressed data.
  void check_size(std::uint64_t produced) const {
    if (produced > block.size) {
      fail_here("its data decompresses to more than the " + std::to_string(block.size) + " bytes its size field gives");
    }
    if (produced < block.size) {
      fail_here("its data decompresses to " + std::to_string(produced) + " bytes, its size field says " +
                std::to_string(block.size));
    }
  }
};

Bytes decompress_bz2(ByteView input, const ChunkSite& site, Bytes recycled) {
  bz_stream stream{};
  if (BZ2_bzDecompressInit(&stream, 0, 0) != BZ_OK) site.fail_here("libbz2 cannot start a decoder");
  struct End {
    bz_stream* stream;
    ~End() { BZ2_bzDecompressEnd(stream); }
  } end{&stream};
  stream.next_in = const_cast<char*>(reinterpret_cast<const char*>(input.data()));
  stream.avail_in = static_cast<unsigned int>(input.size());  // data_len is a uint32
  OutputBuffer out(site.block.size, input.size(), std::move(recycled));
  for (;;) {
    if (!out.grow()) break;
    const auto room = static_cast<unsigned int>(std::min<std::size_t>(out.free_bytes(), UINT_MAX));
    stream.next_out = reinterpret_cast<char*>(out.free_begin());
    stream.avail_out = room;
    const unsigned int input_before = stream.avail_in;
    const int status = BZ2_bzDecompress(&stream);
    out.advance(room - stream.avail_out);
    if (status == BZ_STREAM_END) break;
    if (status != BZ_OK) site.fail_here("corrupt bz2 data (libbz2 error " + std::to_string(status) + ")");
    if (stream.avail_in == input_before && stream.avail_out == room) site.fail_here("the bz2 stream ends early");
  }
  site.check_size(out.produced());
  if (stream.avail_in != 0) site.fail_here(std::to_string(stream.avail_in) + " bytes follow the end of the bz2 stream");
  return out.take();
}

Bytes decompress_lz4(ByteView input, const ChunkSite& site, Bytes recycled) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) site.fail_here("liblz4 cannot start a decoder");
  struct Free {
    LZ4F_dctx* context;
    ~Free() { LZ4F_freeDecompressionContext(context); }
  } free_context{context};
  OutputBuffer out(site.block.size, input.size(), std::move(recycled));
  std::size_t consumed = 0;
  std::size_t frame_left = 1;  // LZ4F_decompress returns 0 once the frame is complete
  while (frame_left != 0 && out.grow()) {
    std::size_t out_bytes = out.free_bytes();
    std::size_t in_bytes = input.size() - consumed;
    frame_left = LZ4F_decompress(context, out.free_begin(), &out_bytes, input.data() + consumed, &in_bytes, nullptr);
    if (LZ4F_isError(frame_left)) site.fail_here(std::string("corrupt lz4 data (") + LZ4F_getErrorName(frame_left) + ")");
    consumed += in_bytes;
    out.advance(out_bytes);
    if (frame_left != 0 && in_bytes == 0 && out_bytes == 0) site.fail_here("the lz4 frame ends early");
  }
  site.check_size(out.produced());
  if (consumed != input.size()) site.fail_here(std::to_string(input.size() - consumed) + " bytes follow the lz4 frame");
  return out.take();
}

/// The block's data, decompressed; its length is the chunk's size field.
/// The chunk's records. `stored` is consumed; `recycled` (memory to reuse for the output of a
/// compressed chunk) may be empty; `spent` receives the input buffer of a compressed chunk for reuse.
Bytes decompress(const Block& block, Bytes stored, std::string_view file, Bytes recycled = {}, Bytes* spent = nullptr) {
  const ChunkSite site{file, block};
  if (block.compressed()) {
    Bytes out = block.compression == "bz2" ? decompress_bz2(stored, site, std::move(recycled))
                                           : decompress_lz4(stored, site, std::move(recycled));
    if (spent != nullptr) *spent = std::move(stored);
    return out;
  }
  site.check_size(stored.size());
  return stored;
}

// ---------------------------------------------------------------------------------------------
// The records inside a block: "Connection" and "Message data".

/// "Connection" (op 0x07): header conn, topic; data: the connection header (topic, type, md5sum,
/// message_definition, and optionally callerid, latching) in the same name=value form.
Connection parse_connection(const RecordFields& fields, ByteView data, std::uint64_t data_offset,
                            std::string_view file) {
  Connection connection;
  connection.id = fields.u32("conn");
  connection.topic = fields.text("topic");
  RecordFields header;
  header.parse(data, data_offset, file, data_offset, "connection header");
  connection.type = header.text("type");
  connection.md5sum = header.text("md5sum");
  connection.definition = header.text("message_definition");
  connection.encoding = "ros1";
  connection.definition_encoding = "ros1msg";
  return connection;
}

/// One "Message data" record (op 0x02: header conn, time; data: the serialised message).
struct RawMessage {
  std::int64_t time_ns = 0;
  std::uint32_t connection_id = 0;
  std::size_t connection = 0;       ///< index into the container's connections (set when streamed)
  std::uint64_t position = 0;       ///< of the record in the block's data
  std::uint64_t data_position = 0;  ///< of the serialised message in the block's data
  std::uint64_t data_bytes = 0;
};

struct BlockRecords {
  std::vector<Connection> connections;
  std::vector<RawMessage> messages;  ///< in file order
};

BlockRecords walk_block(const Block& block, ByteView data, std::string_view file, bool with_connections) {
  BlockRecords records;
  RecordWalker walker(data, file, block.compressed() ? 0 : block.data_offset);
  while (walker.next()) {
    if (walker.op() == static_cast<std::uint8_t>(Op::message_data)) {
      records.messages.push_back({walker.fields().time_ns("time"), walker.fields().u32("conn"), 0, walker.position(),
                                  walker.data_position(), walker.data().size()});
    } else if (walker.op() == static_cast<std::uint8_t>(Op::connection) && with_connections) {
      records.connections.push_back(parse_connection(walker.fields(), walker.data(), walker.data_offset(), file));
    }  // rosbag's reindex skips records of other ops in a chunk, and so do we
  }
  return records;
}

/// The connection and message data records of a block's (decompressed) data. Errors inside a
/// compressed chunk name the chunk and the offset in its decompressed data.
BlockRecords parse_block_records(const Block& block, ByteView data, std::string_view file, bool with_connections) {
  if (!block.compressed()) return walk_block(block, data, file, with_connections);
  try {
    return walk_block(block, data, file, with_connections);
  } catch (const io::ParseError& error) {
    fail(file, block.record_offset, "in this " + block.compression + " chunk, at decompressed " + error.detail());
  }
}

// ---------------------------------------------------------------------------------------------
// What opening learns.

/// The immutable description of an open bag that its streams share.
struct BagLayout {
  std::string path;
  std::vector<Connection> connections;               ///< by connection id
  std::map<std::uint32_t, std::size_t> index_of;     ///< connection id -> index in connections
  std::vector<Block> blocks;                         ///< by (start_ns, record_offset)
  ContainerSummary summary;
};

/// Connections, statistics and blocks by connection id, as the index or the scan finds them.
struct LayoutBuilder {
  std::map<std::uint32_t, Connection> connections;
  std::map<std::uint32_t, ConnectionStatistics> statistics;
  std::map<std::uint32_t, std::uint64_t> first_use;  ///< connection id -> offset of a message using it
  std::vector<Block> blocks;
  ContainerSummary summary;
  std::uint64_t index_length_disagreements = 0;
  std::uint64_t skipped_records = 0;

  /// Connections appear in chunks and again in the index section: the first record of an id wins.
  void add_connection(Connection connection) { connections.try_emplace(connection.id, std::move(connection)); }
  void count(std::uint32_t connection_id, std::int64_t time_ns, std::uint64_t offset) {
    ConnectionStatistics& statistics_of = statistics[connection_id];
    if (statistics_of.messages == 0) statistics_of.first_ns = statistics_of.last_ns = time_ns;
    statistics_of.first_ns = std::min(statistics_of.first_ns, time_ns);
    statistics_of.last_ns = std::max(statistics_of.last_ns, time_ns);
    ++statistics_of.messages;
    first_use.try_emplace(connection_id, offset);
  }
};

void add_repair_notes(const LayoutBuilder& builder, ContainerSummary* summary) {
  if (builder.index_length_disagreements > 0) {
    summary->notes.push_back("index data records: data_len disagrees with count x 12 bytes in " +
                             std::to_string(builder.index_length_disagreements) +
                             " records (an old rosbag bug): count trusted, as rosbag's reader does");
  }
  if (builder.skipped_records > 0) {
    summary->notes.push_back(std::to_string(builder.skipped_records) + " records of unknown op skipped");
  }
}

std::shared_ptr<const BagLayout> finish_layout(LayoutBuilder builder, const BagFile& file) {
  for (const auto& [id, offset] : builder.first_use) {
    if (builder.connections.count(id) == 0) {
      fail(file.path(), offset, "a message data record refers to connection " + std::to_string(id) +
                                    ", which no connection record declares");
    }
  }
  auto layout = std::make_shared<BagLayout>();
  layout->path = file.path();
  layout->summary = std::move(builder.summary);
  layout->summary.format = "ROS 1 bag 2.0";
  layout->summary.file_bytes = file.size();
  for (auto& [id, connection] : builder.connections) {
    layout->index_of[id] = layout->connections.size();
    layout->connections.push_back(std::move(connection));
    layout->summary.connections.push_back(builder.statistics[id]);
  }
  add_repair_notes(builder, &layout->summary);
  layout->blocks = std::move(builder.blocks);
  std::sort(layout->blocks.begin(), layout->blocks.end(), [](const Block& a, const Block& b) {
    return std::tie(a.start_ns, a.record_offset) < std::tie(b.start_ns, b.record_offset);
  });
  return layout;
}

// ---------------------------------------------------------------------------------------------
// "Bag header" and the index: "Connection" and "Chunk info" records at index_pos, "Index data"
// records after each chunk.

struct BagHeader {
  std::uint64_t index_pos = 0;
  std::uint32_t conn_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t first_record = 0;  ///< offset of the record after the bag header
};

void check_version_line(BagFile& file) {
  if (file.size() == 0) {
    throw io::ParseError(file.path(), 0, "empty file: expected a ROS 1 bag, which starts with \"#ROSBAG V2.0\\n\"");
  }
  const Bytes start = file.read(0, std::min<std::uint64_t>(file.size(), 32), "version line");
  const std::string_view text = as_text(start);
  if (text.starts_with(kVersionLine)) return;
  if (text.starts_with(kFormat12Line)) {
    fail(file.path(), 0, "ROS bag format 1.2 (\"#ROSRECORD V1.2\"): cairn reads format 2.0 only; convert it with "
                         "`rosbag reindex BAG` (ROS 1), which rewrites a 1.2 bag as 2.0 and keeps the original as "
                         "BAG.orig.bag");
  }
  if (text.starts_with(kAnyVersionPrefix) || text.starts_with(kOldRecordPrefix)) {
    fail(file.path(), 0, "unsupported ROS bag version " + quoted(text.substr(0, text.find('\n'))) +
                             ": cairn reads format 2.0 (\"#ROSBAG V2.0\")");
  }
  fail(file.path(), 0, "expected \"#ROSBAG V2.0\\n\" (a ROS 1 bag), found " + quoted(text.substr(0, kVersionLine.size())));
}

/// "Bag header" (op 0x03): index_pos, conn_count, chunk_count; its data is padding.
BagHeader read_bag_header(BagFile& file) {
  const std::uint64_t offset = kVersionLine.size();
  const FileRecord record = read_record(file, offset, Op::bag_header, "bag header record");
  // rosbag 1.14+ may name an encryptor plugin here; rosbag/NoEncryptor writes chunks in the clear.
  const Field* encryptor = record.fields.find("encryptor");
  if (encryptor != nullptr && !encryptor->value.empty() && as_text(encryptor->value) != "rosbag/NoEncryptor") {
    fail(file.path(), offset, "encrypted bag (encryptor " + quoted(as_text(encryptor->value)) +
                                  "): cairn cannot decrypt it; `rosbag decrypt` (ROS 1) writes a plain copy");
  }
  if (!file.fits(record.data_offset, record.data_len)) {
    fail(file.path(), offset, "the file ends inside the bag header record's padding");
  }
  return {record.fields.u64("index_pos"), record.fields.u32("conn_count"), record.fields.u32("chunk_count"),
          record.data_end()};
}

/// Why the bag header's index_pos cannot lead to an index, or "" when it may.
std::string index_problem(const BagHeader& header, std::uint64_t file_bytes) {
  if (header.index_pos == 0) return "no index (index_pos is 0: the recording was not closed)";
  if (header.index_pos > file_bytes) {
    return "no index (index_pos " + std::to_string(header.index_pos) + " lies past the end of the " +
           std::to_string(file_bytes) + "-byte file: a truncated copy?)";
  }
  if (header.index_pos < header.first_record) {
    return "no index (index_pos " + std::to_string(header.index_pos) + " points inside the bag header)";
  }
  return "";
}

struct ChunkInfo {
  std::uint64_t record_offset = 0;
  std::uint64_t chunk_pos = 0;
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
  std::map<std::uint32_t, std::uint32_t> counts;  ///< messages per connection id
};

/// "Chunk info" (op 0x06): ver 1, chunk_pos, start_time, end_time, count; data: count pairs of
/// (conn, count).
ChunkInfo read_chunk_info(BagFile& file, const FileRecord& record) {
  if (const std::uint32_t version = record.fields.u32("ver"); version != 1) {
    fail(file.path(), record.offset, "chunk info version " + std::to_string(version) + ": expected 1");
  }
  ChunkInfo info{record.offset, record.fields.u64("chunk_pos"), record.fields.time_ns("start_time"),
                 record.fields.time_ns("end_time"), {}};
  const std::uint64_t entries = record.fields.u32("count");
  if (record.data_len != entries * kChunkInfoEntryBytes) {
    fail(file.path(), record.offset, "chunk info: expected " + std::to_string(entries) + " x 8 data bytes for count " +
                                         std::to_string(entries) + ", found data_len " + std::to_string(record.data_len));
  }
  if (info.start_ns > info.end_ns) {
    fail(file.path(), record.offset, "chunk info: start_time " + std::to_string(info.start_ns) + " ns is after end_time " +
                                         std::to_string(info.end_ns) + " ns");
  }
  const Bytes data = read_data(file, record);
  for (std::size_t i = 0; i < entries; ++i) {
    const std::uint32_t count = load_u32(data.data() + 8 * i + 4);
    if (count > 0) info.counts[load_u32(data.data() + 8 * i)] += count;
  }
  return info;
}

/// The index section at index_pos: conn_count connection records, then chunk_count chunk info
/// records ("Bag header"). Throws when they are not there.
std::vector<ChunkInfo> read_index_section(BagFile& file, const BagHeader& header, LayoutBuilder& builder) {
  std::uint64_t offset = header.index_pos;
  for (std::uint32_t i = 0; i < header.conn_count; ++i) {
    const FileRecord record = read_record(file, offset, Op::connection, "connection record");
    builder.add_connection(parse_connection(record.fields, read_data(file, record), record.data_offset, file.path()));
    offset = record.data_end();
  }
  std::vector<ChunkInfo> infos;
  for (std::uint32_t i = 0; i < header.chunk_count; ++i) {
    const FileRecord record = read_record(file, offset, Op::chunk_info, "chunk info record");
    infos.push_back(read_chunk_info(file, record));
    offset = record.data_end();
  }
  return infos;
}

/// "Index data" (op 0x04) version 1: ver, conn, count; data: count entries of 12 bytes. Old
/// rosbag versions wrote data_len = count x 20 over the same count x 12 bytes; rosbag's reader
/// reads count entries and ignores data_len, and so does this.
struct IndexData {
  std::uint32_t connection_id = 0;
  std::uint32_t count = 0;
  std::uint64_t entries_end = 0;
  bool length_disagrees = false;
};

IndexData index_data_extent(const FileRecord& record, std::string_view file) {
  if (const std::uint32_t version = record.fields.u32("ver"); version != 1) {
    fail(file, record.offset, "index data version " + std::to_string(version) + ": expected 1");
  }
  IndexData index{record.fields.u32("conn"), record.fields.u32("count"), 0, false};
  index.entries_end = record.data_offset + index.count * kIndexEntryBytes;
  index.length_disagrees = record.data_len != index.count * kIndexEntryBytes;
  return index;
}

/// The index data records after a chunk, one per connection in it, checked against its chunk
/// info; their times give each connection's exact first and last message.
void read_chunk_index_data(BagFile& file, const ChunkInfo& info, std::uint64_t offset, LayoutBuilder& builder) {
  std::set<std::uint32_t> seen;
  for (std::size_t i = 0; i < info.counts.size(); ++i) {
    const FileRecord record = read_record(file, offset, Op::index_data, "index data record");
    const IndexData index = index_data_extent(record, file.path());
    const auto listed = info.counts.find(index.connection_id);
    if (listed == info.counts.end() || listed->second != index.count || !seen.insert(index.connection_id).second) {
      fail(file.path(), record.offset, "index data for connection " + std::to_string(index.connection_id) + " lists " +
                                           std::to_string(index.count) + " messages; the chunk info at byte " +
                                           std::to_string(info.record_offset) + " says " +
                                           std::to_string(listed == info.counts.end() ? 0 : listed->second));
    }
    const Bytes entries = file.read(record.data_offset, index.count * kIndexEntryBytes, "index data entries");
    for (std::size_t entry = 0; entry < index.count; ++entry) {
      const std::int64_t time_ns = time_to_ns(entries.data() + kIndexEntryBytes * entry);
      if (time_ns < info.start_ns || time_ns > info.end_ns) {
        fail(file.path(), record.offset, "index data time " + std::to_string(time_ns) + " ns lies outside the range of the chunk info at byte " +
                                             std::to_string(info.record_offset));
      }
      builder.count(index.connection_id, time_ns, info.chunk_pos);
    }
    builder.index_length_disagreements += index.length_disagrees ? 1 : 0;
    offset = index.entries_end;
  }
}

/// The chunk each chunk info points at ("Chunk") and the index data after it. The index has been
/// read, so the file is whole: anything missing here is damage, not truncation.
void read_indexed_chunks(BagFile& file, const std::vector<ChunkInfo>& infos, LayoutBuilder& builder) {
  std::set<std::uint64_t> chunk_positions;
  for (const ChunkInfo& info : infos) {
    if (!chunk_positions.insert(info.chunk_pos).second) {
      fail(file.path(), info.record_offset, "a second chunk info for the chunk at byte " + std::to_string(info.chunk_pos));
    }
    const FileRecord record = read_record(file, info.chunk_pos, Op::chunk, "chunk record (from the chunk info at byte " +
                                                                               std::to_string(info.record_offset) + ")");
    if (!file.fits(record.data_offset, record.data_len)) {
      fail(file.path(), record.offset, "chunk of " + std::to_string(record.data_len) + " data bytes runs past the end of the file");
    }
    Block block = chunk_block(record, file.path());
    block.start_ns = info.start_ns;
    block.end_ns = info.end_ns;
    for (const auto& [id, count] : info.counts) {
      if (builder.connections.count(id) == 0) {
        fail(file.path(), info.record_offset, "the chunk info counts messages of connection " + std::to_string(id) +
                                                  ", which no connection record declares");
      }
      block.counts[id] = count;
    }
    read_chunk_index_data(file, info, record.data_end(), builder);
    ++builder.summary.chunks[block.compression];
    if (!block.counts.empty()) builder.blocks.push_back(std::move(block));
  }
}

// ---------------------------------------------------------------------------------------------
// Without an index: every record from the start, as `rosbag reindex` reads them.

class RecordScanner {
 public:
  RecordScanner(BagFile& file, LayoutBuilder& builder) : file_(file), builder_(builder) {}

  void run(std::uint64_t offset) {
    while (offset < file_.size()) {
      std::optional<FileRecord> record = try_read_record(file_, offset);
      const std::optional<std::uint64_t> next = record ? scan(*record) : truncated(offset);
      if (!next) break;
      offset = *next;  // always past the record's header: the scan ends
    }
    close_loose_run();
  }

 private:
  /// The offset of the next record, or std::nullopt when the scan stops.
  std::optional<std::uint64_t> scan(const FileRecord& record) {
    if (record.op != static_cast<std::uint8_t>(Op::message_data) && record.op != static_cast<std::uint8_t>(Op::connection)) {
      close_loose_run();
    }
    switch (static_cast<Op>(record.op)) {
      case Op::chunk: return scan_chunk(record);
      case Op::connection: return scan_connection(record);
      case Op::message_data: return scan_loose_message(record);
      case Op::index_data: return scan_index_data(record);
      case Op::chunk_info:
      case Op::bag_header: return skip(record);
    }
    ++builder_.skipped_records;
    return skip(record);
  }

  std::optional<std::uint64_t> truncated(std::uint64_t offset) {
    builder_.summary.notes.push_back("file ends inside a record at byte " + std::to_string(offset) + ": the rest is ignored");
    return std::nullopt;
  }
  bool whole(const FileRecord& record) const { return file_.fits(record.data_offset, record.data_len); }
  std::optional<std::uint64_t> skip(const FileRecord& record) {
    return whole(record) ? std::optional(record.data_end()) : truncated(record.offset);
  }

  std::optional<std::uint64_t> scan_chunk(const FileRecord& record) {
    if (record.data_len == 0) return unclosed_chunk(record);
    if (!whole(record)) return cut_chunk(record);
    Block block = chunk_block(record, file_.path());
    const Bytes data = decompress(block, read_data(file_, record), file_.path());
    BlockRecords records = parse_block_records(block, data, file_.path(), true);
    for (Connection& connection : records.connections) builder_.add_connection(std::move(connection));
    for (const RawMessage& message : records.messages) {
      block.add(message.connection_id, message.time_ns);
      builder_.count(message.connection_id, message.time_ns, block.message_offset(message.position));
    }
    ++builder_.summary.chunks[block.compression];
    if (!block.counts.empty()) builder_.blocks.push_back(std::move(block));
    return record.data_end();
  }

  /// A chunk header with data_len 0: rosbag was still writing the chunk when it stopped.
  std::optional<std::uint64_t> unclosed_chunk(const FileRecord& record) {
    const std::string compression = record.fields.text("compression");
    const std::string where = "the chunk at byte " + std::to_string(record.offset) + " was never closed (data_len 0)";
    if (compression == "none") {
      builder_.summary.notes.push_back(where + ": the records after its header are read one by one");
      return record.data_offset;
    }
    builder_.summary.notes.push_back(where + " and its " + compression + " data cannot be delimited: the rest is ignored");
    return std::nullopt;
  }

  /// A chunk the end of the file cuts: an uncompressed one still holds whole records.
  std::optional<std::uint64_t> cut_chunk(const FileRecord& record) {
    if (record.fields.text("compression") != "none") return truncated(record.offset);
    builder_.summary.notes.push_back("the file ends inside the uncompressed chunk at byte " + std::to_string(record.offset) +
                                     ": its whole records are read one by one");
    return record.data_offset;
  }

  std::optional<std::uint64_t> scan_connection(const FileRecord& record) {
    if (!whole(record)) return truncated(record.offset);
    builder_.add_connection(parse_connection(record.fields, read_data(file_, record), record.data_offset, file_.path()));
    return record.data_end();
  }

  /// A message data record outside any chunk: joins the current run (connection records may sit
  /// between its messages), which becomes an uncompressed block.
  std::optional<std::uint64_t> scan_loose_message(const FileRecord& record) {
    if (!whole(record)) return truncated(record.offset);
    const std::uint32_t connection_id = record.fields.u32("conn");
    const std::int64_t time_ns = record.fields.time_ns("time");
    if (loose_open_ && loose_.data_bytes >= kLooseBlockBytes) close_loose_run();
    if (!loose_open_) {
      loose_ = Block{};
      loose_.record_offset = loose_.data_offset = record.offset;
      loose_open_ = true;
    }
    loose_.data_bytes = loose_.size = record.data_end() - loose_.data_offset;
    loose_.add(connection_id, time_ns);
    builder_.count(connection_id, time_ns, record.offset);
    return record.data_end();
  }
  void close_loose_run() {
    if (loose_open_) builder_.blocks.push_back(std::move(loose_));
    loose_open_ = false;
  }

  std::optional<std::uint64_t> scan_index_data(const FileRecord& record) {
    const IndexData index = index_data_extent(record, file_.path());
    if (index.entries_end > file_.size()) return truncated(record.offset);
    builder_.index_length_disagreements += index.length_disagrees ? 1 : 0;
    return index.entries_end;
  }

  BagFile& file_;
  LayoutBuilder& builder_;
  Block loose_;  ///< the current run of loose message data records, when loose_open_
  bool loose_open_ = false;
};

LayoutBuilder read_layout(BagFile& file, const BagHeader& header) {
  std::string problem = index_problem(header, file.size());
  if (problem.empty()) {
    LayoutBuilder builder;
    std::optional<std::vector<ChunkInfo>> infos;
    try {
      infos = read_index_section(file, header, builder);
    } catch (const io::ParseError& error) {
      problem = "the index at byte " + std::to_string(header.index_pos) + " cannot be read (" + error.detail() + ")";
    }
    if (infos) {
      read_indexed_chunks(file, *infos, builder);
      builder.summary.indexed = true;
      return builder;
    }
  }
  LayoutBuilder builder;
  builder.summary.notes.push_back(problem + ": records scanned from the start, as `rosbag reindex` would");
  RecordScanner(file, builder).run(header.first_record);
  return builder;
}

// ---------------------------------------------------------------------------------------------
// Streaming in log-time order.

/// A block decompressed, its wanted messages sorted by (time, position): records within a chunk
/// are in the order they were written, which need not be time order.
struct OpenBlock {
  const Block* block = nullptr;
  std::shared_ptr<Bytes> data;  ///< shared with the messages handed out (Message::owner)
  std::vector<RawMessage> messages;
  std::size_t next = 0;
};

/// Checks a block's messages against what the index or scan said of it (connections declared,
/// times within the chunk's range, counts), and sets their connection indices.
void check_block_messages(const BagLayout& layout, const Block& block, std::vector<RawMessage>& messages) {
  std::map<std::uint32_t, std::uint64_t> counts;
  for (RawMessage& message : messages) {
    const auto index = layout.index_of.find(message.connection_id);
    const std::uint64_t offset = block.message_offset(message.position);
    if (index == layout.index_of.end()) {
      fail(layout.path, offset, "a message data record refers to connection " + std::to_string(message.connection_id) +
                                    ", which no connection record declares");
    }
    if (message.time_ns < block.start_ns || message.time_ns > block.end_ns) {
      fail(layout.path, offset, "message time " + std::to_string(message.time_ns) + " ns lies outside its chunk's range [" +
                                    std::to_string(block.start_ns) + ", " + std::to_string(block.end_ns) + "] from the chunk info");
    }
    message.connection = index->second;
    ++counts[message.connection_id];
  }
  if (counts != block.counts) {
    fail(layout.path, block.record_offset, "the chunk holds " + std::to_string(messages.size()) +
                                               " messages, not those its chunk info counts per connection");
  }
}

/// Buffers of emptied blocks, reused for the next loads once nothing refers to them (the caller's
/// last Message and decoded values may for a while): a chunk's memory is then reused instead of
/// faulted in afresh and zeroed, the costs that dominated reading. At most kSpares are kept.
class BufferPool {
 public:
  void give(std::shared_ptr<Bytes> buffer) {
    if (buffer && spares_.size() < kSpares) spares_.push_back(std::move(buffer));
  }
  /// A buffer nothing else refers to (its contents are garbage), or an empty one.
  Bytes take() {
    for (auto it = spares_.begin(); it != spares_.end(); ++it) {
      if (it->use_count() == 1) {
        Bytes bytes = std::move(**it);
        spares_.erase(it);
        return bytes;
      }
    }
    return {};
  }

 private:
  static constexpr std::size_t kSpares = 4;
  std::vector<std::shared_ptr<Bytes>> spares_;
};

/// Reads and checks a block, with buffers from `pool` (the input of a compressed chunk goes back).
OpenBlock load_block(BagFile& file, const BagLayout& layout, const Block& block, const std::vector<bool>& wanted,
                     BufferPool& pool) {
  OpenBlock open;
  open.block = &block;
  Bytes stored = pool.take();
  file.read_into(block.data_offset, block.data_bytes, "chunk data", &stored);
  Bytes spent;
  open.data = std::make_shared<Bytes>(
      decompress(block, std::move(stored), file.path(), block.compressed() ? pool.take() : Bytes{}, &spent));
  if (!spent.empty()) pool.give(std::make_shared<Bytes>(std::move(spent)));
  std::vector<RawMessage> messages = parse_block_records(block, *open.data, file.path(), false).messages;
  check_block_messages(layout, block, messages);
  for (const RawMessage& message : messages) {
    if (wanted.empty() || wanted[message.connection]) open.messages.push_back(message);
  }
  std::stable_sort(open.messages.begin(), open.messages.end(),
                   [](const RawMessage& a, const RawMessage& b) { return a.time_ns < b.time_ns; });
  return open;
}

/// Merges the open blocks' sorted messages. Blocks open in order of their first message time: the
/// next one opens once the smallest pending message is not earlier than its start, so every message
/// that could come first is pending, and only blocks overlapping in time are in memory together.
class Ros1MessageStream final : public MessageStream {
 public:
  Ros1MessageStream(std::shared_ptr<const BagLayout> layout, std::vector<bool> wanted)
      : layout_(std::move(layout)), file_(layout_->path), wanted_(std::move(wanted)) {
    for (std::size_t i = 0; i < layout_->blocks.size(); ++i) {
      if (has_wanted(layout_->blocks[i])) pending_.push_back(i);
    }
  }

  bool next(Message* message) override {
    recycle_retired();  // the previous message's data stays valid until this call
    while (next_pending_ < pending_.size() &&
           (heads_.empty() || layout_->blocks[pending_[next_pending_]].start_ns <= heads_.top().time_ns)) {
      open(layout_->blocks[pending_[next_pending_++]]);
    }
    if (heads_.empty()) return false;
    const Head head = heads_.top();
    heads_.pop();
    OpenBlock& block = *head.block;
    const RawMessage& raw = block.messages[block.next++];
    message->connection = raw.connection;
    message->log_time_ns = raw.time_ns;
    message->owner = block.data;
    message->data = ByteView(*block.data).subspan(static_cast<std::size_t>(raw.data_position),
                                                 static_cast<std::size_t>(raw.data_bytes));
    message->file_offset = block.block->message_offset(raw.position);
    if (block.next < block.messages.size()) {
      push_head(head.block);
    } else {
      retired_.splice(retired_.end(), open_, head.block);
    }
    return true;
  }

 private:
  struct Head {
    std::int64_t time_ns;
    std::uint64_t record_offset;
    std::uint64_t position;
    std::list<OpenBlock>::iterator block;
  };
  struct Later {
    bool operator()(const Head& a, const Head& b) const {
      return std::tie(a.time_ns, a.record_offset, a.position) > std::tie(b.time_ns, b.record_offset, b.position);
    }
  };

  bool has_wanted(const Block& block) const {
    if (wanted_.empty()) return true;
    return std::any_of(block.counts.begin(), block.counts.end(),
                       [&](const auto& count) { return wanted_[layout_->index_of.at(count.first)]; });
  }
  void open(const Block& block) {
    OpenBlock loaded = load_block(file_, *layout_, block, wanted_, pool_);
    if (loaded.messages.empty()) return;
    open_.push_back(std::move(loaded));
    push_head(std::prev(open_.end()));
  }
  void push_head(std::list<OpenBlock>::iterator block) {
    const RawMessage& raw = block->messages[block->next];
    heads_.push({raw.time_ns, block->block->record_offset, raw.position, block});
  }

  std::shared_ptr<const BagLayout> layout_;
  BagFile file_;
  std::vector<bool> wanted_;
  std::vector<std::size_t> pending_;  ///< blocks with wanted messages, by (start_ns, record_offset)
  std::size_t next_pending_ = 0;
  std::list<OpenBlock> open_;
  std::list<OpenBlock> retired_;  ///< emptied blocks, freed on the next call
  BufferPool pool_;

  void recycle_retired() {
    for (OpenBlock& block : retired_) pool_.give(std::move(block.data));
    retired_.clear();
  }
  std::priority_queue<Head, std::vector<Head>, Later> heads_;  ///< each open block's next message
};

class Ros1Bag final : public Container {
 public:
  explicit Ros1Bag(std::shared_ptr<const BagLayout> layout) : layout_(std::move(layout)) {}
  const std::string& path() const override { return layout_->path; }
  const std::vector<Connection>& connections() const override { return layout_->connections; }
  const ContainerSummary& summary() const override { return layout_->summary; }
  std::unique_ptr<MessageStream> messages(const std::vector<bool>& wanted) override {
    CAIRN_ASSERT(wanted.empty() || wanted.size() == layout_->connections.size(),
                 "messages(wanted): `wanted` must be empty or hold one flag per connection");
    return std::make_unique<Ros1MessageStream>(layout_, wanted);
  }

 private:
  std::shared_ptr<const BagLayout> layout_;
};

}  // namespace

std::unique_ptr<Container> open_ros1_bag(const std::string& path) {
  if (path == "-") throw io::ParseError(path, 0, "a ROS bag needs random access: it cannot be read from standard input");
  io::check_input_file(path, "a ROS bag file");
  BagFile file(path);
  check_version_line(file);
  const BagHeader header = read_bag_header(file);
  return std::make_unique<Ros1Bag>(finish_layout(read_layout(file, header), file));
}

bool looks_like_ros1_bag(std::span<const std::uint8_t> first_bytes) {
  const std::string_view text = as_text(first_bytes);
  return text.starts_with(kAnyVersionPrefix) || text.starts_with(kOldRecordPrefix);
}

}  // namespace cairn::bag
