#include "cairn/slam2d/map_file.hpp"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/io/input_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::slam2d {
namespace {

constexpr char kMagic[8] = {'C', 'A', 'I', 'R', 'N', 'M', 'A', 'P'};
constexpr std::size_t kHeaderBytes = 32;   // magic, version, flags, file size, payload size
constexpr std::size_t kTrailerBytes = 4;   // CRC-32
constexpr std::uint64_t kMaxFileBytes = std::uint64_t{4} << 30;
constexpr std::uint64_t kMaxPayloadBytes = std::uint64_t{16} << 30;
constexpr std::uint32_t kMaxSourceBytes = 65536;
constexpr std::uint32_t kMaxGridSide = 65536;             // cells; 3.3 km at 5 cm
constexpr std::uint64_t kMaxGridCells = std::uint64_t{1} << 28;
constexpr std::int64_t kMaxGridOffset = 100000000;       // ProbabilityGrid's own bound (|offset| < this)
static_assert(std::endian::native == std::endian::little || std::endian::native == std::endian::big);

// ---------------------------------------------------------------------------------------------
// Writing: little endian whatever the host.

class Writer {
 public:
  void u8(std::uint8_t v) { bytes_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int b = 0; b < 4; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void u64(std::uint64_t v) {
    for (int b = 0; b < 8; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void raw(const void* data, std::size_t size) { bytes_.append(static_cast<const char*>(data), size); }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

void write_pose(Writer& w, const core::SE2& T) {
  w.f64(T.x());
  w.f64(T.y());
  w.f64(T.angle());
}

std::string encode_payload(const SavedMap2D& map) {
  Writer w;
  // Map header: what the map was built with.
  w.f64(map.grid.resolution_m);
  w.f64(map.grid.hit_probability);
  w.f64(map.grid.miss_probability);
  w.f64(map.grid.min_probability);
  w.f64(map.grid.max_probability);
  w.f64(map.map_points.cell_size_m);
  w.f64(map.map_points.normal_radius_m);
  w.i32(map.map_points.normal_min_neighbours);
  w.f64(map.map_points.normal_max_eigenvalue_ratio);
  w.f64(map.filter.min_range_m);
  w.f64(map.filter.max_range_m);
  w.f64(map.filter.missing_ray_length_m);
  w.f64(map.filter.voxel_size_m);
  w.i32(map.filter.adaptive_min_points);
  w.f64(map.filter.adaptive_max_voxel_size_m);
  CAIRN_ASSERT(map.source.size() <= kMaxSourceBytes, "map source name longer than 64 KiB");
  w.u32(static_cast<std::uint32_t>(map.source.size()));
  w.raw(map.source.data(), map.source.size());
  w.u32(static_cast<std::uint32_t>(map.keyframes.size()));
  w.u32(static_cast<std::uint32_t>(map.submaps.size()));
  for (const SavedKeyframe& kf : map.keyframes) {
    w.i64(kf.time.nanoseconds());
    write_pose(w, kf.T_world_laser);
    w.i32(kf.segment);
  }
  for (const SavedSubmap& submap : map.submaps) {
    write_pose(w, submap.T_world_submap);
    w.i32(submap.segment);
    w.i32(submap.first_keyframe);
    w.i32(submap.keyframe_count);
    // The observed part of the grid only.
    const ProbabilityGrid& grid = submap.grid;
    int i0 = 0, j0 = 0, i1 = -1, j1 = -1;
    const bool any = grid.known_bounds(i0, j0, i1, j1);
    const int width = any ? i1 - i0 + 1 : 0;
    const int height = any ? j1 - j0 + 1 : 0;
    w.i64(any ? grid.offset_i() + i0 : 0);
    w.i64(any ? grid.offset_j() + j0 : 0);
    w.u32(static_cast<std::uint32_t>(width));
    w.u32(static_cast<std::uint32_t>(height));
    const std::size_t cells = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    std::string mask((cells + 7) / 8, '\0');
    std::vector<float> values;
    for (int j = 0; j < height; ++j) {
      for (int i = 0; i < width; ++i) {
        if (!grid.cell_known(i + i0, j + j0)) continue;
        const std::size_t k = static_cast<std::size_t>(j) * static_cast<std::size_t>(width) + static_cast<std::size_t>(i);
        mask[k / 8] = static_cast<char>(static_cast<std::uint8_t>(mask[k / 8]) | (1u << (k % 8)));
        values.push_back(grid.cell_log_odds(i + i0, j + j0));
      }
    }
    w.raw(mask.data(), mask.size());
    for (const float v : values) w.f32(v);
    w.u32(static_cast<std::uint32_t>(submap.points_submap.size()));
    for (const auto& p : submap.points_submap) {
      w.f64(p.x());
      w.f64(p.y());
    }
  }
  return std::move(w.bytes());
}

// ---------------------------------------------------------------------------------------------
// Reading.

std::uint32_t load_u32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 | static_cast<std::uint32_t>(p[2]) << 16 |
         static_cast<std::uint32_t>(p[3]) << 24;
}
std::uint64_t load_u64(const unsigned char* p) {
  return static_cast<std::uint64_t>(load_u32(p)) | static_cast<std::uint64_t>(load_u32(p + 4)) << 32;
}

/// CRC-32 (ISO-HDLC, as zlib, gzip and PNG compute it) of `size` bytes.
std::uint32_t crc32_of(const unsigned char* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t at = 0; at < size;) {
    const std::size_t chunk = std::min<std::size_t>(size - at, std::size_t{1} << 30);
    crc = crc32(crc, data + at, static_cast<uInt>(chunk));
    at += chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

std::string hex32(std::uint32_t v) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "%08x", v);
  return buffer;
}

/// A cursor over the payload; every read is checked against the bytes left and every error
/// names the payload offset and the field.
class Reader {
 public:
  Reader(const std::string& payload, const std::string& name) : data_(payload), name_(name) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw io::ParseError(name_, 0, "payload byte " + std::to_string(field_at_) + ": " + what);
  }
  void need(std::size_t bytes, const std::string& field) {
    field_at_ = at_;
    if (bytes > left()) {
      fail("file ends early: expected " + field + " (" + std::to_string(bytes) + " bytes), " + std::to_string(left()) +
           " left");
    }
  }
  std::size_t left() const { return data_.size() - at_; }
  std::size_t offset() const { return at_; }

  std::uint32_t u32(const std::string& field) {
    need(4, field);
    const std::uint32_t v = load_u32(bytes() + at_);
    at_ += 4;
    return v;
  }
  std::uint64_t u64(const std::string& field) {
    need(8, field);
    const std::uint64_t v = load_u64(bytes() + at_);
    at_ += 8;
    return v;
  }
  std::int32_t i32(const std::string& field) { return static_cast<std::int32_t>(u32(field)); }
  std::int64_t i64(const std::string& field) { return static_cast<std::int64_t>(u64(field)); }
  float f32(const std::string& field) { return std::bit_cast<float>(u32(field)); }
  /// A finite double in [low, high].
  double f64(const std::string& field, double low, double high) {
    const double v = std::bit_cast<double>(u64(field));
    if (!std::isfinite(v) || v < low || v > high) {
      std::ostringstream s;
      s.precision(17);
      s << field << ": expected a finite number in [" << low << ", " << high << "], found " << v;
      fail(s.str());
    }
    return v;
  }
  /// An integer in [low, high].
  std::int64_t integer32(const std::string& field, std::int64_t low, std::int64_t high) {
    const std::int32_t v = i32(field);
    check_range(field, v, low, high);
    return v;
  }
  void check_range(const std::string& field, std::int64_t v, std::int64_t low, std::int64_t high) const {
    if (v < low || v > high) {
      fail(field + ": expected an integer in [" + std::to_string(low) + ", " + std::to_string(high) + "], found " +
           std::to_string(v));
    }
  }
  /// A count of records of `record_bytes` each: at most what the bytes left can hold, checked
  /// before anything is allocated.
  std::size_t count(const std::string& field, std::size_t record_bytes) {
    const std::uint32_t n = u32(field);
    if (static_cast<std::uint64_t>(n) * record_bytes > left()) {
      fail(field + " " + std::to_string(n) + " needs " + std::to_string(static_cast<std::uint64_t>(n) * record_bytes) +
           " bytes, only " + std::to_string(left()) + " left");
    }
    return n;
  }
  const unsigned char* take(std::size_t bytes, const std::string& field) {
    need(bytes, field);
    const unsigned char* p = this->bytes() + at_;
    at_ += bytes;
    return p;
  }
  core::SE2 pose(const std::string& field) {
    const double x = f64(field + " x", -1e9, 1e9);
    const double y = f64(field + " y", -1e9, 1e9);
    // Written as SE2::angle(), in (-pi, pi]; a little slack for other writers.
    const double theta = f64(field + " theta", -std::numbers::pi - 1e-9, std::numbers::pi + 1e-9);
    return core::SE2(x, y, theta);
  }

 private:
  const unsigned char* bytes() const { return reinterpret_cast<const unsigned char*>(data_.data()); }
  const std::string& data_;
  const std::string& name_;
  std::size_t at_ = 0;
  std::size_t field_at_ = 0;
};

double log_odds(double p) { return std::log(p / (1.0 - p)); }

SavedMap2D decode_payload(const std::string& payload, const std::string& name) {
  Reader r(payload, name);
  SavedMap2D map;
  // Ranges: what ProbabilityGrid, PointMap and the scan filter accept, within sane physical bounds.
  map.grid.resolution_m = r.f64("grid resolution_m", 1e-3, 10.0);
  map.grid.hit_probability = r.f64("grid hit_probability", std::nextafter(0.5, 1.0), std::nextafter(1.0, 0.0));
  map.grid.miss_probability = r.f64("grid miss_probability", std::nextafter(0.0, 1.0), std::nextafter(0.5, 0.0));
  map.grid.min_probability = r.f64("grid min_probability", 1e-6, 0.5);
  map.grid.max_probability = r.f64("grid max_probability", 0.5, 1.0 - 1e-6);
  if (!(map.grid.min_probability < map.grid.max_probability)) r.fail("grid min_probability must be below max_probability");
  map.map_points.cell_size_m = r.f64("point map cell_size_m", 1e-3, 100.0);
  map.map_points.normal_radius_m = r.f64("point map normal_radius_m", 1e-3, 100.0);
  map.map_points.normal_min_neighbours = static_cast<int>(r.integer32("point map normal_min_neighbours", 0, 1000000));
  map.map_points.normal_max_eigenvalue_ratio = r.f64("point map normal_max_eigenvalue_ratio", 0.0, 1.0);
  map.filter.min_range_m = r.f64("filter min_range_m", 0.0, 1e6);
  map.filter.max_range_m = r.f64("filter max_range_m", 0.0, 1e6);
  map.filter.missing_ray_length_m = r.f64("filter missing_ray_length_m", 0.0, 1e6);
  map.filter.voxel_size_m = r.f64("filter voxel_size_m", 0.0, 100.0);
  map.filter.adaptive_min_points = static_cast<int>(r.integer32("filter adaptive_min_points", 0, 100000000));
  map.filter.adaptive_max_voxel_size_m = r.f64("filter adaptive_max_voxel_size_m", 0.0, 100.0);
  const std::size_t source_bytes = r.count("source length", 1);
  if (source_bytes > kMaxSourceBytes) r.fail("source length: expected at most 65536 bytes, found " + std::to_string(source_bytes));
  const unsigned char* source = r.take(source_bytes, "source");
  map.source.assign(reinterpret_cast<const char*>(source), source_bytes);
  if (map.source.find('\0') != std::string::npos) r.fail("source: a NUL byte in the name");

  constexpr std::size_t kKeyframeBytes = 8 + 24 + 4;
  constexpr std::size_t kSubmapMinBytes = 24 + 12 + 16 + 8 + 4;
  const std::size_t keyframes = r.count("keyframe count", kKeyframeBytes);
  const std::size_t submaps = r.count("submap count", 1);
  map.keyframes.reserve(keyframes);
  for (std::size_t k = 0; k < keyframes; ++k) {
    const std::string field = "keyframe " + std::to_string(k);
    SavedKeyframe kf;
    kf.time = core::Timestamp::from_nanoseconds(r.i64(field + " time"));
    kf.T_world_laser = r.pose(field + " pose");
    kf.segment = static_cast<int>(r.integer32(field + " segment", 0, std::numeric_limits<std::int32_t>::max()));
    map.keyframes.push_back(kf);
  }
  if (static_cast<std::uint64_t>(submaps) * kSubmapMinBytes > r.left()) {
    r.fail("submap count " + std::to_string(submaps) + " needs at least " + std::to_string(submaps * kSubmapMinBytes) +
           " bytes, only " + std::to_string(r.left()) + " left");
  }
  const double min_l = log_odds(map.grid.min_probability), max_l = log_odds(map.grid.max_probability);
  map.submaps.reserve(submaps);
  for (std::size_t s = 0; s < submaps; ++s) {
    const std::string field = "submap " + std::to_string(s);
    SavedSubmap submap{core::SE2(), ProbabilityGrid(map.grid), {}, 0, 0, 0};
    submap.T_world_submap = r.pose(field + " pose");
    submap.segment = static_cast<int>(r.integer32(field + " segment", 0, std::numeric_limits<std::int32_t>::max()));
    const std::int64_t last_keyframe = static_cast<std::int64_t>(keyframes) - 1;
    submap.first_keyframe = static_cast<int>(r.integer32(field + " first_keyframe", 0, std::max<std::int64_t>(last_keyframe, 0)));
    submap.keyframe_count = static_cast<int>(r.integer32(field + " keyframe_count", 0, static_cast<std::int64_t>(keyframes)));
    const std::int64_t offset_i = r.i64(field + " grid offset_i");
    r.check_range(field + " grid offset_i", offset_i, -kMaxGridOffset + 1, kMaxGridOffset - 1);
    const std::int64_t offset_j = r.i64(field + " grid offset_j");
    r.check_range(field + " grid offset_j", offset_j, -kMaxGridOffset + 1, kMaxGridOffset - 1);
    const std::uint32_t width = r.u32(field + " grid width");
    r.check_range(field + " grid width", width, 0, kMaxGridSide);
    const std::uint32_t height = r.u32(field + " grid height");
    r.check_range(field + " grid height", height, 0, kMaxGridSide);
    if ((width == 0) != (height == 0)) r.fail(field + " grid: width and height must both be 0 or both positive");
    const std::uint64_t cells = static_cast<std::uint64_t>(width) * height;
    if (cells > kMaxGridCells) r.fail(field + " grid: " + std::to_string(cells) + " cells, at most 2^28 allowed");
    const std::size_t mask_bytes = static_cast<std::size_t>((cells + 7) / 8);
    const unsigned char* mask = r.take(mask_bytes, field + " known-cell mask");
    std::size_t known_cells = 0;
    for (std::size_t b = 0; b < mask_bytes; ++b) known_cells += static_cast<std::size_t>(std::popcount(mask[b]));
    if (cells % 8 != 0 && mask_bytes > 0 && (mask[mask_bytes - 1] >> (cells % 8)) != 0)
      r.fail(field + " known-cell mask: bits set past the last cell");
    if (cells > 0 && known_cells == 0) r.fail(field + " grid: no known cell (an empty grid is stored as 0 x 0)");
    if (static_cast<std::uint64_t>(known_cells) * 4 > r.left()) {
      r.fail(field + " grid: " + std::to_string(known_cells) + " known cells need " + std::to_string(known_cells * 4) +
             " bytes of log-odds, only " + std::to_string(r.left()) + " left");
    }
    std::vector<float> values(static_cast<std::size_t>(cells), 0.0f);
    std::vector<std::uint8_t> known(static_cast<std::size_t>(cells), 0);
    for (std::size_t k = 0; k < cells; ++k) {
      if (((mask[k / 8] >> (k % 8)) & 1u) == 0) continue;
      const float l = r.f32(field + " cell log-odds");
      const double value = static_cast<double>(l);
      if (!std::isfinite(value) || value < min_l - 1e-5 || value > max_l + 1e-5) {
        std::ostringstream message;
        message.precision(9);
        message << field << " cell " << k << " log-odds: expected a finite value in [" << min_l << ", " << max_l
                << "] (the grid's clamp), found " << value;
        r.fail(message.str());
      }
      values[k] = l;
      known[k] = 1;
    }
    submap.grid = ProbabilityGrid::from_cells(map.grid, static_cast<long>(offset_i), static_cast<long>(offset_j),
                                              static_cast<int>(width), static_cast<int>(height), std::move(values),
                                              std::move(known));
    const std::size_t points = r.count(field + " point count", 16);
    submap.points_submap.reserve(points);
    for (std::size_t k = 0; k < points; ++k) {
      const double x = r.f64(field + " point x", -1e9, 1e9);
      const double y = r.f64(field + " point y", -1e9, 1e9);
      submap.points_submap.emplace_back(x, y);
    }
    map.submaps.push_back(std::move(submap));
  }
  if (r.left() != 0) {
    throw io::ParseError(name, 0, "payload byte " + std::to_string(r.offset()) + ": " + std::to_string(r.left()) +
                                      " bytes after the last submap (expected the end of the payload)");
  }
  return map;
}

std::string inflate_payload(const unsigned char* data, std::size_t size, std::uint64_t payload_bytes,
                            const std::string& name) {
  z_stream stream{};
  if (inflateInit(&stream) != Z_OK) throw io::ParseError(name, 0, "cannot initialise zlib");
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
      throw io::ParseError(name, 0, "compressed payload ends early (" + std::to_string(produced) + " of " +
                                        std::to_string(payload_bytes) + " bytes)");
    }
    if (status != Z_OK && status != Z_BUF_ERROR) {
      const std::string message = stream.msg != nullptr ? stream.msg : "error " + std::to_string(status);
      inflateEnd(&stream);
      throw io::ParseError(name, 0, "corrupt compressed payload (zlib: " + message + ")");
    }
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END) {
    throw io::ParseError(name, 0, "compressed payload is longer than the " + std::to_string(payload_bytes) +
                                      " bytes the header declares");
  }
  if (produced != payload_bytes) {
    throw io::ParseError(name, 0, "compressed payload holds " + std::to_string(produced) + " bytes, the header declares " +
                                      std::to_string(payload_bytes));
  }
  if (consumed != size) {
    throw io::ParseError(name, 0, std::to_string(size - consumed) + " bytes after the end of the compressed payload");
  }
  out.resize(produced);
  return out;
}

}  // namespace

