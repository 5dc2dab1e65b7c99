// Hostile inputs for the bag containers (bag/ros1_bag.hpp, bag/mcap_reader.hpp, bag/sqlite_bag.hpp)
// and the deserialisers behind them, with exact expectations. The inputs are copies of the shared
// bags (../shared/data/bags) in a scratch folder, cut short or with one field rewritten by hand;
// the expected values come from those files, read here by small walkers written from the
// specifications (wiki.ros.org/Bags/Format/2.0 "Records"; mcap.dev/spec "Records", "Chunk",
// "Footer"), from bags/SOURCE.txt and from metadata.yaml, never from the code under test. Every
// error must name the file and the byte offset or the field it concerns. The fuzz targets
// fuzz/fuzz_{ros1_bag,mcap,rosbag2_sqlite,cdr}.cpp cover the same readers with random input.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/deserialize.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/message_schema.hpp"
#include "cairn/bag/ros1_bag.hpp"
#include "cairn/bag/sqlite_bag.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::bag {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Files and errors.

/// A scratch folder removed at the end of the test.
struct Scratch {
  fs::path path;
  Scratch() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path = fs::temp_directory_path() /
           ("cairn_test_containers_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Scratch() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
};

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::string write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path.string();
}

std::string shared_bytes(const std::string& relative) { return read_bytes(test::data_path(relative)); }

/// what() of the io::ParseError `action` throws; a test failure when it throws nothing or another type.
std::string parse_error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const io::ParseError& error) {
    return error.what();
  } catch (const std::exception& other) {
    ADD_FAILURE() << "expected io::ParseError, got another exception: " << other.what();
    return "";
  }
  ADD_FAILURE() << "expected io::ParseError, nothing was thrown";
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// True when `text` says "byte N" for exactly this N (not a longer number starting with it).
bool names_byte(const std::string& text, std::uint64_t offset) {
  return std::regex_search(text, std::regex("byte " + std::to_string(offset) + "([^0-9]|$)"));
}
/// True when `text` says "message byte N" (an offset inside a message's bytes) for exactly this N.
bool names_message_byte(const std::string& text, std::uint64_t offset) {
  return std::regex_search(text, std::regex("message byte " + std::to_string(offset) + "([^0-9]|$)"));
}

std::uint32_t u32_at(const std::string& bytes, std::size_t at) {
  std::uint32_t value = 0;
  std::memcpy(&value, bytes.data() + at, sizeof value);  // little-endian hosts, as the formats
  return value;
}
std::uint64_t u64_at(const std::string& bytes, std::size_t at) {
  std::uint64_t value = 0;
  std::memcpy(&value, bytes.data() + at, sizeof value);
  return value;
}
void put_u16(std::string& bytes, std::size_t at, std::uint16_t value) { std::memcpy(bytes.data() + at, &value, sizeof value); }
void put_u32(std::string& bytes, std::size_t at, std::uint32_t value) { std::memcpy(bytes.data() + at, &value, sizeof value); }
void put_u64(std::string& bytes, std::size_t at, std::uint64_t value) { std::memcpy(bytes.data() + at, &value, sizeof value); }

// ---------------------------------------------------------------------------------------------
// What a bag streams: topic, log time, bytes of every message, in stream order.

struct Streamed {
  std::string topic;
  std::int64_t time_ns = 0;
  std::string data;
  bool operator==(const Streamed&) const = default;
};

std::vector<Streamed> stream_all(Bag& bag) {
  std::vector<Streamed> out;
  const auto stream = bag.read();
  BagMessage message;
  while (stream->next(&message)) {
    const auto& data = message.message.data;
    out.push_back({bag.topics()[message.topic].name, message.message.log_time_ns,
                   std::string(reinterpret_cast<const char*>(data.data()), data.size())});
  }
  return out;
}

bool time_sorted(const std::vector<Streamed>& messages) {
  return std::is_sorted(messages.begin(), messages.end(),
                        [](const Streamed& a, const Streamed& b) { return a.time_ns < b.time_ns; });
}

