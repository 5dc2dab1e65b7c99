#include "cairn/lidar3d/map_file.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstddef>
#include <limits>

#include "cairn/core/assert.hpp"
#include "cairn/io/map_container.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::lidar3d {
namespace {

// The framing (magic, version, flags, sizes, zlib, CRC-32) and the checked little-endian writer and
// reader are io/map_container.hpp's, shared with the 2D map (slam2d/map_file.cpp); this file holds
// the payload, laid out in docs/formats.md ("cairn 3D LiDAR map").
constexpr std::uint32_t kMaxSourceBytes = 65536;
constexpr std::uint32_t kMaxConfigurationBytes = std::uint32_t{1} << 20;
constexpr std::int64_t kMaxDescriptorEntries = std::int64_t{1} << 20;  // rings x sectors (default 20 x 60)
constexpr double kMaxCoordinate = 1e7;   // metres, map points (f32 steps are 1 m there)
constexpr double kMaxTranslation = 1e9;  // metres, poses (as the 2D map)
constexpr double kUnitQuaternionTolerance = 1e-6;
constexpr double kUnitNormalTolerance = 1e-3;
constexpr std::size_t kPointBytes = 12 + 12;                         // f32 x y z of the point and of its normal
constexpr std::size_t kPoseBytes = 24 + 32;                          // f64 translation, f64 quaternion x y z w
constexpr std::size_t kKeyframeFixedBytes = 8 + 8 + kPoseBytes + 4;  // then 4 bytes per descriptor entry
constexpr std::size_t kEdgeBytes = 4 + 4 + kPoseBytes + 21 * 8 + 1;

// Enum codes of the file, index = code: the file's numbering never follows a reordering of the enums.
constexpr FrontEnd kFrontEndCodes[] = {FrontEnd::kDense, FrontEnd::kLoamFeatures};
constexpr DeskewMode kDeskewCodes[] = {DeskewMode::kOff, DeskewMode::kPointTimes, DeskewMode::kAzimuth};

io::ContainerKind container_kind() { return io::known_container_kind("CAIRN3DM", kMap3dFileVersion); }

std::string text(double v) {
  std::string out;
  io::append_number(out, v);
  return out;
}

template <typename Enum, std::size_t N>
std::uint32_t code_of(const Enum (&codes)[N], Enum value, const char* what) {
  for (std::size_t c = 0; c < N; ++c) {
    if (codes[c] == value) return static_cast<std::uint32_t>(c);
  }
  CAIRN_ASSERT(false, what);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Writing.

void write_pose(io::BinaryWriter& w, const core::SE3& T) {
  for (int i = 0; i < 3; ++i) w.f64(T.translation()[i]);
  const Eigen::Quaterniond& q = T.unit_quaternion();
  w.f64(q.x());
  w.f64(q.y());
  w.f64(q.z());
  w.f64(q.w());
}

void encode_options(io::BinaryWriter& w, const SavedMap3D& map) {
  const SavedSensorModel& s = map.sensor;
  w.u32(code_of(kFrontEndCodes, s.front_end, "a saved map's front end must be kDense or kLoamFeatures, never kAuto"));
  w.u32(code_of(kDeskewCodes, s.deskew, "a deskew mode without a file code"));
  w.f64(s.min_range_m);
  w.f64(s.max_range_m);
  w.f64(s.vertical_angle_correction_rad);
  w.f64(s.sweep_period_s);
  w.f64(s.voxel_size_m);
  w.i32(s.max_points_per_voxel);
  w.u8(s.rings_from_kitti_order ? 1 : 0);
  const ScanContextOptions& o = map.scan_context;
  w.i32(o.rings);
  w.i32(o.sectors);
  w.f64(o.max_radius_m);
  w.f64(o.sensor_height_m);
  w.i32(o.candidates);
  w.f64(o.search_ratio);
  w.i32(o.exclude_recent);
  w.f64(o.max_distance);
  w.i32(o.tree_rebuild_period);
  w.u32(static_cast<std::uint32_t>(o.lateral_offsets_m.size()));
  for (const double offset : o.lateral_offsets_m) w.f64(offset);
  w.f64(map.map_voxel_m);
  CAIRN_ASSERT(map.configuration_json.size() <= kMaxConfigurationBytes, "map configuration JSON longer than 1 MiB");
  w.string(map.configuration_json);
  CAIRN_ASSERT(map.source.size() <= kMaxSourceBytes, "map source name longer than 64 KiB");
  w.string(map.source);
}

void encode_graph(io::BinaryWriter& w, const SavedMap3D& map) {
  const Eigen::Index rings = map.scan_context.rings, sectors = map.scan_context.sectors;
  w.u32(static_cast<std::uint32_t>(map.keyframes.size()));
  for (const SavedKeyframe3D& kf : map.keyframes) {
    w.f64(kf.time_s);
    w.u64(static_cast<std::uint64_t>(kf.scan));
    write_pose(w, kf.T_world_sensor);
    w.i32(kf.segment);
    CAIRN_ASSERT(kf.scan_context.rows() == rings && kf.scan_context.cols() == sectors,
                 "a keyframe's Scan Context must be scan_context.rings x scan_context.sectors");
    for (Eigen::Index i = 0; i < rings; ++i) {
      for (Eigen::Index j = 0; j < sectors; ++j) w.f32(kf.scan_context(i, j));  // ring by ring
    }
  }
  w.u32(static_cast<std::uint32_t>(map.edges.size()));
  for (const SavedEdge3D& edge : map.edges) {
    w.i32(edge.from);
    w.i32(edge.to);
    write_pose(w, edge.T_from_to);
    for (int r = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) w.f64(edge.information(r, c));  // upper triangle, row by row (g2o's order)
    }
    w.u8(edge.loop ? 1 : 0);
  }
}

std::string encode_payload(const SavedMap3D& map) {
  io::BinaryWriter w;
  encode_options(w, map);
  CAIRN_ASSERT(map.points_world.size() == map.normals_world.size(), "a saved map needs one normal per point");
  CAIRN_ASSERT(map.points_world.size() <= std::numeric_limits<std::uint32_t>::max(), "more than 2^32 - 1 map points");
  w.u32(static_cast<std::uint32_t>(map.points_world.size()));
  for (const Eigen::Vector3f& p : map.points_world) {
    for (int i = 0; i < 3; ++i) w.f32(p[i]);
  }
  for (const Eigen::Vector3f& n : map.normals_world) {
    for (int i = 0; i < 3; ++i) w.f32(n[i]);
  }
  encode_graph(w, map);
  return std::move(w.bytes());
}

// ---------------------------------------------------------------------------------------------
// Reading.

template <typename Enum, std::size_t N>
Enum read_code(io::BinaryReader& r, const std::string& field, const Enum (&codes)[N]) {
  const std::uint32_t code = r.u32(field);
  if (code >= N) {
    std::string known;
    for (std::size_t c = 0; c < N; ++c) {
      known += (c == 0 ? "" : ", ") + std::to_string(c) + " (" + std::string(to_string(codes[c])) + ")";
    }
    r.fail(field + ": expected one of " + known + ", found " + std::to_string(code));
  }
  return codes[code];
}

// Checked as LidarOdometryOptions::is_valid checks the same fields, so a map holds only a sensor
// model the odometry would have run with.
SavedSensorModel decode_sensor_model(io::BinaryReader& r) {
  const std::size_t at = r.offset();
  SavedSensorModel s;
  s.front_end = read_code(r, "sensor front_end", kFrontEndCodes);
  s.deskew = read_code(r, "sensor deskew", kDeskewCodes);
  s.min_range_m = r.finite_f64("sensor min_range_m");
  s.max_range_m = r.finite_f64("sensor max_range_m");
  s.vertical_angle_correction_rad = r.finite_f64("sensor vertical_angle_correction_rad");
  s.sweep_period_s = r.finite_f64("sensor sweep_period_s");
  s.voxel_size_m = r.finite_f64("sensor voxel_size_m");
  s.max_points_per_voxel = r.i32("sensor max_points_per_voxel");
  const std::uint8_t kitti_order = r.u8("sensor rings_from_kitti_order");
  if (kitti_order > 1) r.fail("sensor rings_from_kitti_order: expected 0 or 1, found " + std::to_string(kitti_order));
  s.rings_from_kitti_order = kitti_order == 1;
  LidarOdometryOptions odometry;
  odometry.front_end = s.front_end;
  odometry.deskew = s.deskew;
  odometry.min_range_m = s.min_range_m;
  odometry.max_range_m = s.max_range_m;
  odometry.vertical_angle_correction_rad = s.vertical_angle_correction_rad;
  odometry.sweep_period_s = s.sweep_period_s;
  odometry.voxel_size_m = s.voxel_size_m;
  odometry.max_points_per_voxel = s.max_points_per_voxel;
  if (std::string why; !odometry.is_valid(&why)) r.fail_at(at, "sensor model: " + why);
  return s;
}

// ScanContextOptions::is_valid decides; the descriptor size is bounded on top, since every keyframe
// holds rings x sectors floats.
ScanContextOptions decode_scan_context_options(io::BinaryReader& r) {
  const std::size_t at = r.offset();
  ScanContextOptions o;
  o.rings = r.i32("scan context rings");
  o.sectors = r.i32("scan context sectors");
  o.max_radius_m = r.finite_f64("scan context max_radius_m");
  o.sensor_height_m = r.finite_f64("scan context sensor_height_m");
  o.candidates = r.i32("scan context candidates");
  o.search_ratio = r.finite_f64("scan context search_ratio");
  o.exclude_recent = r.i32("scan context exclude_recent");
  o.max_distance = r.finite_f64("scan context max_distance");
  o.tree_rebuild_period = r.i32("scan context tree_rebuild_period");
  const std::size_t offsets = r.count("scan context lateral_offsets_m count", 8);
  o.lateral_offsets_m.reserve(offsets);
  for (std::size_t k = 0; k < offsets; ++k) {
    o.lateral_offsets_m.push_back(r.finite_f64("scan context lateral_offsets_m " + std::to_string(k)));
  }
  if (std::string why; !o.is_valid(&why)) r.fail_at(at, "scan context options: " + why);
  const std::int64_t entries = std::int64_t{o.rings} * o.sectors;
  if (entries > kMaxDescriptorEntries) {
    r.fail_at(at, "scan context options: rings x sectors = " + std::to_string(entries) +
                      " descriptor entries, at most 2^20 allowed");
  }
  return o;
}

// Points, then normals, each a block of x y z f32 taken whole (the count was checked against the
// bytes left) and decoded in place.
void decode_points(io::BinaryReader& r, SavedMap3D& map) {
  const std::size_t points = r.count("point count", kPointBytes);
  const std::size_t points_at = r.offset();
  const unsigned char* p = r.take(12 * points, "points");
  const std::size_t normals_at = r.offset();
  const unsigned char* n = r.take(12 * points, "normals");
  auto value = [](const unsigned char* block, std::size_t k, int i) {
    return std::bit_cast<float>(io::load_u32(block + 12 * k + 4 * static_cast<std::size_t>(i)));
  };
  map.points_world.resize(points);
  map.normals_world.resize(points);
  for (std::size_t k = 0; k < points; ++k) {
    for (int i = 0; i < 3; ++i) {
      const float c = value(p, k, i);
      if (!(std::abs(static_cast<double>(c)) <= kMaxCoordinate)) {
        r.fail_at(points_at + 12 * k + 4 * static_cast<std::size_t>(i),
                  "point " + std::to_string(k) + " " + "xyz"[i] + ": expected a finite coordinate within 1e7 m, found " +
                      text(static_cast<double>(c)));
      }
      map.points_world[k][i] = c;
      map.normals_world[k][i] = value(n, k, i);
    }
    const Eigen::Vector3f& normal = map.normals_world[k];
    const double norm = normal.cast<double>().norm();
    if (!((normal.array() == 0.0f).all() || std::abs(norm - 1.0) <= kUnitNormalTolerance)) {
      r.fail_at(normals_at + 12 * k, "normal " + std::to_string(k) +
                                         ": expected zero or a unit vector (norm within 1e-3 of 1), found norm " + text(norm));
    }
  }
}

// Translation within 1e9 m; quaternion x y z w of norm 1 to 1e-6, normalised (a unit quaternion is
// kept bit for bit: core/so3.hpp).
core::SE3 read_pose(io::BinaryReader& r, const std::string& field) {
  Eigen::Vector3d t;
  for (int i = 0; i < 3; ++i) t[i] = r.f64(field + " " + "xyz"[i], -kMaxTranslation, kMaxTranslation);
  const std::size_t at = r.offset();
  const double qx = r.finite_f64(field + " qx"), qy = r.finite_f64(field + " qy");
  const double qz = r.finite_f64(field + " qz"), qw = r.finite_f64(field + " qw");
  const Eigen::Quaterniond q(qw, qx, qy, qz);
  const double norm = q.norm();  // components finite: at worst inf, never NaN
  if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
    r.fail_at(at, field + " quaternion: expected a unit quaternion (norm within 1e-6 of 1), found norm " + text(norm));
  }
  return core::SE3(q, t);
}

