// The saved 3D LiDAR map file (lidar3d/map_file.hpp, docs/formats.md "cairn 3D LiDAR map"): round
// trip of a map built by hand, the layout of the payload written independently here from the
// documentation, and every kind of corruption (truncation at every length, flipped bytes, the
// wrong kind of file, a future version, bad fields behind a valid checksum). The model is the 2D
// map's test (tests/slam2d/test_localization.cpp, MapFile.*).

#include <gtest/gtest.h>

#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/io/map_container.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/lidar3d/map_file.hpp"
#include "cairn/slam2d/map_file.hpp"

namespace cairn::lidar3d {
namespace {

namespace fs = std::filesystem;

core::SE3 random_pose(std::mt19937& random, double extent_m) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const core::SO3 R = core::SO3::exp(Eigen::Vector3d(unit(random), unit(random), 3.0 * unit(random)));
  return core::SE3(R, Eigen::Vector3d(extent_m * unit(random), extent_m * unit(random), unit(random)));
}

// Symmetric positive definite, exactly symmetric (the file stores the upper triangle).
Eigen::Matrix<double, 6, 6> random_information(std::mt19937& random) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::Matrix<double, 6, 6> A;
  for (int i = 0; i < 36; ++i) A(i / 6, i % 6) = unit(random);
  Eigen::Matrix<double, 6, 6> information = 50.0 * A * A.transpose() + Eigen::Matrix<double, 6, 6>::Identity();
  return 0.5 * (information + information.transpose()).eval();
}

// A map by hand, with settings away from every default (so a reader that ignored a field would be
// caught): `points` points with normals (every third zero, the others unit), 4 keyframes with
// random descriptors, three odometry edges and one loop closure.
SavedMap3D hand_map(std::size_t points, int rings, int sectors) {
  SavedMap3D map;
  map.sensor.front_end = FrontEnd::kLoamFeatures;
  map.sensor.rings_from_kitti_order = true;
  map.sensor.min_range_m = 0.75;
  map.sensor.max_range_m = 82.5;
  map.sensor.deskew = DeskewMode::kAzimuth;
  map.sensor.vertical_angle_correction_rad = 3.578e-3;
  map.sensor.sweep_period_s = 0.05;
  map.sensor.voxel_size_m = 0.85;
  map.sensor.max_points_per_voxel = 13;
  map.scan_context.rings = rings;
  map.scan_context.sectors = sectors;
  map.scan_context.max_radius_m = 55.5;
  map.scan_context.sensor_height_m = 1.73;
  map.scan_context.candidates = 7;
  map.scan_context.search_ratio = 0.25;
  map.scan_context.exclude_recent = 3;
  map.scan_context.max_distance = 0.31;
  map.scan_context.tree_rebuild_period = 9;
  map.scan_context.lateral_offsets_m = {-3.5, 2.25};
  map.map_voxel_m = 0.35;
  map.configuration_json = R"({"odometry":{"voxel_size_m":0.85},"loop":{"enabled":true}})";
  map.source = "synthetic/straße.bag";
  std::mt19937 random(42);
  std::uniform_real_distribution<float> coordinate(-120.0f, 120.0f);
  std::normal_distribution<float> gaussian(0.0f, 1.0f);
  for (std::size_t k = 0; k < points; ++k) {
    map.points_world.emplace_back(coordinate(random), coordinate(random), 0.1f * coordinate(random));
    const Eigen::Vector3f n(gaussian(random), gaussian(random), gaussian(random));
    map.normals_world.push_back(k % 3 == 0 ? Eigen::Vector3f::Zero() : Eigen::Vector3f(n.normalized()));
  }
  std::uniform_real_distribution<float> height(0.0f, 6.0f);
  for (int k = 0; k < 4; ++k) {
    SavedKeyframe3D kf;
    kf.time_s = 1317384506.25 + 0.1 * k;
    kf.scan = static_cast<std::size_t>(10 * k + 3);
    kf.T_world_sensor = random_pose(random, 30.0);
    kf.segment = k / 2;
    kf.scan_context = Eigen::MatrixXf(rings, sectors);
    for (int i = 0; i < rings; ++i) {
      for (int j = 0; j < sectors; ++j) kf.scan_context(i, j) = (i + j) % 5 == 0 ? 0.0f : height(random);
    }
    map.keyframes.push_back(kf);
  }
  for (int k = 0; k < 4; ++k) {
    SavedEdge3D edge;
    edge.from = k < 3 ? k : 3;
    edge.to = k < 3 ? k + 1 : 0;
    edge.T_from_to = random_pose(random, 3.0);
    edge.information = random_information(random);
    edge.loop = k == 3;
    map.edges.push_back(edge);
  }
  return map;
}