bool any_note(const Bag& bag, const std::function<bool(const std::string&)>& says) {
  const auto& notes = bag.files().front()->summary().notes;
  return std::any_of(notes.begin(), notes.end(), says);
}
bool any_note(const Bag& bag, const std::string& part) {
  return any_note(bag, [&](const std::string& note) { return contains(note, part); });
}
bool any_note_names_byte(const Bag& bag, std::uint64_t offset) {
  return any_note(bag, [&](const std::string& note) { return names_byte(note, offset); });
}

// ---------------------------------------------------------------------------------------------
// ROS 1 bag 2.0, read here from the spec: "#ROSBAG V2.0\n", then records of <header_len><header>
// <data_len><data>, the header being fields <field_len><name>=<value>.

constexpr std::size_t kRos1VersionLineBytes = 13;

struct Ros1Record {
  std::size_t offset = 0;
  std::map<std::string, std::string> fields;
  std::size_t field_value_offset(const std::string& name) const { return value_offsets.at(name); }
  std::map<std::string, std::size_t> value_offsets;  ///< absolute offset of each field's value
  std::size_t data_offset = 0;
  std::size_t data_len = 0;
  bool whole = false;  ///< its data lies before the end given
  std::size_t end() const { return data_offset + data_len; }
  int op() const { return fields.count("op") != 0 ? static_cast<unsigned char>(fields.at("op")[0]) : -1; }
  std::int64_t time_ns() const {  // "time": uint32 sec, uint32 nsec
    const std::string& t = fields.at("time");
    return static_cast<std::int64_t>(u32_at(t, 0)) * 1'000'000'000 + u32_at(t, 4);
  }
};

/// The record at `at` whose header lies before `end`, or nullopt.
std::optional<Ros1Record> ros1_record(const std::string& bytes, std::size_t at, std::size_t end) {
  if (at + 4 > end) return std::nullopt;
  const std::size_t header_len = u32_at(bytes, at);
  if (at + 8 + header_len > end) return std::nullopt;
  Ros1Record record;
  record.offset = at;
  for (std::size_t p = at + 4; p < at + 4 + header_len;) {
    const std::size_t length = u32_at(bytes, p);
    const std::string field = bytes.substr(p + 4, length);
    const std::size_t equals = field.find('=');
    record.fields[field.substr(0, equals)] = field.substr(equals + 1);
    record.value_offsets[field.substr(0, equals)] = p + 4 + equals + 1;
    p += 4 + length;
  }
  record.data_len = u32_at(bytes, at + 4 + header_len);
  record.data_offset = at + 8 + header_len;
  record.whole = record.end() <= end;
  return record;
}

/// The top-level records from the bag header on, up to the first one that is not whole (for bags
/// whose index data records give their true data_len).
std::vector<Ros1Record> ros1_top_records(const std::string& bytes) {
  std::vector<Ros1Record> records;
  std::size_t at = kRos1VersionLineBytes;
  while (auto record = ros1_record(bytes, at, bytes.size())) {
    records.push_back(*record);
    if (!record->whole) break;
    at = record->end();
  }
  return records;
}

/// conn field -> topic, from the connection records seen so far.
using Ros1Topics = std::map<std::string, std::string>;

/// The message data records of the uncompressed chunk `chunk` that lie whole in `bytes`, with
/// their topics (connection records: this chunk's and those in `topic_of_conn`, which gets this
/// chunk's), in file order; `first_cut` gets the offset of the record the end of the bytes cuts (0
/// when none).
std::vector<Streamed> ros1_chunk_messages(const std::string& bytes, const Ros1Record& chunk, Ros1Topics& topic_of_conn,
                                          std::size_t* first_cut) {
  std::vector<Streamed> messages;
  const std::size_t end = std::min(chunk.end(), bytes.size());
  std::size_t at = chunk.data_offset;
  *first_cut = 0;
  while (at < end) {
    const auto record = ros1_record(bytes, at, end);
    if (!record || !record->whole) {
      *first_cut = at;
      break;
    }
    if (record->op() == 0x07) topic_of_conn[record->fields.at("conn")] = record->fields.at("topic");
    if (record->op() == 0x02) {
      messages.push_back({topic_of_conn.at(record->fields.at("conn")), record->time_ns(),
                          bytes.substr(record->data_offset, record->data_len)});
    }
    at = record->end();
  }
  return messages;
}

