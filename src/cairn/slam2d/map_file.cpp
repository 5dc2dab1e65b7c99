#include "cairn/slam2d/map_file.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/io/map_container.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::slam2d {
namespace {

// The framing (magic, version, flags, sizes, zlib, CRC-32) and the checked little-endian writer and
// reader are io/map_container.hpp's, shared with the 3D LiDAR map; this file holds the payload.
constexpr std::uint32_t kMaxSourceBytes = 65536;
constexpr std::uint32_t kMaxGridSide = 65536;             // cells; 3.3 km at 5 cm
constexpr std::uint64_t kMaxGridCells = std::uint64_t{1} << 28;
constexpr std::int64_t kMaxGridOffset = 100000000;       // ProbabilityGrid's own bound (|offset| < this)

io::ContainerKind container_kind() { return io::known_container_kind("CAIRNMAP", kMapFileVersion); }

void write_pose(io::BinaryWriter& w, const core::SE2& T) {
  w.f64(T.x());
  w.f64(T.y());
  w.f64(T.angle());
}

std::string encode_payload(const SavedMap2D& map) {
  io::BinaryWriter w;
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
  w.string(map.source);
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

core::SE2 read_pose(io::BinaryReader& r, const std::string& field) {
  const double x = r.f64(field + " x", -1e9, 1e9);
  const double y = r.f64(field + " y", -1e9, 1e9);
  // Written as SE2::angle(), in (-pi, pi]; a little slack for other writers.
  const double theta = r.f64(field + " theta", -std::numbers::pi - 1e-9, std::numbers::pi + 1e-9);
  return core::SE2(x, y, theta);
}

double log_odds(double p) { return std::log(p / (1.0 - p)); }

// The map header: what the map was built with. Ranges: what ProbabilityGrid, PointMap and the scan
// filter accept, within sane physical bounds.
void decode_settings(io::BinaryReader& r, SavedMap2D& map) {
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
  map.source = r.string("source", kMaxSourceBytes);
  if (map.source.find('\0') != std::string::npos) r.fail("source: a NUL byte in the name");
}

// A submap's grid: offsets, size, known-cell mask, then the log-odds of the known cells, each
// within the grid's clamp [min_l, max_l]. Nothing is allocated before the mask and the bytes
// left show the cells can be there.
ProbabilityGrid decode_grid(io::BinaryReader& r, const std::string& field, const ProbabilityGridOptions& options) {
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
  const double min_l = log_odds(options.min_probability), max_l = log_odds(options.max_probability);
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
  return ProbabilityGrid::from_cells(options, static_cast<long>(offset_i), static_cast<long>(offset_j),
                                     static_cast<int>(width), static_cast<int>(height), std::move(values), std::move(known));
}

SavedSubmap decode_submap(io::BinaryReader& r, std::size_t s, std::size_t keyframes, const ProbabilityGridOptions& options) {
  const std::string field = "submap " + std::to_string(s);
  SavedSubmap submap{core::SE2(), ProbabilityGrid(options), {}, 0, 0, 0};
  submap.T_world_submap = read_pose(r, field + " pose");
  submap.segment = static_cast<int>(r.integer32(field + " segment", 0, std::numeric_limits<std::int32_t>::max()));
  const std::int64_t last_keyframe = static_cast<std::int64_t>(keyframes) - 1;
  submap.first_keyframe = static_cast<int>(r.integer32(field + " first_keyframe", 0, std::max<std::int64_t>(last_keyframe, 0)));
  submap.keyframe_count = static_cast<int>(r.integer32(field + " keyframe_count", 0, static_cast<std::int64_t>(keyframes)));
  submap.grid = decode_grid(r, field, options);
  const std::size_t points = r.count(field + " point count", 16);
  submap.points_submap.reserve(points);
  for (std::size_t k = 0; k < points; ++k) {
    const double x = r.f64(field + " point x", -1e9, 1e9);
    const double y = r.f64(field + " point y", -1e9, 1e9);
    submap.points_submap.emplace_back(x, y);
  }
  return submap;
}

SavedMap2D decode_payload(const std::string& payload, const std::string& name) {
  io::BinaryReader r(payload, name);
  SavedMap2D map;
  decode_settings(r, map);
  constexpr std::size_t kKeyframeBytes = 8 + 24 + 4;
  constexpr std::size_t kSubmapMinBytes = 24 + 12 + 16 + 8 + 4;
  const std::size_t keyframes = r.count("keyframe count", kKeyframeBytes);
  const std::size_t submaps = r.count("submap count", 1);
  map.keyframes.reserve(keyframes);
  for (std::size_t k = 0; k < keyframes; ++k) {
    const std::string field = "keyframe " + std::to_string(k);
    SavedKeyframe kf;
    kf.time = core::Timestamp::from_nanoseconds(r.i64(field + " time"));
    kf.T_world_laser = read_pose(r, field + " pose");
    kf.segment = static_cast<int>(r.integer32(field + " segment", 0, std::numeric_limits<std::int32_t>::max()));
    map.keyframes.push_back(kf);
  }
  if (static_cast<std::uint64_t>(submaps) * kSubmapMinBytes > r.left()) {
    r.fail("submap count " + std::to_string(submaps) + " needs at least " + std::to_string(submaps * kSubmapMinBytes) +
           " bytes, only " + std::to_string(r.left()) + " left");
  }
  map.submaps.reserve(submaps);
  for (std::size_t s = 0; s < submaps; ++s) map.submaps.push_back(decode_submap(r, s, keyframes, map.grid));
  r.expect_end("submap");
  return map;
}

}  // namespace

std::string encode_saved_map(const SavedMap2D& map) { return io::encode_container(container_kind(), encode_payload(map)); }

void write_saved_map(const std::string& path, const SavedMap2D& map) {
  const std::string bytes = encode_saved_map(map);
  io::write_output(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

SavedMap2D decode_saved_map(const std::string& bytes, const std::string& name) {
  return decode_payload(io::decode_container(bytes, name, container_kind()), name);
}

SavedMap2D read_saved_map(const std::string& path) {
  return decode_saved_map(io::read_container_file(path, "a map file"), path == "-" ? "standard input" : path);
}

}  // namespace cairn::slam2d