SavedMap3D map_of_300_points() { return hand_map(300, 6, 10); }
SavedMap3D tiny_map() { return hand_map(4, 2, 3); }

void expect_same_pose(const core::SE3& a, const core::SE3& b, const std::string& what) {
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.translation()[i], b.translation()[i]) << what;
  for (int i = 0; i < 4; ++i) EXPECT_EQ(a.unit_quaternion().coeffs()[i], b.unit_quaternion().coeffs()[i]) << what;
}

// Every field, doubles and floats with ==.
void expect_same_map(const SavedMap3D& a, const SavedMap3D& b) {
  EXPECT_EQ(a.sensor.front_end, b.sensor.front_end);
  EXPECT_EQ(a.sensor.rings_from_kitti_order, b.sensor.rings_from_kitti_order);
  EXPECT_EQ(a.sensor.min_range_m, b.sensor.min_range_m);
  EXPECT_EQ(a.sensor.max_range_m, b.sensor.max_range_m);
  EXPECT_EQ(a.sensor.deskew, b.sensor.deskew);
  EXPECT_EQ(a.sensor.vertical_angle_correction_rad, b.sensor.vertical_angle_correction_rad);
  EXPECT_EQ(a.sensor.sweep_period_s, b.sensor.sweep_period_s);
  EXPECT_EQ(a.sensor.voxel_size_m, b.sensor.voxel_size_m);
  EXPECT_EQ(a.sensor.max_points_per_voxel, b.sensor.max_points_per_voxel);
  EXPECT_EQ(a.scan_context.rings, b.scan_context.rings);
  EXPECT_EQ(a.scan_context.sectors, b.scan_context.sectors);
  EXPECT_EQ(a.scan_context.max_radius_m, b.scan_context.max_radius_m);
  EXPECT_EQ(a.scan_context.sensor_height_m, b.scan_context.sensor_height_m);
  EXPECT_EQ(a.scan_context.candidates, b.scan_context.candidates);
  EXPECT_EQ(a.scan_context.search_ratio, b.scan_context.search_ratio);
  EXPECT_EQ(a.scan_context.exclude_recent, b.scan_context.exclude_recent);
  EXPECT_EQ(a.scan_context.max_distance, b.scan_context.max_distance);
  EXPECT_EQ(a.scan_context.tree_rebuild_period, b.scan_context.tree_rebuild_period);
  EXPECT_EQ(a.scan_context.lateral_offsets_m, b.scan_context.lateral_offsets_m);
  EXPECT_EQ(a.map_voxel_m, b.map_voxel_m);
  EXPECT_EQ(a.configuration_json, b.configuration_json);
  EXPECT_EQ(a.source, b.source);
  EXPECT_TRUE(a.points_world == b.points_world);
  EXPECT_TRUE(a.normals_world == b.normals_world);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t k = 0; k < a.keyframes.size(); ++k) {
    const std::string what = "keyframe " + std::to_string(k);
    EXPECT_EQ(a.keyframes[k].time_s, b.keyframes[k].time_s) << what;
    EXPECT_EQ(a.keyframes[k].scan, b.keyframes[k].scan) << what;
    expect_same_pose(a.keyframes[k].T_world_sensor, b.keyframes[k].T_world_sensor, what);
    EXPECT_EQ(a.keyframes[k].segment, b.keyframes[k].segment) << what;
    ASSERT_EQ(a.keyframes[k].scan_context.rows(), b.keyframes[k].scan_context.rows()) << what;
    ASSERT_EQ(a.keyframes[k].scan_context.cols(), b.keyframes[k].scan_context.cols()) << what;
    EXPECT_TRUE(a.keyframes[k].scan_context == b.keyframes[k].scan_context) << what;
  }
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (std::size_t e = 0; e < a.edges.size(); ++e) {
    const std::string what = "edge " + std::to_string(e);
    EXPECT_EQ(a.edges[e].from, b.edges[e].from) << what;
    EXPECT_EQ(a.edges[e].to, b.edges[e].to) << what;
    expect_same_pose(a.edges[e].T_from_to, b.edges[e].T_from_to, what);
    EXPECT_TRUE(a.edges[e].information == b.edges[e].information) << what;
    EXPECT_EQ(a.edges[e].loop, b.edges[e].loop) << what;
  }
}

// ---------------------------------------------------------------------------------------------
// The payload written here, field by field as docs/formats.md lays it out, independently of the
// writer under test; `Tamper` changes what the map itself cannot hold.