std::vector<Streamed> sorted_by_time(std::vector<Streamed> messages) {
  std::stable_sort(messages.begin(), messages.end(),
                   [](const Streamed& a, const Streamed& b) { return a.time_ns < b.time_ns; });
  return messages;
}

/// The first chunk record (op 0x05) of a bag.
Ros1Record first_chunk(const std::string& bytes) {
  for (const Ros1Record& record : ros1_top_records(bytes)) {
    if (record.op() == 0x05) return record;
  }
  ADD_FAILURE() << "no chunk record";
  return {};
}

TEST(Ros1Hostile, EmptyFileIsRefusedNamingTheFile) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/empty-file.bag");
  Scratch scratch;
  const std::string path = write_bytes(scratch.path / "empty.bag", shared_bytes("bags/rosbag_js/empty-file.bag"));
  const std::string what = parse_error_of([&] { Bag::open(path); });
  EXPECT_NE(what.find(path), std::string::npos) << what;
  EXPECT_NE(what.find("empty file"), std::string::npos) << what;
  const std::string direct = parse_error_of([&] { open_ros1_bag(path); });
  EXPECT_NE(direct.find(path), std::string::npos) << direct;
  EXPECT_NE(direct.find("#ROSBAG V2.0"), std::string::npos) << direct;
}

TEST(Ros1Hostile, Format12IsRefusedNamingTheFormatAndTheConversion) {
  Scratch scratch;
  const std::string path = write_bytes(scratch.path / "old.bag", "#ROSRECORD V1.2\n" + std::string(64, '\0'));
  const std::string what = parse_error_of([&] { Bag::open(path); });
  EXPECT_NE(what.find(path + ":"), std::string::npos) << what;
  EXPECT_TRUE(names_byte(what, 0)) << what;
  EXPECT_NE(what.find("1.2"), std::string::npos) << what;
  EXPECT_NE(what.find("rosbag reindex"), std::string::npos) << what;
}

TEST(Ros1Hostile, BagCutAtHalfIsScannedAndStreamsItsWholeMessagesSorted) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example.bag");
  Scratch scratch;
  const std::string full = shared_bytes("bags/rosbag_js/example.bag");
  const std::string cut = full.substr(0, full.size() / 2);
  const std::string path = write_bytes(scratch.path / "half.bag", cut);
  const Ros1Record chunk = first_chunk(cut);
  ASSERT_FALSE(chunk.whole);  // the cut lies inside the (uncompressed) chunk
  ASSERT_EQ(chunk.fields.at("compression"), "none");
  std::size_t first_cut = 0;
  Ros1Topics topics;
  const std::vector<Streamed> whole = ros1_chunk_messages(cut, chunk, topics, &first_cut);
  ASSERT_GT(whole.size(), 100u);
  ASSERT_GT(first_cut, 0u);

  Bag bag = Bag::open(path);
  EXPECT_FALSE(bag.files().front()->summary().indexed);
  EXPECT_TRUE(any_note(bag, "no index")) << "a note says why the records were scanned";
  EXPECT_TRUE(any_note_names_byte(bag, first_cut)) << "a note names where the file ends inside a record";
  const std::vector<Streamed> streamed = stream_all(bag);
  EXPECT_TRUE(time_sorted(streamed));
  EXPECT_EQ(streamed.size(), whole.size());
  EXPECT_TRUE(streamed == sorted_by_time(whole));
}

TEST(Ros1Hostile, UnknownChunkCompressionIsNamedWithTheChunksByte) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-unsorted-chunks.bag");
  Scratch scratch;
  std::string bytes = shared_bytes("bags/rosbag_js/example-unsorted-chunks.bag");
  const Ros1Record chunk = first_chunk(bytes);
  ASSERT_EQ(chunk.fields.at("compression"), "none");
  bytes.replace(chunk.field_value_offset("compression"), 4, "zstd");  // same length: the framing holds
  const std::string path = write_bytes(scratch.path / "zstd_chunk.bag", bytes);
  const std::string what = parse_error_of([&] { Bag::open(path); });
  EXPECT_NE(what.find(path + ":"), std::string::npos) << what;
  EXPECT_TRUE(names_byte(what, chunk.offset)) << what;
  EXPECT_NE(what.find("\"zstd\""), std::string::npos) << what;
}

