#include "cairn/io/map_container.hpp"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/io/input_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {

constexpr std::size_t kHeaderBytes = 32;  // magic, version, flags, file size, payload size
constexpr std::size_t kTrailerBytes = 4;  // CRC-32
constexpr std::uint64_t kMaxFileBytes = std::uint64_t{4} << 30;
constexpr std::uint64_t kMaxPayloadBytes = std::uint64_t{16} << 30;

/// The containers cairn writes: decode_container names the kind of a file with another's magic.
struct KnownKind {
  std::string_view magic;
  std::string_view what;
  std::string_view how_to_make;
};
constexpr KnownKind kKnownKinds[] = {
    {"CAIRNMAP", "cairn 2D map", "cairn slam2d --save-map"},
    {"CAIRN3DM", "cairn 3D LiDAR map", "cairn slam3d --save-map"},
    {"CAIRNVSM", "cairn visual map", "cairn vslam --save-map"},
};

std::string_view magic_of(const ContainerKind& kind) { return {kind.magic.data(), kind.magic.size()}; }

std::string hex32(std::uint32_t v) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "%08x", v);
  return buffer;
}

/// Empty file and magic: the messages say what the file should be and, when it is another
/// cairn map, what it is.
void check_magic(const std::string& bytes, const std::string& name, const ContainerKind& kind) {
  const std::string magic(magic_of(kind));
  if (bytes.empty()) throw ParseError(name, 0, "empty file: expected a " + kind.what + " (" + kind.how_to_make + ")");
  if (bytes.size() >= 8 && std::string_view(bytes.data(), 8) == magic) return;
  for (const KnownKind& other : kKnownKinds) {
    if (bytes.size() >= 8 && std::string_view(bytes.data(), 8) == other.magic) {
      throw ParseError(name, 0, "not a " + kind.what + " file: this is a " + std::string(other.what) + " (" +
                                    std::string(other.how_to_make) + "), expected a " + kind.what +
                                    " (the magic bytes \"" + magic + "\" at the start; write one with " +
                                    kind.how_to_make + ")");
    }
  }
  throw ParseError(name, 0, "not a " + kind.what + " file: expected the magic bytes \"" + magic +
                                "\" at the start (write one with " + kind.how_to_make + ")");
}

/// Version, flags, file size and checksum: everything the header and trailer can say about the
/// bytes before the zlib stream is touched.
void check_frame(const std::string& bytes, const std::string& name, const ContainerKind& kind) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  if (bytes.size() < kHeaderBytes + kTrailerBytes) {
    throw ParseError(name, 0, "file ends early: " + std::to_string(bytes.size()) + " bytes, a cairn map has at least " +
                                  std::to_string(kHeaderBytes + kTrailerBytes));
  }
  const std::uint32_t version = load_u32(data + 8);
  if (version == 0 || version > kind.version) {
    throw ParseError(name, 0, "map format version " + std::to_string(version) + ": this cairn reads version " +
                                  std::to_string(kind.version) +
                                  (version > kind.version ? " (the file was written by a newer cairn)" : ""));
  }
  const std::uint32_t flags = load_u32(data + 12);
  if (flags != 0) throw ParseError(name, 0, "header flags 0x" + hex32(flags) + ": expected 0 (no flags are defined)");
  const std::uint64_t file_bytes = load_u64(data + 16);
  if (file_bytes != bytes.size()) {
    throw ParseError(name, 0, "the header says the file has " + std::to_string(file_bytes) + " bytes, it has " +
                                  std::to_string(bytes.size()) +
                                  (file_bytes > bytes.size() ? " (truncated)" : " (data appended or header corrupt)"));
  }
  const std::size_t body = bytes.size() - kTrailerBytes;
  const std::uint32_t stored_crc = load_u32(data + body);
  const std::uint32_t computed_crc = crc32_of(data, body);
  if (stored_crc != computed_crc) {
    throw ParseError(name, 0, "checksum mismatch: the file stores CRC-32 " + hex32(stored_crc) + ", its content gives " +
                                  hex32(computed_crc) + " (the file is corrupt)");
  }
}