std::string encode_saved_map(const SavedMap2D& map) {
  const std::string payload = encode_payload(map);
  uLongf compressed_size = compressBound(static_cast<uLong>(payload.size()));
  std::string compressed(compressed_size, '\0');
  const int status = compress2(reinterpret_cast<Bytef*>(compressed.data()), &compressed_size,
                               reinterpret_cast<const Bytef*>(payload.data()), static_cast<uLong>(payload.size()),
                               Z_DEFAULT_COMPRESSION);
  CAIRN_ASSERT(status == Z_OK, "zlib compress2 failed on a buffer of compressBound size");
  compressed.resize(compressed_size);
  Writer w;
  w.raw(kMagic, sizeof kMagic);
  w.u32(kMapFileVersion);
  w.u32(0);  // flags
  w.u64(kHeaderBytes + compressed.size() + kTrailerBytes);
  w.u64(payload.size());
  w.raw(compressed.data(), compressed.size());
  std::string& bytes = w.bytes();
  w.u32(crc32_of(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()));
  return std::move(bytes);
}

void write_saved_map(const std::string& path, const SavedMap2D& map) {
  const std::string bytes = encode_saved_map(map);
  io::write_output(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

SavedMap2D decode_saved_map(const std::string& bytes, const std::string& name) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  if (bytes.empty()) throw io::ParseError(name, 0, "empty file: expected a cairn 2D map (cairn slam2d --save-map)");
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    throw io::ParseError(name, 0, "not a cairn 2D map file: expected the magic bytes \"CAIRNMAP\" at the start "
                                  "(write one with cairn slam2d --save-map)");
  }
  if (bytes.size() < kHeaderBytes + kTrailerBytes) {
    throw io::ParseError(name, 0, "file ends early: " + std::to_string(bytes.size()) + " bytes, a cairn map has at least " +
                                      std::to_string(kHeaderBytes + kTrailerBytes));
  }
  const std::uint32_t version = load_u32(data + 8);
  if (version == 0 || version > kMapFileVersion) {
    throw io::ParseError(name, 0, "map format version " + std::to_string(version) + ": this cairn reads version " +
                                      std::to_string(kMapFileVersion) +
                                      (version > kMapFileVersion ? " (the file was written by a newer cairn)" : ""));
  }
  const std::uint32_t flags = load_u32(data + 12);
  if (flags != 0) throw io::ParseError(name, 0, "header flags 0x" + hex32(flags) + ": expected 0 (no flags are defined)");
  const std::uint64_t file_bytes = load_u64(data + 16);
  if (file_bytes != bytes.size()) {
    throw io::ParseError(name, 0, "the header says the file has " + std::to_string(file_bytes) + " bytes, it has " +
                                      std::to_string(bytes.size()) +
                                      (file_bytes > bytes.size() ? " (truncated)" : " (data appended or header corrupt)"));
  }
  const std::size_t body = bytes.size() - kTrailerBytes;
  const std::uint32_t stored_crc = load_u32(data + body);
  const std::uint32_t computed_crc = crc32_of(data, body);
  if (stored_crc != computed_crc) {
    throw io::ParseError(name, 0, "checksum mismatch: the file stores CRC-32 " + hex32(stored_crc) + ", its content gives " +
                                      hex32(computed_crc) + " (the file is corrupt)");
  }
  const std::uint64_t payload_bytes = load_u64(data + 24);
  if (payload_bytes > kMaxPayloadBytes) {
    throw io::ParseError(name, 0, "payload size " + std::to_string(payload_bytes) + " bytes: at most 16 GiB allowed");
  }
  const std::string payload = inflate_payload(data + kHeaderBytes, body - kHeaderBytes, payload_bytes, name);
  return decode_payload(payload, name);
}

SavedMap2D read_saved_map(const std::string& path) {
  std::string bytes;
  if (path == "-") {
    bytes = io::standard_input(kMaxFileBytes);
  } else {
    io::check_input_file(path, "a map file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw io::ParseError(path, 0, std::string("cannot open: ") + std::strerror(errno));
    // Read in chunks (works for pipes and devices too), never past the largest map file.
    std::string chunk(std::size_t{1} << 20, '\0');
    while (in) {
      in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
      bytes.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
      if (bytes.size() > kMaxFileBytes) throw io::ParseError(path, 0, "larger than 4 GiB: not a cairn map file");
    }
    if (in.bad()) throw io::ParseError(path, 0, "cannot read the file");
  }
  return decode_saved_map(bytes, path == "-" ? "standard input" : path);
}

}  // namespace cairn::slam2d