TEST(Ros1Hostile, UncompressedChunkWhoseSizeFieldLiesIsRefusedAtOpen) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-unsorted-chunks.bag");
  Scratch scratch;
  std::string bytes = shared_bytes("bags/rosbag_js/example-unsorted-chunks.bag");
  const Ros1Record chunk = first_chunk(bytes);
  const std::uint32_t size = u32_at(chunk.fields.at("size"), 0);
  ASSERT_EQ(size, chunk.data_len);
  put_u32(bytes, chunk.field_value_offset("size"), size + 1);
  const std::string path = write_bytes(scratch.path / "size_lies.bag", bytes);
  const std::string what = parse_error_of([&] { Bag::open(path); });
  EXPECT_NE(what.find(path + ":"), std::string::npos) << what;
  EXPECT_TRUE(names_byte(what, chunk.offset)) << what;
  EXPECT_NE(what.find(std::to_string(size + 1)), std::string::npos) << what;
  EXPECT_NE(what.find(std::to_string(chunk.data_len)), std::string::npos) << what;
}

TEST(Ros1Hostile, CompressedChunkWhoseSizeFieldLiesFailsTheStreamNamingTheChunk) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-lz4.bag");
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-bz2.bag");
  Scratch scratch;
  for (const std::string name : {"example-lz4.bag", "example-bz2.bag"}) {
    for (const std::int64_t change : {-1, +1000}) {
      std::string bytes = shared_bytes("bags/rosbag_js/" + name);
      const Ros1Record chunk = first_chunk(bytes);
      const std::string compression = chunk.fields.at("compression");
      const auto size = static_cast<std::uint32_t>(u32_at(chunk.fields.at("size"), 0) + change);
      put_u32(bytes, chunk.field_value_offset("size"), size);
      const std::string path = write_bytes(scratch.path / (std::to_string(change) + name), bytes);
      Bag bag = Bag::open(path);  // opened from the index: the chunk is not decompressed yet
      const std::string what = parse_error_of([&] { stream_all(bag); });
      EXPECT_NE(what.find(path + ":"), std::string::npos) << what;
      EXPECT_TRUE(names_byte(what, chunk.offset)) << what;
      EXPECT_NE(what.find(compression + " chunk"), std::string::npos) << what;
      EXPECT_NE(what.find(std::to_string(size)), std::string::npos) << what;
    }
  }
}

TEST(Ros1Hostile, MalformedIndexOfTheScanToolsBagIsRepairedWithANote) {
  CAIRN_REQUIRE_DATA("bags/scan_tools_laser_scan_matcher_demo.bag");
  Bag bag = Bag::open(test::data_path("bags/scan_tools_laser_scan_matcher_demo.bag").string());
  EXPECT_TRUE(any_note(bag, "data_len")) << "the repair of the index data records is noted";
  const std::vector<Streamed> streamed = stream_all(bag);
  EXPECT_EQ(streamed.size(), 360u);  // bags/SOURCE.txt: 360 scans
  EXPECT_TRUE(time_sorted(streamed));
}

TEST(Ros1Hostile, UnsortedChunksStreamInTimeOrder) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-unsorted-chunks.bag");
  const std::string bytes = shared_bytes("bags/rosbag_js/example-unsorted-chunks.bag");
  std::vector<Streamed> in_file_order;
  Ros1Topics topics;
  for (const Ros1Record& record : ros1_top_records(bytes)) {
    if (record.op() != 0x05) continue;
    std::size_t cut = 0;
    const std::vector<Streamed> messages = ros1_chunk_messages(bytes, record, topics, &cut);
    in_file_order.insert(in_file_order.end(), messages.begin(), messages.end());
  }
  ASSERT_EQ(in_file_order.size(), 3u);
  ASSERT_FALSE(time_sorted(in_file_order));  // the fixture's point
  Bag bag = Bag::open(test::data_path("bags/rosbag_js/example-unsorted-chunks.bag").string());
  EXPECT_TRUE(stream_all(bag) == sorted_by_time(in_file_order));
}