/// Exactly `payload_bytes` from the zlib stream of `size` bytes, which must end where the data ends.
std::string inflate_payload(const unsigned char* data, std::size_t size, std::uint64_t payload_bytes, const std::string& name) {
  z_stream stream{};
  if (inflateInit(&stream) != Z_OK) throw ParseError(name, 0, "cannot initialise zlib");
  std::string out;
  // Grow with the data actually inflated, never to a size only a header claims.
  out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(payload_bytes, std::uint64_t{1} << 26)));
  std::size_t produced = 0;
  std::size_t consumed = 0;
  int status = Z_OK;
  while (status != Z_STREAM_END) {
    if (produced == out.size()) {
      if (out.size() >= payload_bytes) break;  // full but the stream goes on: longer than declared
      out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(payload_bytes, 2 * static_cast<std::uint64_t>(out.size()) + 1)));
    }
    const std::size_t in_chunk = std::min<std::size_t>(size - consumed, std::numeric_limits<uInt>::max());
    const std::size_t out_chunk = std::min<std::size_t>(out.size() - produced, std::numeric_limits<uInt>::max());
    stream.next_in = const_cast<Bytef*>(data + consumed);
    stream.avail_in = static_cast<uInt>(in_chunk);
    stream.next_out = reinterpret_cast<Bytef*>(out.data() + produced);
    stream.avail_out = static_cast<uInt>(out_chunk);
    status = inflate(&stream, Z_NO_FLUSH);
    consumed += in_chunk - stream.avail_in;
    produced += out_chunk - stream.avail_out;
    if (status == Z_STREAM_END) break;
    if (status == Z_BUF_ERROR && consumed == size && produced < out.size()) {
      inflateEnd(&stream);
      throw ParseError(name, 0, "compressed payload ends early (" + std::to_string(produced) + " of " +
                                    std::to_string(payload_bytes) + " bytes)");
    }
    if (status != Z_OK && status != Z_BUF_ERROR) {
      const std::string message = stream.msg != nullptr ? stream.msg : "error " + std::to_string(status);
      inflateEnd(&stream);
      throw ParseError(name, 0, "corrupt compressed payload (zlib: " + message + ")");
    }
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END) {
    throw ParseError(name, 0, "compressed payload is longer than the " + std::to_string(payload_bytes) +
                                  " bytes the header declares");
  }
  if (produced != payload_bytes) {
    throw ParseError(name, 0, "compressed payload holds " + std::to_string(produced) + " bytes, the header declares " +
                                  std::to_string(payload_bytes));
  }
  if (consumed != size) {
    throw ParseError(name, 0, std::to_string(size - consumed) + " bytes after the end of the compressed payload");
  }
  out.resize(produced);
  return out;
}

}  // namespace

ContainerKind known_container_kind(std::string_view magic, std::uint32_t version) {
  for (const KnownKind& known : kKnownKinds) {
    if (known.magic != magic) continue;
    ContainerKind kind;
    std::copy(known.magic.begin(), known.magic.end(), kind.magic.begin());
    kind.version = version;
    kind.what = known.what;
    kind.how_to_make = known.how_to_make;
    return kind;
  }
  CAIRN_ASSERT(false, "known_container_kind: a magic that is not in the table of cairn containers");
  return {};
}