struct Tamper {
  std::optional<std::uint32_t> front_end_code;
  double keyframe_1_quaternion_scale = 1.0;
  std::optional<std::uint32_t> keyframe_count;
  std::optional<std::uint8_t> last_loop_code;
};

void write_pose(io::BinaryWriter& w, const core::SE3& T, double quaternion_scale = 1.0) {
  for (int i = 0; i < 3; ++i) w.f64(T.translation()[i]);
  for (int i = 0; i < 4; ++i) w.f64(quaternion_scale * T.unit_quaternion().coeffs()[i]);  // x y z w
}

std::string payload_by_hand(const SavedMap3D& map, const Tamper& tamper = {}) {
  io::BinaryWriter w;
  w.u32(tamper.front_end_code.value_or(map.sensor.front_end == FrontEnd::kDense ? 0 : 1));
  w.u32(map.sensor.deskew == DeskewMode::kOff ? 0 : map.sensor.deskew == DeskewMode::kPointTimes ? 1 : 2);
  for (const double v : {map.sensor.min_range_m, map.sensor.max_range_m, map.sensor.vertical_angle_correction_rad,
                         map.sensor.sweep_period_s, map.sensor.voxel_size_m}) {
    w.f64(v);
  }
  w.i32(map.sensor.max_points_per_voxel);
  w.u8(map.sensor.rings_from_kitti_order ? 1 : 0);
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
  w.string(map.configuration_json);
  w.string(map.source);
  w.u32(static_cast<std::uint32_t>(map.points_world.size()));
  for (const Eigen::Vector3f& p : map.points_world) {
    for (int i = 0; i < 3; ++i) w.f32(p[i]);
  }
  for (const Eigen::Vector3f& n : map.normals_world) {
    for (int i = 0; i < 3; ++i) w.f32(n[i]);
  }
  w.u32(tamper.keyframe_count.value_or(static_cast<std::uint32_t>(map.keyframes.size())));
  for (std::size_t k = 0; k < map.keyframes.size(); ++k) {
    const SavedKeyframe3D& kf = map.keyframes[k];
    w.f64(kf.time_s);
    w.u64(kf.scan);
    write_pose(w, kf.T_world_sensor, k == 1 ? tamper.keyframe_1_quaternion_scale : 1.0);
    w.i32(kf.segment);
    for (int i = 0; i < o.rings; ++i) {
      for (int j = 0; j < o.sectors; ++j) w.f32(kf.scan_context(i, j));
    }
  }
  w.u32(static_cast<std::uint32_t>(map.edges.size()));
  for (std::size_t e = 0; e < map.edges.size(); ++e) {
    const SavedEdge3D& edge = map.edges[e];
    w.i32(edge.from);
    w.i32(edge.to);
    write_pose(w, edge.T_from_to);
    for (int r = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) w.f64(edge.information(r, c));
    }
    w.u8(e + 1 == map.edges.size() && tamper.last_loop_code ? *tamper.last_loop_code : edge.loop ? 1 : 0);
  }
  return std::move(w.bytes());
}

const io::ContainerKind& kind_3d() {
  static const io::ContainerKind kind{
      {'C', 'A', 'I', 'R', 'N', '3', 'D', 'M'}, 1, "cairn 3D LiDAR map", "cairn slam3d --save-map"};
  return kind;
}

std::string file_of(const std::string& payload) { return io::encode_container(kind_3d(), payload); }

// Expects decode to throw a ParseError naming the file whose message contains every one of `expected`.
void expect_parse_error(const std::string& bytes, const std::vector<std::string>& expected, const std::string& context) {
  try {
    decode_saved_map(bytes, "map.c3dm");
    ADD_FAILURE() << context << ": accepted";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.file(), "map.c3dm") << context;
    for (const std::string& part : expected) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << context << ": " << e.what();
    }
  }
}

void store_u32(std::string& bytes, std::size_t at, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) bytes[at + static_cast<std::size_t>(b)] = static_cast<char>((v >> (8 * b)) & 0xff);
}
void fix_crc(std::string& bytes) {
  store_u32(bytes, bytes.size() - 4, io::crc32_of(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size() - 4));
}

// ---------------------------------------------------------------------------------------------