TEST(Ros1Hostile, PlainBz2AndLz4CopiesStreamByteIdenticalMessages) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example.bag");
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-bz2.bag");
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-lz4.bag");
  const std::string bytes = shared_bytes("bags/rosbag_js/example.bag");
  std::size_t cut = 0;
  Ros1Topics topics;
  const std::vector<Streamed> expected = sorted_by_time(ros1_chunk_messages(bytes, first_chunk(bytes), topics, &cut));
  ASSERT_EQ(cut, 0u);
  ASSERT_GT(expected.size(), 1000u);
  for (const std::string name : {"example.bag", "example-bz2.bag", "example-lz4.bag"}) {
    Bag bag = Bag::open(test::data_path("bags/rosbag_js/" + name).string());
    EXPECT_TRUE(stream_all(bag) == expected) << name;
  }
}

TEST(Ros1Hostile, StringLongerThanItsMessageIsADecodeErrorNamingTheRecord) {
  CAIRN_REQUIRE_DATA("bags/rosbag_js/example-unsorted-chunks.bag");
  Scratch scratch;
  std::string bytes = shared_bytes("bags/rosbag_js/example-unsorted-chunks.bag");
  const Ros1Record chunk = first_chunk(bytes);
  std::optional<Ros1Record> message;
  for (std::size_t at = chunk.data_offset; at < chunk.end() && !message;) {
    const Ros1Record record = *ros1_record(bytes, at, chunk.end());
    if (record.op() == 0x02) message = record;
    at = record.end();
  }
  ASSERT_TRUE(message.has_value());
  put_u32(bytes, message->data_offset, 0xFFFFFFFFu);  // std_msgs/String: uint32 length, then the bytes
  const std::string path = write_bytes(scratch.path / "long_string.bag", bytes);
  Bag bag = Bag::open(path);
  MessageDecoder decoder(bag);
  const auto stream = bag.read();
  BagMessage streamed;
  std::string what;
  while (stream->next(&streamed)) {
    if (streamed.message.log_time_ns != message->time_ns()) continue;
    what = parse_error_of([&] { decoder.decode(streamed); });
  }
  EXPECT_NE(what.find(path + ":"), std::string::npos) << what;
  EXPECT_TRUE(names_byte(what, message->offset)) << what;
  EXPECT_TRUE(names_message_byte(what, 4)) << what;  // after the length
  EXPECT_NE(what.find("4294967295"), std::string::npos) << what;
}

// ---------------------------------------------------------------------------------------------
// MCAP, read here from the spec: magic (8 bytes), records <opcode u8><length u64><content>, the
// Footer (opcode 0x02, 20 content bytes) before the closing magic.

constexpr std::size_t kMcapMagicBytes = 8;
constexpr std::size_t kMcapFooterRecordBytes = 9 + 20;

struct McapRecord {
  std::size_t offset = 0;
  std::uint8_t opcode = 0;
  std::size_t content = 0;  ///< offset of the content
  std::size_t length = 0;
  std::size_t end() const { return content + length; }
};

/// The whole records in [from, end) of `bytes`, in order.
std::vector<McapRecord> mcap_records(const std::string& bytes, std::size_t from, std::size_t end) {
  std::vector<McapRecord> records;
  for (std::size_t at = from; at + 9 <= end;) {
    const McapRecord record{at, static_cast<std::uint8_t>(bytes[at]), at + 9, static_cast<std::size_t>(u64_at(bytes, at + 1))};
    if (record.end() > end) break;
    records.push_back(record);
    at = record.end();
  }
  return records;
}

std::vector<McapRecord> mcap_data_records(const std::string& bytes) {
  return mcap_records(bytes, kMcapMagicBytes, bytes.size());
}

/// The file's Footer zeroed (summary_start, summary_offset_start, summary_crc): a reader must scan.
std::string without_summary(std::string bytes) {
  const std::size_t footer = bytes.size() - kMcapMagicBytes - kMcapFooterRecordBytes;
  EXPECT_EQ(bytes[footer], 0x02);
  put_u64(bytes, footer + 9, 0);
  put_u64(bytes, footer + 17, 0);
  put_u32(bytes, footer + 25, 0);
  return bytes;
}

