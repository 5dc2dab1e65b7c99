#pragma once
/// \file
/// The framing every saved cairn map shares (the 2D map of slam2d/map_file.hpp, the 3D LiDAR map of
/// lidar3d/map_file.hpp, the visual map of vslam/map_file.hpp; docs/formats.md, "cairn 2D map",
/// "cairn 3D LiDAR map" and "cairn visual map"):
///
///   8-byte magic | u32 version | u32 flags | u64 file size | u64 payload size |
///   zlib stream of the payload | u32 CRC-32 of everything before it
///
/// and the little-endian writer and checked reader the payloads are written and read with. The
/// container is checked whole before a payload byte is used (size, magic, version, flags, the
/// checksum, so a flipped bit anywhere is caught first, then the zlib stream against the declared
/// payload size); the reader then checks every field against the bytes left. Any failure is an
/// io::ParseError naming the file; payload errors also name the payload byte offset and the field:
/// `map.cmap: payload byte 124: keyframe count 4294967295 needs ... bytes, only 80 left`. A corrupt
/// or hostile file can neither crash a reader nor make it allocate more than the data it holds.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

namespace cairn::io {

/// What one kind of container is: its magic, the format version this build writes (and the newest
/// it reads), and how it is named in messages.
struct ContainerKind {
  std::array<char, 8> magic{};
  std::uint32_t version = 1;
  std::string what;         ///< e.g. "cairn 2D map"
  std::string how_to_make;  ///< e.g. "cairn slam2d --save-map"
};

/// The kind of a container cairn writes, by magic, with `version`: "CAIRNMAP" (a cairn 2D map,
/// cairn slam2d --save-map), "CAIRN3DM" (a cairn 3D LiDAR map, cairn slam3d --save-map) or
/// "CAIRNVSM" (a cairn visual map, cairn vslam --save-map). The names come from one table, which
/// decode_container also uses to tell what a file of another kind is. Precondition: `magic` is in
/// the table.
ContainerKind known_container_kind(std::string_view magic, std::uint32_t version);

/// The file: the header of `kind`, `payload` deflated (zlib's default level), the CRC-32.
std::string encode_container(const ContainerKind& kind, const std::string& payload);

/// The payload of a container of `kind`, after every check of the file comment. Throws
/// ParseError(name, 0, ...) for an empty file, a wrong magic (naming the other cairn map when the
/// magic is one: "this is a cairn 3D LiDAR map (cairn slam3d --save-map), expected ..."), a
/// version other than 1 to kind.version, flags other than 0, a file size other than the header's,
/// a checksum mismatch, a payload size over 16 GiB, or a zlib stream that is corrupt or holds
/// another number of bytes than declared. The payload grows with what zlib actually inflates,
/// never to a size only the header claims.
std::string decode_container(const std::string& bytes, const std::string& name, const ContainerKind& kind);

/// The bytes of a container file, or of standard input for "-" (then named "standard input" in
/// the caller's errors). Checks the path with check_input_file(path, what) ("a map file") and
/// refuses a file over 4 GiB as soon as it passes that size. Throws ParseError(path, 0, ...).
std::string read_container_file(const std::string& path, const std::string& what);

/// CRC-32 (ISO-HDLC, as zlib, gzip and PNG compute it) of `size` bytes: the container's checksum.
std::uint32_t crc32_of(const unsigned char* data, std::size_t size);

/// Appends little-endian numbers whatever the host (docs/formats.md: u32, i32, u64, i64 two's
/// complement, f32, f64 IEEE 754).
class BinaryWriter {
 public:
  void u8(std::uint8_t v) { bytes_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f32(float v);
  void f64(double v);
  void raw(const void* data, std::size_t size) { bytes_.append(static_cast<const char*>(data), size); }
  /// u32 length, then the bytes. Precondition: text.size() < 2^32.
  void string(const std::string& text);
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

/// A cursor over a payload: every read is checked against the bytes left and every error is
/// ParseError(name, 0, "payload byte N: ...") with N the offset of the field being read. The
/// payload must outlive the reader.
class BinaryReader {
 public:
  BinaryReader(std::string_view payload, std::string name) : data_(payload), name_(std::move(name)) {}

  /// Throws the ParseError at the offset of the field read last.
  [[noreturn]] void fail(const std::string& what) const { fail_at(field_at_, what); }
  /// Throws the ParseError at payload byte `offset` (for a check over several fields).
  [[noreturn]] void fail_at(std::size_t offset, const std::string& what) const;
  /// Marks the next `bytes` as the field `field`; "file ends early" when fewer are left.
  void need(std::size_t bytes, const std::string& field);
  std::size_t left() const { return data_.size() - at_; }
  std::size_t offset() const { return at_; }

  std::uint8_t u8(const std::string& field);
  std::uint32_t u32(const std::string& field);
  std::uint64_t u64(const std::string& field);
  std::int32_t i32(const std::string& field) { return static_cast<std::int32_t>(u32(field)); }
  std::int64_t i64(const std::string& field) { return static_cast<std::int64_t>(u64(field)); }
  /// Any 32 bits (NaN included): the caller checks the value.
  float f32(const std::string& field);
  /// A finite double in [low, high].
  double f64(const std::string& field, double low, double high);
  /// Any finite double (for fields whose range an options struct's is_valid checks).
  double finite_f64(const std::string& field);
  /// An integer in [low, high].
  std::int64_t integer32(const std::string& field, std::int64_t low, std::int64_t high);
  void check_range(const std::string& field, std::int64_t v, std::int64_t low, std::int64_t high) const;
  /// A count of records of `record_bytes` each: at most what the bytes left can hold, checked
  /// before anything is allocated.
  std::size_t count(const std::string& field, std::size_t record_bytes);
  const unsigned char* take(std::size_t bytes, const std::string& field);
  /// A u32 length ("<field> length", at most `max_bytes`) and that many bytes.
  std::string string(const std::string& field, std::uint32_t max_bytes);
  /// Fails unless every byte was read: "N bytes after the last <last> (expected the end of the
  /// payload)".
  void expect_end(const std::string& last) const;

 private:
  const unsigned char* bytes() const { return reinterpret_cast<const unsigned char*>(data_.data()); }
  std::string_view data_;
  std::string name_;
  std::size_t at_ = 0;
  std::size_t field_at_ = 0;
};

/// Little-endian loads from raw bytes (a block taken with BinaryReader::take).
inline std::uint32_t load_u32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 | static_cast<std::uint32_t>(p[2]) << 16 |
         static_cast<std::uint32_t>(p[3]) << 24;
}
inline std::uint64_t load_u64(const unsigned char* p) {
  return static_cast<std::uint64_t>(load_u32(p)) | static_cast<std::uint64_t>(load_u32(p + 4)) << 32;
}

}  // namespace cairn::io