TEST(MapFile3d, RoundTripKeepsEveryFieldBitForBit) {
  const SavedMap3D map = map_of_300_points();
  const std::string bytes = encode_saved_map(map);
  const SavedMap3D back = decode_saved_map(bytes, "map.c3dm");
  expect_same_map(map, back);
  EXPECT_EQ(encode_saved_map(back), bytes);
  // The header: magic, version 1, flags 0, the file's own size.
  EXPECT_EQ(bytes.substr(0, 8), "CAIRN3DM");
  EXPECT_EQ(io::load_u32(reinterpret_cast<const unsigned char*>(bytes.data()) + 8), 1u);
  EXPECT_EQ(io::load_u32(reinterpret_cast<const unsigned char*>(bytes.data()) + 12), 0u);
  EXPECT_EQ(io::load_u64(reinterpret_cast<const unsigned char*>(bytes.data()) + 16), bytes.size());
}

TEST(MapFile3d, PayloadIsLaidOutAsDocumented) {
  for (const SavedMap3D& map : {map_of_300_points(), tiny_map()}) {
    EXPECT_EQ(io::decode_container(encode_saved_map(map), "map.c3dm", kind_3d()), payload_by_hand(map));
    expect_same_map(map, decode_saved_map(file_of(payload_by_hand(map)), "map.c3dm"));
  }
}

TEST(MapFile3d, WriteAndReadThroughAFile) {
  const SavedMap3D map = map_of_300_points();
  const fs::path dir = fs::temp_directory_path() / ("cairn-test-map3d-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "map.c3dm").string();
  write_saved_map(path, map);
  expect_same_map(map, read_saved_map(path));
  EXPECT_THROW(read_saved_map((dir / "missing.c3dm").string()), io::ParseError);
  EXPECT_THROW(read_saved_map(dir.string()), io::ParseError);
  fs::remove_all(dir);
}

TEST(MapFile3d, EveryTruncationIsAnError) {
  const std::string good = encode_saved_map(tiny_map());
  for (std::size_t n = 0; n < good.size(); ++n) {
    EXPECT_THROW(decode_saved_map(good.substr(0, n), "map.c3dm"), io::ParseError) << "truncated to " << n;
  }
  expect_parse_error(good.substr(0, good.size() - 10), {"(truncated)"}, "truncated");
  expect_parse_error(good + "x", {"data appended"}, "appended");
  // The payload cut short behind a valid checksum: every length.
  const std::string payload = payload_by_hand(tiny_map());
  for (std::size_t n = 0; n < payload.size(); ++n) {
    EXPECT_THROW(decode_saved_map(file_of(payload.substr(0, n)), "map.c3dm"), io::ParseError) << "payload cut to " << n;
  }
}

TEST(MapFile3d, FlippedBytesAreCaughtByTheChecksum) {
  const std::string good = encode_saved_map(map_of_300_points());
  for (std::size_t at = 0; at < good.size(); at += 7) {
    std::string flipped = good;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x5a);
    try {
      decode_saved_map(flipped, "map.c3dm");
      ADD_FAILURE() << "byte " << at << " flipped: accepted";
    } catch (const io::ParseError& e) {
      // Magic, version, flags and file size are checked first; from the payload size on, the CRC.
      if (at >= 24) {
        EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << at << ": " << e.what();
      }
    }
  }
}

TEST(MapFile3d, OtherFilesAreNamed) {
  expect_parse_error("", {"empty file", "cairn 3D LiDAR map"}, "empty");
  expect_parse_error("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n", {"not a cairn 3D LiDAR map file", "CAIRN3DM"}, "a text file");
  // A cairn 2D map: named as such, both ways.
  const std::string map_2d = slam2d::encode_saved_map(slam2d::SavedMap2D{});
  expect_parse_error(map_2d, {"this is a cairn 2D map (cairn slam2d --save-map)", "expected a cairn 3D LiDAR map"}, "a 2D map");
  try {
    slam2d::decode_saved_map(encode_saved_map(tiny_map()), "map.c3dm");
    ADD_FAILURE() << "the 2D reader accepted a 3D map";
  } catch (const io::ParseError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("not a cairn 2D map file"), std::string::npos) << message;
    EXPECT_NE(message.find("this is a cairn 3D LiDAR map (cairn slam3d --save-map)"), std::string::npos) << message;
  }
  // A future version, its checksum recomputed.
  std::string future = encode_saved_map(tiny_map());
  store_u32(future, 8, 2);
  fix_crc(future);
  expect_parse_error(future, {"map format version 2", "written by a newer cairn"}, "version 2");
}

// The offset of the first point: 53 bytes of sensor model, 56 + 8 L of Scan Context options, the
// map voxel, then the two strings (docs/formats.md).
std::size_t points_offset(const SavedMap3D& map) {
  return 53 + 56 + 8 * map.scan_context.lateral_offsets_m.size() + 8 + 4 + map.configuration_json.size() + 4 +
         map.source.size() + 4;
}