/// "Chunk": message_start_time, message_end_time, uncompressed_size, uncompressed_crc (u32),
/// compression (string), records (u64 length + bytes).
struct ChunkLayout {
  std::size_t crc_offset = 0;
  std::string compression;
  std::size_t records = 0;
  std::size_t records_length = 0;
};
ChunkLayout chunk_layout(const std::string& bytes, const McapRecord& chunk) {
  ChunkLayout layout;
  layout.crc_offset = chunk.content + 24;
  const std::size_t compression_length = u32_at(bytes, chunk.content + 28);
  layout.compression = bytes.substr(chunk.content + 32, compression_length);
  layout.records_length = static_cast<std::size_t>(u64_at(bytes, chunk.content + 32 + compression_length));
  layout.records = chunk.content + 32 + compression_length + 8;
  return layout;
}

std::optional<McapRecord> first_record(const std::vector<McapRecord>& records, std::uint8_t opcode) {
  for (const McapRecord& record : records) {
    if (record.opcode == opcode) return record;
  }
  return std::nullopt;
}

/// "message_count: N" values of a rosbag2 metadata.yaml, read with a regex (the bag's total first).
std::vector<long long> metadata_message_counts(const std::string& folder) {
  const std::string text = read_bytes(test::data_path(folder + "/metadata.yaml"));
  std::vector<long long> out;
  const std::regex pattern("message_count:\\s*(\\d+)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), pattern); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stoll((*it)[1].str()));
  }
  return out;
}

TEST(McapHostile, CopyCutAfterItsChunkReadsTheWholeRecordsByAScan) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap");
  Scratch scratch;
  const std::string full = shared_bytes("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap");
  const std::optional<McapRecord> chunk = first_record(mcap_data_records(full), 0x06);
  ASSERT_TRUE(chunk.has_value());
  const std::size_t cut_at = chunk->end() + 5;  // inside the record after the chunk
  const std::string path = write_bytes(scratch.path / "cut.mcap", full.substr(0, cut_at));
  Bag bag = Bag::open(path);
  EXPECT_FALSE(bag.files().front()->summary().indexed);
  EXPECT_TRUE(any_note_names_byte(bag, chunk->end())) << "the note names the record the cut falls in";
  const std::vector<Streamed> streamed = stream_all(bag);
  const auto counts = metadata_message_counts("bags/rosbag2/mcap_cdr_test");
  ASSERT_FALSE(counts.empty());
  EXPECT_EQ(static_cast<long long>(streamed.size()), counts.front());
  EXPECT_TRUE(time_sorted(streamed));
  Bag whole = Bag::open(test::data_path("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap").string());
  EXPECT_TRUE(streamed == stream_all(whole));
}

TEST(McapHostile, CopyCutInsideItsOnlyChunkOpensEmptyNamingTheRecord) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap");
  Scratch scratch;
  const std::string full = shared_bytes("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap");
  const std::optional<McapRecord> chunk = first_record(mcap_data_records(full), 0x06);
  ASSERT_TRUE(chunk.has_value());
  const std::string path = write_bytes(scratch.path / "cut_in_chunk.mcap", full.substr(0, chunk->content + chunk->length / 2));
  Bag bag = Bag::open(path);
  EXPECT_FALSE(bag.files().front()->summary().indexed);
  EXPECT_TRUE(any_note_names_byte(bag, chunk->offset));
  EXPECT_TRUE(stream_all(bag).empty());
}

TEST(McapHostile, SummaryAndForcedScanStreamTheSameMessages) {
  for (const std::string relative : {"bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap", "bags/rosbag2/mcap_talker/talker.mcap"}) {
    CAIRN_REQUIRE_DATA(relative);
    Scratch scratch;
    const std::string path = write_bytes(scratch.path / "scan.mcap", without_summary(shared_bytes(relative)));
    Bag indexed = Bag::open(test::data_path(relative).string());
    Bag scanned = Bag::open(path);
    EXPECT_TRUE(indexed.files().front()->summary().indexed) << relative;
    EXPECT_FALSE(scanned.files().front()->summary().indexed) << relative;
    const std::vector<Streamed> from_summary = stream_all(indexed);
    EXPECT_FALSE(from_summary.empty());
    EXPECT_TRUE(from_summary == stream_all(scanned)) << relative;
  }
}