SavedKeyframe3D decode_keyframe(io::BinaryReader& r, std::size_t k, const ScanContextOptions& options) {
  const std::string field = "keyframe " + std::to_string(k);
  SavedKeyframe3D kf;
  kf.time_s = r.finite_f64(field + " time_s");
  const std::uint64_t scan = r.u64(field + " scan");
  if constexpr (sizeof(std::size_t) < sizeof(std::uint64_t)) {
    if (scan > std::numeric_limits<std::size_t>::max()) r.fail(field + " scan: index too large for this machine");
  }
  kf.scan = static_cast<std::size_t>(scan);
  kf.T_world_sensor = read_pose(r, field + " pose");
  kf.segment = static_cast<int>(r.integer32(field + " segment", 0, std::numeric_limits<std::int32_t>::max()));
  const std::size_t rings = static_cast<std::size_t>(options.rings), sectors = static_cast<std::size_t>(options.sectors);
  const std::size_t at = r.offset();
  const unsigned char* d = r.take(4 * rings * sectors, field + " scan context");
  kf.scan_context.resize(options.rings, options.sectors);
  for (std::size_t i = 0; i < rings; ++i) {
    for (std::size_t j = 0; j < sectors; ++j) {
      const std::size_t entry = i * sectors + j;  // ring by ring
      const float v = std::bit_cast<float>(io::load_u32(d + 4 * entry));
      if (!(std::isfinite(v) && v >= 0.0f)) {
        r.fail_at(at + 4 * entry, field + " scan context ring " + std::to_string(i) + " sector " + std::to_string(j) +
                                      ": expected a finite height >= 0, found " + text(static_cast<double>(v)));
      }
      kf.scan_context(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = v;
    }
  }
  return kf;
}

SavedEdge3D decode_edge(io::BinaryReader& r, std::size_t e, std::size_t keyframes) {
  const std::string field = "edge " + std::to_string(e);
  const std::int64_t last = static_cast<std::int64_t>(keyframes) - 1;
  SavedEdge3D edge;
  edge.from = r.i32(field + " from");
  if (keyframes == 0) r.fail(field + ": the map has no keyframes for an edge to join");
  r.check_range(field + " from", edge.from, 0, last);
  edge.to = static_cast<int>(r.integer32(field + " to", 0, last));
  if (edge.from == edge.to) r.fail(field + ": from and to are both keyframe " + std::to_string(edge.to));
  edge.T_from_to = read_pose(r, field + " pose");
  const std::size_t at = r.offset();
  for (int row = 0; row < 6; ++row) {
    for (int col = row; col < 6; ++col) {
      const double v = r.finite_f64(field + " information (" + std::to_string(row) + ", " + std::to_string(col) + ")");
      edge.information(row, col) = v;
      edge.information(col, row) = v;
    }
  }
  // Cholesky succeeds exactly for a symmetric positive definite matrix (an overflow shows as a
  // non-finite factor).
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(edge.information);
  if (llt.info() != Eigen::Success || !llt.matrixLLT().allFinite()) {
    r.fail_at(at, field + " information: expected a symmetric positive definite matrix (its Cholesky factorisation fails)");
  }
  const std::uint8_t loop = r.u8(field + " loop");
  if (loop > 1) r.fail(field + " loop: expected 0 or 1, found " + std::to_string(loop));
  edge.loop = loop == 1;
  return edge;
}

SavedMap3D decode_payload(const std::string& payload, const std::string& name) {
  io::BinaryReader r(payload, name);
  SavedMap3D map;
  map.sensor = decode_sensor_model(r);
  map.scan_context = decode_scan_context_options(r);
  map.map_voxel_m = r.finite_f64("map_voxel_m");
  if (!(map.map_voxel_m > 0.0)) r.fail("map_voxel_m: expected a number > 0, found " + text(map.map_voxel_m));
  map.configuration_json = r.string("configuration_json", kMaxConfigurationBytes);
  map.source = r.string("source", kMaxSourceBytes);
  if (map.source.find('\0') != std::string::npos) r.fail("source: a NUL byte in the name");
  decode_points(r, map);
  const std::size_t descriptor_bytes =
      4 * static_cast<std::size_t>(map.scan_context.rings) * static_cast<std::size_t>(map.scan_context.sectors);
  const std::size_t keyframes = r.count("keyframe count", kKeyframeFixedBytes + descriptor_bytes);
  map.keyframes.reserve(keyframes);
  for (std::size_t k = 0; k < keyframes; ++k) map.keyframes.push_back(decode_keyframe(r, k, map.scan_context));
  const std::size_t edges = r.count("edge count", kEdgeBytes);
  map.edges.reserve(edges);
  for (std::size_t e = 0; e < edges; ++e) map.edges.push_back(decode_edge(r, e, keyframes));
  r.expect_end("edge");
  return map;
}

}  // namespace

std::string encode_saved_map(const SavedMap3D& map) { return io::encode_container(container_kind(), encode_payload(map)); }

void write_saved_map(const std::string& path, const SavedMap3D& map) {
  const std::string bytes = encode_saved_map(map);
  io::write_output(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

SavedMap3D decode_saved_map(const std::string& bytes, const std::string& name) {
  return decode_payload(io::decode_container(bytes, name, container_kind()), name);
}

SavedMap3D read_saved_map(const std::string& path) {
  return decode_saved_map(io::read_container_file(path, "a map file"), path == "-" ? "standard input" : path);
}

}  // namespace cairn::lidar3d