TEST(MapFile3d, BadFieldsBehindAValidChecksumAreNamed) {
  const SavedMap3D good = map_of_300_points();
  ASSERT_NO_THROW(decode_saved_map(file_of(payload_by_hand(good)), "map.c3dm"));  // the helpers are right
  {
    SavedMap3D map = good;
    map.points_world[7].y() = std::numeric_limits<float>::quiet_NaN();
    const std::size_t at = points_offset(map) + 12 * 7 + 4;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte " + std::to_string(at) + ": point 7 y"}, "NaN point");
  }
  {
    SavedMap3D map = good;
    map.points_world[11].z() = 2e7f;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 11 z", "within 1e7"}, "far point");
  }
  {
    SavedMap3D map = good;
    map.normals_world[4] = Eigen::Vector3f(0.5f, 0.0f, 0.0f);
    expect_parse_error(file_of(payload_by_hand(map)), {"normal 4", "unit vector"}, "short normal");
  }
  Tamper quaternion;
  quaternion.keyframe_1_quaternion_scale = 1.01;
  expect_parse_error(file_of(payload_by_hand(good, quaternion)), {"keyframe 1 pose quaternion", "unit quaternion"},
                     "non-unit quaternion");
  {
    SavedMap3D map = good;
    map.keyframes[2].scan_context(1, 3) = -0.5f;
    expect_parse_error(file_of(payload_by_hand(map)), {"keyframe 2 scan context ring 1 sector 3", ">= 0"}, "negative descriptor");
  }
  {
    SavedMap3D map = good;
    map.edges[1].to = 9;
    expect_parse_error(file_of(payload_by_hand(map)), {"edge 1 to", "[0, 3]"}, "edge to a missing keyframe");
    map.edges[1].to = map.edges[1].from;
    expect_parse_error(file_of(payload_by_hand(map)), {"edge 1: from and to are both keyframe"}, "self loop");
  }
  {
    SavedMap3D map = good;
    map.edges[2].information(3, 3) = -1.0;
    expect_parse_error(file_of(payload_by_hand(map)), {"edge 2 information", "positive definite"}, "indefinite information");
    map.edges[2].information(0, 5) = map.edges[2].information(5, 0) = std::numeric_limits<double>::infinity();
    expect_parse_error(file_of(payload_by_hand(map)), {"edge 2 information (0, 5)", "finite"}, "infinite information");
  }
  Tamper count;
  count.keyframe_count = 1000000;
  expect_parse_error(file_of(payload_by_hand(good, count)), {"keyframe count 1000000 needs"}, "huge keyframe count");
  Tamper front_end;
  front_end.front_end_code = 7;
  expect_parse_error(file_of(payload_by_hand(good, front_end)), {"payload byte 0: sensor front_end", "found 7"},
                     "unknown front end");
  Tamper loop;
  loop.last_loop_code = 2;
  expect_parse_error(file_of(payload_by_hand(good, loop)), {"edge 3 loop", "0 or 1"}, "loop flag");
  {
    SavedMap3D map = good;
    map.sensor.min_range_m = 100.0;  // beyond max_range_m
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 0: sensor model", "min_range_m"}, "sensor model");
  }
  {
    SavedMap3D map = good;
    map.scan_context.candidates = 0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 53: scan context options", "candidates"}, "scan context");
  }
  {
    SavedMap3D map = good;
    map.source = std::string("a\0b", 3);
    expect_parse_error(file_of(payload_by_hand(map)), {"source: a NUL byte"}, "NUL in the source");
  }
  expect_parse_error(file_of(payload_by_hand(good) + "x"), {"1 bytes after the last edge"}, "trailing payload");
}

// Random payload bytes behind a valid checksum, many times: errors, never a crash.
TEST(MapFile3d, RandomPayloadCorruptionsAreErrorsOrMaps) {
  const std::string payload = payload_by_hand(tiny_map());
  std::mt19937 random(11);
  for (int trial = 0; trial < 500; ++trial) {
    std::string p = payload;
    for (int c = 0; c < 1 + trial % 4; ++c) {
      p[std::uniform_int_distribution<std::size_t>(0, p.size() - 1)(random)] = static_cast<char>(random() & 0xff);
    }
    try {
      decode_saved_map(file_of(p), "map.c3dm");
    } catch (const io::ParseError&) {
    }
  }
}

}  // namespace
}  // namespace cairn::lidar3d