TEST(McapHostile, MessageOnAnUndeclaredChannelIsAnErrorAtItsByte) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap");
  Scratch scratch;
  std::string bytes = shared_bytes("bags/rosbag2/mcap_cdr_test/cdr_test_0.mcap");
  const std::optional<McapRecord> chunk = first_record(mcap_data_records(bytes), 0x06);
  ASSERT_TRUE(chunk.has_value());
  const ChunkLayout layout = chunk_layout(bytes, *chunk);
  ASSERT_EQ(layout.compression, "");  // records in the clear: offsets inside are file offsets
  const std::optional<McapRecord> message = first_record(mcap_records(bytes, layout.records, layout.records + layout.records_length), 0x05);
  ASSERT_TRUE(message.has_value());
  put_u16(bytes, message->content, 999);  // "Message": channel_id first
  put_u32(bytes, layout.crc_offset, 0);   // no uncompressed_crc: the damage must be found otherwise

  const std::string indexed_path = write_bytes(scratch.path / "undeclared.mcap", bytes);
  Bag bag = Bag::open(indexed_path);
  const std::string what = parse_error_of([&] { stream_all(bag); });
  EXPECT_NE(what.find(indexed_path + ":"), std::string::npos) << what;
  EXPECT_TRUE(names_byte(what, message->offset)) << what;
  EXPECT_NE(what.find("channel id 999"), std::string::npos) << what;

  const std::string scanned_path = write_bytes(scratch.path / "undeclared_scan.mcap", without_summary(bytes));
  const std::string scan_what = parse_error_of([&] { Bag::open(scanned_path); });
  EXPECT_NE(scan_what.find(scanned_path + ":"), std::string::npos) << scan_what;
  EXPECT_TRUE(names_byte(scan_what, message->offset)) << scan_what;
  EXPECT_NE(scan_what.find("channel id 999"), std::string::npos) << scan_what;
}

// ---------------------------------------------------------------------------------------------
// rosbag2 SQLite3.

TEST(SqliteHostile, FilesThatAreNoDatabaseAreRefusedNamingTheFile) {
  Scratch scratch;
  const std::string text = write_bytes(scratch.path / "notes.db3", "hello, not a database\n");
  const std::string by_content = parse_error_of([&] { Bag::open(text); });
  EXPECT_NE(by_content.find(text + ":"), std::string::npos) << by_content;
  EXPECT_NE(by_content.find("not a bag"), std::string::npos) << by_content;
  const std::string direct = parse_error_of([&] { open_sqlite_bag(text); });
  EXPECT_NE(direct.find(text + ":"), std::string::npos) << direct;
  EXPECT_NE(direct.find("not a rosbag2 SQLite3 bag"), std::string::npos) << direct;

  // SQLite's magic, then no database: refused by libsqlite3 when the topics table is read.
  const std::string magic = write_bytes(scratch.path / "magic.db3", std::string("SQLite format 3\0", 16) + std::string(2000, 'x'));
  const std::string what = parse_error_of([&] { Bag::open(magic); });
  EXPECT_NE(what.find(magic + ":"), std::string::npos) << what;
  EXPECT_NE(what.find("not a rosbag2 SQLite3 bag"), std::string::npos) << what;
  EXPECT_NE(what.find("topics"), std::string::npos) << what;
}

TEST(SqliteHostile, DatabaseCutAtHalfIsRefusedNamingTheFile) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/sqlite3_cdr_test/cdr_test_0.db3");
  Scratch scratch;
  const std::string full = shared_bytes("bags/rosbag2/sqlite3_cdr_test/cdr_test_0.db3");
  const std::string path = write_bytes(scratch.path / "half.db3", full.substr(0, full.size() / 2));
  const std::string what = parse_error_of([&] { Bag::open(path); });
  EXPECT_NE(what.find(path + ":"), std::string::npos) << what;
  EXPECT_NE(what.find("malformed"), std::string::npos) << what;  // libsqlite3's SQLITE_CORRUPT text
}