std::uint32_t crc32_of(const unsigned char* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t at = 0; at < size;) {
    const std::size_t chunk = std::min<std::size_t>(size - at, std::size_t{1} << 30);
    crc = crc32(crc, data + at, static_cast<uInt>(chunk));
    at += chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

std::string encode_container(const ContainerKind& kind, const std::string& payload) {
  uLongf compressed_size = compressBound(static_cast<uLong>(payload.size()));
  std::string compressed(compressed_size, '\0');
  const int status = compress2(reinterpret_cast<Bytef*>(compressed.data()), &compressed_size,
                               reinterpret_cast<const Bytef*>(payload.data()), static_cast<uLong>(payload.size()),
                               Z_DEFAULT_COMPRESSION);
  CAIRN_ASSERT(status == Z_OK, "zlib compress2 failed on a buffer of compressBound size");
  compressed.resize(compressed_size);
  BinaryWriter w;
  w.raw(kind.magic.data(), kind.magic.size());
  w.u32(kind.version);
  w.u32(0);  // flags
  w.u64(kHeaderBytes + compressed.size() + kTrailerBytes);
  w.u64(payload.size());
  w.raw(compressed.data(), compressed.size());
  std::string& bytes = w.bytes();
  w.u32(crc32_of(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()));
  return std::move(bytes);
}

std::string decode_container(const std::string& bytes, const std::string& name, const ContainerKind& kind) {
  check_magic(bytes, name, kind);
  check_frame(bytes, name, kind);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::uint64_t payload_bytes = load_u64(data + 24);
  if (payload_bytes > kMaxPayloadBytes) {
    throw ParseError(name, 0, "payload size " + std::to_string(payload_bytes) + " bytes: at most 16 GiB allowed");
  }
  return inflate_payload(data + kHeaderBytes, bytes.size() - kTrailerBytes - kHeaderBytes, payload_bytes, name);
}

std::string read_container_file(const std::string& path, const std::string& what) {
  if (path == "-") return standard_input(kMaxFileBytes);
  check_input_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParseError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  // Read in chunks (works for pipes and devices too), never past the largest map file.
  std::string bytes;
  std::string chunk(std::size_t{1} << 20, '\0');
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    bytes.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (bytes.size() > kMaxFileBytes) throw ParseError(path, 0, "larger than 4 GiB: not a cairn map file");
  }
  if (in.bad()) throw ParseError(path, 0, "cannot read the file");
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// BinaryWriter: little endian whatever the host.

void BinaryWriter::u32(std::uint32_t v) {
  for (int b = 0; b < 4; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
}
void BinaryWriter::u64(std::uint64_t v) {
  for (int b = 0; b < 8; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
}
void BinaryWriter::f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
void BinaryWriter::f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
void BinaryWriter::string(const std::string& text) {
  CAIRN_ASSERT(text.size() <= std::numeric_limits<std::uint32_t>::max(), "BinaryWriter::string: 4 GiB or more");
  u32(static_cast<std::uint32_t>(text.size()));
  raw(text.data(), text.size());
}

// ---------------------------------------------------------------------------------------------
// BinaryReader.

void BinaryReader::fail_at(std::size_t offset, const std::string& what) const {
  throw ParseError(name_, 0, "payload byte " + std::to_string(offset) + ": " + what);
}

void BinaryReader::need(std::size_t bytes, const std::string& field) {
  field_at_ = at_;
  if (bytes > left()) {
    fail("file ends early: expected " + field + " (" + std::to_string(bytes) + " bytes), " + std::to_string(left()) +
         " left");
  }
}

std::uint8_t BinaryReader::u8(const std::string& field) {
  need(1, field);
  return bytes()[at_++];
}

std::uint32_t BinaryReader::u32(const std::string& field) {
  need(4, field);
  const std::uint32_t v = load_u32(bytes() + at_);
  at_ += 4;
  return v;
}

std::uint64_t BinaryReader::u64(const std::string& field) {
  need(8, field);
  const std::uint64_t v = load_u64(bytes() + at_);
  at_ += 8;
  return v;
}

float BinaryReader::f32(const std::string& field) { return std::bit_cast<float>(u32(field)); }

double BinaryReader::f64(const std::string& field, double low, double high) {
  const double v = std::bit_cast<double>(u64(field));
  if (!std::isfinite(v) || v < low || v > high) {
    std::ostringstream s;
    s.precision(17);
    s << field << ": expected a finite number in [" << low << ", " << high << "], found " << v;
    fail(s.str());
  }
  return v;
}

double BinaryReader::finite_f64(const std::string& field) {
  const double v = std::bit_cast<double>(u64(field));
  if (!std::isfinite(v)) fail(field + ": expected a finite number, found " + std::to_string(v));
  return v;
}

std::int64_t BinaryReader::integer32(const std::string& field, std::int64_t low, std::int64_t high) {
  const std::int32_t v = i32(field);
  check_range(field, v, low, high);
  return v;
}

void BinaryReader::check_range(const std::string& field, std::int64_t v, std::int64_t low, std::int64_t high) const {
  if (v < low || v > high) {
    fail(field + ": expected an integer in [" + std::to_string(low) + ", " + std::to_string(high) + "], found " +
         std::to_string(v));
  }
}

std::size_t BinaryReader::count(const std::string& field, std::size_t record_bytes) {
  const std::uint32_t n = u32(field);
  if (static_cast<std::uint64_t>(n) * record_bytes > left()) {
    fail(field + " " + std::to_string(n) + " needs " + std::to_string(static_cast<std::uint64_t>(n) * record_bytes) +
         " bytes, only " + std::to_string(left()) + " left");
  }
  return n;
}

const unsigned char* BinaryReader::take(std::size_t bytes, const std::string& field) {
  need(bytes, field);
  const unsigned char* p = this->bytes() + at_;
  at_ += bytes;
  return p;
}

std::string BinaryReader::string(const std::string& field, std::uint32_t max_bytes) {
  const std::size_t length = count(field + " length", 1);
  if (length > max_bytes) {
    fail(field + " length: expected at most " + std::to_string(max_bytes) + " bytes, found " + std::to_string(length));
  }
  const unsigned char* text = take(length, field);
  return std::string(reinterpret_cast<const char*>(text), length);
}

void BinaryReader::expect_end(const std::string& last) const {
  if (left() != 0) {
    fail_at(offset(), std::to_string(left()) + " bytes after the last " + last + " (expected the end of the payload)");
  }
}

}  // namespace cairn::io