// ---------------------------------------------------------------------------------------------
// Payloads: counts and lengths read from the bytes are checked against the bytes left before
// anything is allocated (a failed allocation would be std::bad_alloc or std::length_error here).

std::vector<std::uint8_t> bytes_of(std::initializer_list<std::uint8_t> list) { return list; }

TEST(PayloadHostile, SequenceCountBeyondTheBytesNamesTheField) {
  const SchemaSet scan = SchemaSet::parse("test/Scan", "float32 angle\nfloat32[] ranges\n", SchemaSet::Dialect::kRos2, "scan.db3: /scan");
  // CDR little endian; angle; ranges count 0xFFFFFFF0 with 4 bytes after it.
  const auto cdr = bytes_of({0, 1, 0, 0, 0, 0, 0x80, 0x3f, 0xf0, 0xff, 0xff, 0xff, 1, 2, 3, 4});
  const std::string what = parse_error_of([&] { deserialize(scan, cdr, Serialization::kCdr, "scan.db3: /scan"); });
  EXPECT_NE(what.find("scan.db3: /scan"), std::string::npos) << what;
  EXPECT_NE(what.find("ranges"), std::string::npos) << what;
  EXPECT_NE(what.find("4294967280"), std::string::npos) << what;
  EXPECT_TRUE(names_message_byte(what, 12)) << what;  // after the count

  const SchemaSet image = SchemaSet::parse("test/Blob", "uint8[] data\n", SchemaSet::Dialect::kRos1, "blob.bag: /blob");
  const auto ros1 = bytes_of({0xff, 0xff, 0xff, 0x7f, 9, 9});
  const std::string blob = parse_error_of([&] { deserialize(image, ros1, Serialization::kRos1, "blob.bag: /blob"); });
  EXPECT_NE(blob.find("blob.bag: /blob"), std::string::npos) << blob;
  EXPECT_NE(blob.find("data"), std::string::npos) << blob;
  EXPECT_NE(blob.find("2147483647"), std::string::npos) << blob;
  EXPECT_TRUE(names_message_byte(blob, 4)) << blob;
}

TEST(PayloadHostile, SequenceOfMessagesBeyondTheBytesNamesTheField) {
  const char* definition =
      "Item[] items\n"
      "================================================================================\n"
      "MSG: test/Item\n"
      "string label\n"
      "int32[] values\n";
  const SchemaSet set = SchemaSet::parse("test/List", definition, SchemaSet::Dialect::kRos1, "list.bag: /list");
  const auto ros1 = bytes_of({0x00, 0x00, 0x00, 0x40, 0, 0, 0, 0});  // items: 2^30, then 4 bytes
  const std::string what = parse_error_of([&] { deserialize(set, ros1, Serialization::kRos1, "list.bag: /list"); });
  EXPECT_NE(what.find("list.bag: /list"), std::string::npos) << what;
  EXPECT_NE(what.find("items"), std::string::npos) << what;
  EXPECT_NE(what.find("1073741824"), std::string::npos) << what;
  EXPECT_TRUE(names_message_byte(what, 4)) << what;
}

TEST(PayloadHostile, StringLengthBeyondTheBytesNamesTheByte) {
  const SchemaSet set = SchemaSet::parse("test/Text", "uint32 seq\nstring text\n", SchemaSet::Dialect::kRos2, "text.mcap: /text");
  // CDR: seq, then a string of length 0xFFFFFFFF at message byte 8 (4 after the header).
  const auto cdr = bytes_of({0, 1, 0, 0, 7, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 'a', 0});
  const std::string what = parse_error_of([&] { deserialize(set, cdr, Serialization::kCdr, "text.mcap: /text"); });
  EXPECT_NE(what.find("text.mcap: /text"), std::string::npos) << what;
  EXPECT_TRUE(names_message_byte(what, 12)) << what;  // after the length field
  EXPECT_NE(what.find("4294967295"), std::string::npos) << what;
}

}  // namespace
}  // namespace cairn::bag
