// The saved visual map file (vslam/map_file.hpp, docs/formats.md "cairn visual map"): round trip
// of a map built by hand, the layout of the payload written independently here from the
// documentation, and every kind of corruption (truncation at every length, flipped bytes, the
// wrong kind of file, a future version, bad fields behind a valid checksum). The model is the 3D
// LiDAR map's test (tests/lidar3d/test_map_file3d.cpp).

#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/io/map_container.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vslam/map_file.hpp"

namespace cairn::vslam {
namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

core::SE3 random_pose(std::mt19937& random, double extent_m) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const core::SO3 R = core::SO3::exp(Eigen::Vector3d(unit(random), 3.0 * unit(random), unit(random)));
  return core::SE3(R, Eigen::Vector3d(extent_m * unit(random), unit(random), extent_m * unit(random)));
}

std::array<std::uint8_t, 32> random_descriptor(std::mt19937& random) {
  std::array<std::uint8_t, 32> d{};
  for (std::uint8_t& byte : d) byte = static_cast<std::uint8_t>(random() & 0xff);
  return d;
}

// Which keypoints each hand-built point observes, (keyframe, keypoint); the keypoints' map_point
// is set from this, so the two sides agree. Point 2's observations are not in keyframe order.
const std::vector<std::vector<std::pair<int, int>>>& hand_observations() {
  static const std::vector<std::vector<std::pair<int, int>>> observations = {
      {{0, 0}, {1, 2}, {2, 1}},
      {{0, 3}, {1, 0}},
      {{1, 4}, {2, 5}, {0, 5}},
      {{2, 0}},
  };
  return observations;
}

constexpr int kKeyframes = 3;
constexpr int kKeypointsPerKeyframe = 6;
constexpr int kOrbLevels = 6;

// A map by hand, with settings away from every default (so a reader that ignored a field would be
// caught): RGB-D, a distorted camera, non-default ORB options, a vocabulary; 3 keyframes of 6
// keypoints (some with depth, some without), 4 points observed as hand_observations() says, and the
// covisibility those observations give (keyframes 0 and 1 share points 0, 1, 2; 0 and 2 share 0, 2;
// 1 and 2 share 0, 2).
SavedVisualMap hand_map() {
  SavedVisualMap map;
  map.kind = io::SequenceKind::kRgbd;
  map.camera.fx = 517.306408;
  map.camera.fy = 516.469215;
  map.camera.cx = 318.643040;
  map.camera.cy = 255.313989;
  map.camera.k1 = 0.262383;
  map.camera.k2 = -0.953104;
  map.camera.p1 = -0.005358;
  map.camera.p2 = 0.002628;
  map.camera.k3 = 1.163314;
  map.camera.width = 640;
  map.camera.height = 480;
  map.camera.baseline_m = 0.125;
  map.camera.depth_units_per_m = 5000.0;
  map.camera.virtual_baseline_m = 0.0773;
  map.orb.features = 1234;
  map.orb.scale_factor = 1.25;
  map.orb.levels = kOrbLevels;
  map.orb.initial_fast_threshold = 19;
  map.orb.min_fast_threshold = 8;
  map.orb.cell_px = 32;
  map.close_depth_m = 3.0938;
  map.vocabulary.fingerprint = 0x0123456789abcdefULL;
  map.vocabulary.words = 4321;
  map.vocabulary.branching = 10;
  map.vocabulary.depth = 5;
  map.configuration_json = R"({"orb":{"features":1234},"loop":{"enabled":true}})";
  map.source = "synthetic/straße/rgb.txt";
  std::mt19937 random(7);
  std::uniform_real_distribution<float> pixel(0.0f, 600.0f);
  std::uniform_real_distribution<double> metres(0.5, 8.0);
  for (int k = 0; k < kKeyframes; ++k) {
    SavedKeyframe kf;
    kf.time_ns = 1305031102175304000 + 500000000 * static_cast<std::int64_t>(k);
    kf.frame = static_cast<std::uint64_t>(20 * k + 1);
    kf.T_world_camera = k == 0 ? core::SE3() : random_pose(random, 2.0);
    for (int j = 0; j < kKeypointsPerKeyframe; ++j) {
      SavedKeypoint kp;
      kp.x = pixel(random);
      kp.y = 0.75f * pixel(random);
      kp.size = 31.0f * static_cast<float>(1 + j % 3);
      kp.angle = 0.5f * pixel(random);
      kp.response = 0.001f * pixel(random);
      kp.octave = (j + k) % kOrbLevels;
      kp.undistorted_x = static_cast<double>(kp.x) + 0.25;
      kp.undistorted_y = static_cast<double>(kp.y) - 0.125;
      kp.depth = j % 3 == 2 ? -1.0 : metres(random);
      kp.u_right = kp.depth < 0.0 ? -1.0 : kp.undistorted_x - 40.0 / kp.depth;
      kp.descriptor = random_descriptor(random);
      kf.keypoints.push_back(kp);
    }
    map.keyframes.push_back(kf);
  }
  const auto& observations = hand_observations();
  for (std::size_t m = 0; m < observations.size(); ++m) {
    SavedMapPoint p;
    p.p_world = Eigen::Vector3d(metres(random), -metres(random), 2.0 * metres(random));
    p.normal = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
    if (m == 1) p.normal = -Eigen::Vector3d::UnitX();
    p.min_distance = 0.5 + 0.25 * static_cast<double>(m);
    p.max_distance = 7.5 + static_cast<double>(m);
    p.descriptor = random_descriptor(random);
    p.reference_keyframe = observations[m][0].first;
    p.visible = 10 + static_cast<int>(m);
    p.found = 4 + static_cast<int>(m);
    for (const auto& [keyframe, keypoint] : observations[m]) {
      p.observations.push_back({keyframe, keypoint});
      map.keyframes[static_cast<std::size_t>(keyframe)].keypoints[static_cast<std::size_t>(keypoint)].map_point =
          static_cast<std::int32_t>(m);
    }
    map.points.push_back(p);
  }
  map.covisibility = {{0, 1, 3}, {0, 2, 2}, {1, 2, 2}};
  return map;
}

// The smallest map: monocular, no vocabulary, one keyframe without keypoints, nothing else.
SavedVisualMap minimal_map() {
  SavedVisualMap map;
  map.kind = io::SequenceKind::kMonocular;
  map.camera.fx = map.camera.fy = 400.0;
  map.camera.cx = 320.0;
  map.camera.cy = 240.0;
  map.camera.width = 640;
  map.camera.height = 480;
  map.keyframes.resize(1);
  map.keyframes[0].time_ns = 12500000000;
  map.keyframes[0].frame = 3;
  return map;
}

void expect_same_pose(const core::SE3& a, const core::SE3& b, const std::string& what) {
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.translation()[i], b.translation()[i]) << what;
  for (int i = 0; i < 4; ++i) EXPECT_EQ(a.unit_quaternion().coeffs()[i], b.unit_quaternion().coeffs()[i]) << what;
}

// Every field, doubles and floats with ==.
void expect_same_map(const SavedVisualMap& a, const SavedVisualMap& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.camera.fx, b.camera.fx);
  EXPECT_EQ(a.camera.fy, b.camera.fy);
  EXPECT_EQ(a.camera.cx, b.camera.cx);
  EXPECT_EQ(a.camera.cy, b.camera.cy);
  EXPECT_EQ(a.camera.k1, b.camera.k1);
  EXPECT_EQ(a.camera.k2, b.camera.k2);
  EXPECT_EQ(a.camera.p1, b.camera.p1);
  EXPECT_EQ(a.camera.p2, b.camera.p2);
  EXPECT_EQ(a.camera.k3, b.camera.k3);
  EXPECT_EQ(a.camera.width, b.camera.width);
  EXPECT_EQ(a.camera.height, b.camera.height);
  EXPECT_EQ(a.camera.baseline_m, b.camera.baseline_m);
  EXPECT_EQ(a.camera.depth_units_per_m, b.camera.depth_units_per_m);
  EXPECT_EQ(a.camera.virtual_baseline_m, b.camera.virtual_baseline_m);
  EXPECT_EQ(a.orb.features, b.orb.features);
  EXPECT_EQ(a.orb.scale_factor, b.orb.scale_factor);
  EXPECT_EQ(a.orb.levels, b.orb.levels);
  EXPECT_EQ(a.orb.initial_fast_threshold, b.orb.initial_fast_threshold);
  EXPECT_EQ(a.orb.min_fast_threshold, b.orb.min_fast_threshold);
  EXPECT_EQ(a.orb.cell_px, b.orb.cell_px);
  EXPECT_EQ(a.close_depth_m, b.close_depth_m);
  EXPECT_EQ(a.vocabulary, b.vocabulary);
  EXPECT_EQ(a.configuration_json, b.configuration_json);
  EXPECT_EQ(a.source, b.source);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t k = 0; k < a.keyframes.size(); ++k) {
    const std::string what = "keyframe " + std::to_string(k);
    const SavedKeyframe& ka = a.keyframes[k];
    const SavedKeyframe& kb = b.keyframes[k];
    EXPECT_EQ(ka.time_ns, kb.time_ns) << what;
    EXPECT_EQ(ka.frame, kb.frame) << what;
    expect_same_pose(ka.T_world_camera, kb.T_world_camera, what);
    ASSERT_EQ(ka.keypoints.size(), kb.keypoints.size()) << what;
    for (std::size_t j = 0; j < ka.keypoints.size(); ++j) {
      const std::string which = what + " keypoint " + std::to_string(j);
      const SavedKeypoint& pa = ka.keypoints[j];
      const SavedKeypoint& pb = kb.keypoints[j];
      EXPECT_EQ(pa.x, pb.x) << which;
      EXPECT_EQ(pa.y, pb.y) << which;
      EXPECT_EQ(pa.size, pb.size) << which;
      EXPECT_EQ(pa.angle, pb.angle) << which;
      EXPECT_EQ(pa.response, pb.response) << which;
      EXPECT_EQ(pa.octave, pb.octave) << which;
      EXPECT_EQ(pa.undistorted_x, pb.undistorted_x) << which;
      EXPECT_EQ(pa.undistorted_y, pb.undistorted_y) << which;
      EXPECT_EQ(pa.u_right, pb.u_right) << which;
      EXPECT_EQ(pa.depth, pb.depth) << which;
      EXPECT_EQ(pa.map_point, pb.map_point) << which;
      EXPECT_EQ(pa.descriptor, pb.descriptor) << which;
    }
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t m = 0; m < a.points.size(); ++m) {
    const std::string what = "point " + std::to_string(m);
    const SavedMapPoint& pa = a.points[m];
    const SavedMapPoint& pb = b.points[m];
    EXPECT_TRUE(pa.p_world == pb.p_world) << what;
    EXPECT_TRUE(pa.normal == pb.normal) << what;
    EXPECT_EQ(pa.min_distance, pb.min_distance) << what;
    EXPECT_EQ(pa.max_distance, pb.max_distance) << what;
    EXPECT_EQ(pa.descriptor, pb.descriptor) << what;
    EXPECT_EQ(pa.reference_keyframe, pb.reference_keyframe) << what;
    EXPECT_EQ(pa.visible, pb.visible) << what;
    EXPECT_EQ(pa.found, pb.found) << what;
    ASSERT_EQ(pa.observations.size(), pb.observations.size()) << what;
    for (std::size_t n = 0; n < pa.observations.size(); ++n) {
      EXPECT_EQ(pa.observations[n].keyframe, pb.observations[n].keyframe) << what << " observation " << n;
      EXPECT_EQ(pa.observations[n].keypoint, pb.observations[n].keypoint) << what << " observation " << n;
    }
  }
  ASSERT_EQ(a.covisibility.size(), b.covisibility.size());
  for (std::size_t e = 0; e < a.covisibility.size(); ++e) {
    EXPECT_EQ(a.covisibility[e].a, b.covisibility[e].a) << "covisibility " << e;
    EXPECT_EQ(a.covisibility[e].b, b.covisibility[e].b) << "covisibility " << e;
    EXPECT_EQ(a.covisibility[e].shared, b.covisibility[e].shared) << "covisibility " << e;
  }
}

// ---------------------------------------------------------------------------------------------
// The payload written here, field by field as docs/formats.md lays it out, independently of the
// writer under test; `Tamper` changes what the map itself cannot hold.

struct Tamper {
  std::optional<std::uint8_t> kind_code;
  double keyframe_1_quaternion_scale = 1.0;
  std::optional<std::uint32_t> keyframe_count;
  std::optional<std::uint32_t> point_2_observation_count;
};

void write_pose(io::BinaryWriter& w, const core::SE3& T, double quaternion_scale = 1.0) {
  for (int i = 0; i < 3; ++i) w.f64(T.translation()[i]);
  for (int i = 0; i < 4; ++i) w.f64(quaternion_scale * T.unit_quaternion().coeffs()[i]);  // x y z w
}

std::string payload_by_hand(const SavedVisualMap& map, const Tamper& tamper = {}) {
  io::BinaryWriter w;
  w.u8(tamper.kind_code.value_or(map.kind == io::SequenceKind::kStereo ? 0 : map.kind == io::SequenceKind::kRgbd ? 1 : 2));
  const io::CameraCalibration& c = map.camera;
  for (const double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3}) w.f64(v);
  w.i32(c.width);
  w.i32(c.height);
  w.f64(c.baseline_m);
  w.f64(c.depth_units_per_m);
  w.f64(c.virtual_baseline_m);
  w.i32(map.orb.features);
  w.f64(map.orb.scale_factor);
  w.i32(map.orb.levels);
  w.i32(map.orb.initial_fast_threshold);
  w.i32(map.orb.min_fast_threshold);
  w.i32(map.orb.cell_px);
  w.f64(map.close_depth_m);
  w.u64(map.vocabulary.fingerprint);
  w.u32(map.vocabulary.words);
  w.i32(map.vocabulary.branching);
  w.i32(map.vocabulary.depth);
  w.string(map.configuration_json);
  w.string(map.source);
  w.u32(tamper.keyframe_count.value_or(static_cast<std::uint32_t>(map.keyframes.size())));
  for (std::size_t k = 0; k < map.keyframes.size(); ++k) {
    const SavedKeyframe& kf = map.keyframes[k];
    w.i64(kf.time_ns);
    w.u64(kf.frame);
    write_pose(w, kf.T_world_camera, k == 1 ? tamper.keyframe_1_quaternion_scale : 1.0);
    w.u32(static_cast<std::uint32_t>(kf.keypoints.size()));
    for (const SavedKeypoint& kp : kf.keypoints) {
      for (const float v : {kp.x, kp.y, kp.size, kp.angle, kp.response}) w.f32(v);
      w.i32(kp.octave);
      for (const double v : {kp.undistorted_x, kp.undistorted_y, kp.u_right, kp.depth}) w.f64(v);
      w.i32(kp.map_point);
      w.raw(kp.descriptor.data(), 32);
    }
  }
  w.u32(static_cast<std::uint32_t>(map.points.size()));
  for (std::size_t m = 0; m < map.points.size(); ++m) {
    const SavedMapPoint& p = map.points[m];
    for (int i = 0; i < 3; ++i) w.f64(p.p_world[i]);
    for (int i = 0; i < 3; ++i) w.f64(p.normal[i]);
    w.f64(p.min_distance);
    w.f64(p.max_distance);
    w.raw(p.descriptor.data(), 32);
    w.i32(p.reference_keyframe);
    w.i32(p.visible);
    w.i32(p.found);
    const std::uint32_t observations = static_cast<std::uint32_t>(p.observations.size());
    w.u32(m == 2 && tamper.point_2_observation_count ? *tamper.point_2_observation_count : observations);
    for (const SavedObservation& o : p.observations) {
      w.i32(o.keyframe);
      w.i32(o.keypoint);
    }
  }
  w.u32(static_cast<std::uint32_t>(map.covisibility.size()));
  for (const SavedCovisibility& e : map.covisibility) {
    w.i32(e.a);
    w.i32(e.b);
    w.i32(e.shared);
  }
  return std::move(w.bytes());
}

const io::ContainerKind& kind_visual() {
  static const io::ContainerKind kind{
      {'C', 'A', 'I', 'R', 'N', 'V', 'S', 'M'}, 1, "cairn visual map", "cairn vslam --save-map"};
  return kind;
}

std::string file_of(const std::string& payload) { return io::encode_container(kind_visual(), payload); }

// Offsets from docs/formats.md: the first keyframe at 173 + c + n (settings, the two string lengths
// and the keyframe count besides the configuration and source), 76 bytes of keyframe before its
// 92-byte keypoint records, the point count, then 112 bytes of point before its 8-byte observations.
std::size_t keyframes_offset(const SavedVisualMap& map) { return 173 + map.configuration_json.size() + map.source.size(); }

std::size_t keypoint_offset(const SavedVisualMap& map, std::size_t keyframe, std::size_t keypoint) {
  std::size_t at = keyframes_offset(map);
  for (std::size_t k = 0; k < keyframe; ++k) at += 76 + 92 * map.keyframes[k].keypoints.size();
  return at + 76 + 92 * keypoint;
}

std::size_t point_offset(const SavedVisualMap& map, std::size_t point) {
  std::size_t at = keypoint_offset(map, map.keyframes.size(), 0) - 76 + 4;  // past the last keyframe and the point count
  for (std::size_t m = 0; m < point; ++m) at += 112 + 8 * map.points[m].observations.size();
  return at;
}

// Expects decode to throw a ParseError naming the file whose message contains every one of `expected`.
void expect_parse_error(const std::string& bytes, const std::vector<std::string>& expected, const std::string& context) {
  try {
    decode_saved_map(bytes, "map.cvsm");
    ADD_FAILURE() << context << ": accepted";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.file(), "map.cvsm") << context;
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

SavedKeypoint& keypoint(SavedVisualMap& map, std::size_t keyframe, std::size_t index) {
  return map.keyframes[keyframe].keypoints[index];
}

// ---------------------------------------------------------------------------------------------

TEST(MapFileVisual, RoundTripKeepsEveryFieldBitForBit) {
  for (const SavedVisualMap& map : {hand_map(), minimal_map()}) {
    const std::string bytes = encode_saved_map(map);
    const SavedVisualMap back = decode_saved_map(bytes, "map.cvsm");
    expect_same_map(map, back);
    EXPECT_EQ(encode_saved_map(back), bytes);
    // The header: magic, version 1, flags 0, the file's own size.
    EXPECT_EQ(bytes.substr(0, 8), "CAIRNVSM");
    EXPECT_EQ(io::load_u32(reinterpret_cast<const unsigned char*>(bytes.data()) + 8), 1u);
    EXPECT_EQ(io::load_u32(reinterpret_cast<const unsigned char*>(bytes.data()) + 12), 0u);
    EXPECT_EQ(io::load_u64(reinterpret_cast<const unsigned char*>(bytes.data()) + 16), bytes.size());
  }
  // The hand-built links survive: keyframe 1's keypoint 2 observes point 0, point 2 is seen in
  // keyframes 1, 2, 0 in that order.
  const SavedVisualMap back = decode_saved_map(encode_saved_map(hand_map()), "map.cvsm");
  EXPECT_EQ(back.keyframes[1].keypoints[2].map_point, 0);
  EXPECT_EQ(back.keyframes[1].keypoints[1].map_point, -1);
  ASSERT_EQ(back.points[2].observations.size(), 3u);
  EXPECT_EQ(back.points[2].observations[2].keyframe, 0);
  EXPECT_EQ(back.points[2].observations[2].keypoint, 5);
}

TEST(MapFileVisual, PayloadIsLaidOutAsDocumented) {
  for (const SavedVisualMap& map : {hand_map(), minimal_map()}) {
    EXPECT_EQ(io::decode_container(encode_saved_map(map), "map.cvsm", kind_visual()), payload_by_hand(map));
    expect_same_map(map, decode_saved_map(file_of(payload_by_hand(map)), "map.cvsm"));
  }
  // Sizes from the documentation: 173 + c + n, 76 + 92 N per keyframe, 4, 112 + 8 O per point, 4,
  // 12 per covisibility edge.
  const SavedVisualMap map = hand_map();
  std::size_t observations = 0;
  for (const auto& list : hand_observations()) observations += list.size();
  EXPECT_EQ(payload_by_hand(map).size(), keyframes_offset(map) + kKeyframes * (76 + 92 * kKeypointsPerKeyframe) + 4 +
                                             112 * hand_observations().size() + 8 * observations + 4 + 3 * 12);
}

TEST(MapFileVisual, WriteAndReadThroughAFile) {
  const SavedVisualMap map = hand_map();
  const fs::path dir = fs::temp_directory_path() / ("cairn-test-vslam-map-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "map.cvsm").string();
  write_saved_map(path, map);
  expect_same_map(map, read_saved_map(path));
  EXPECT_THROW(read_saved_map((dir / "missing.cvsm").string()), io::ParseError);
  EXPECT_THROW(read_saved_map(dir.string()), io::ParseError);
  fs::remove_all(dir);
}

TEST(MapFileVisual, EveryTruncationIsAnError) {
  const std::string good = encode_saved_map(hand_map());
  for (std::size_t n = 0; n < good.size(); ++n) {
    EXPECT_THROW(decode_saved_map(good.substr(0, n), "map.cvsm"), io::ParseError) << "truncated to " << n;
  }
  expect_parse_error(good.substr(0, good.size() - 10), {"(truncated)"}, "truncated");
  expect_parse_error(good + "x", {"data appended"}, "appended");
  // The payload cut short behind a valid checksum: every length.
  const std::string payload = payload_by_hand(hand_map());
  for (std::size_t n = 0; n < payload.size(); ++n) {
    EXPECT_THROW(decode_saved_map(file_of(payload.substr(0, n)), "map.cvsm"), io::ParseError) << "payload cut to " << n;
  }
  expect_parse_error(file_of(payload.substr(0, 40)), {"payload byte 33: file ends early: expected camera k1"}, "cut in the camera");
}

TEST(MapFileVisual, FlippedBytesAreCaughtByTheChecksum) {
  const std::string good = encode_saved_map(hand_map());
  for (std::size_t at = 0; at < good.size(); ++at) {
    std::string flipped = good;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x5a);
    try {
      decode_saved_map(flipped, "map.cvsm");
      ADD_FAILURE() << "byte " << at << " flipped: accepted";
    } catch (const io::ParseError& e) {
      // Magic, version, flags and file size are checked first; from the payload size on, the CRC.
      if (at >= 24) {
        EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << at << ": " << e.what();
      }
    }
  }
}

TEST(MapFileVisual, OtherFilesAreNamed) {
  expect_parse_error("", {"empty file", "cairn visual map", "cairn vslam --save-map"}, "empty");
  expect_parse_error("P5\n640 480\n255\n", {"not a cairn visual map file", "CAIRNVSM"}, "a text file");
  // A 3D LiDAR map and a 2D map: the container of another kind is named as such.
  expect_parse_error(io::encode_container(io::known_container_kind("CAIRN3DM", 1), "x"),
                     {"this is a cairn 3D LiDAR map (cairn slam3d --save-map)", "expected a cairn visual map"}, "a 3D map");
  expect_parse_error(io::encode_container(io::known_container_kind("CAIRNMAP", 1), "x"),
                     {"this is a cairn 2D map (cairn slam2d --save-map)", "expected a cairn visual map"}, "a 2D map");
  // The other readers name a visual map (the table of kinds is shared).
  try {
    io::decode_container(encode_saved_map(minimal_map()), "map.cvsm", io::known_container_kind("CAIRN3DM", 1));
    ADD_FAILURE() << "a 3D container accepted a visual map";
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("this is a cairn visual map (cairn vslam --save-map)"), std::string::npos) << e.what();
  }
  // A future version, its checksum recomputed.
  std::string future = encode_saved_map(minimal_map());
  store_u32(future, 8, 2);
  fix_crc(future);
  expect_parse_error(future, {"map format version 2", "written by a newer cairn"}, "version 2");
}

TEST(MapFileVisual, BadSettingsBehindAValidChecksumAreNamed) {
  const SavedVisualMap good = hand_map();
  ASSERT_NO_THROW(decode_saved_map(file_of(payload_by_hand(good)), "map.cvsm"));  // the helpers are right
  Tamper kind;
  kind.kind_code = 7;
  expect_parse_error(file_of(payload_by_hand(good, kind)), {"payload byte 0: kind", "2 (monocular)", "found 7"}, "unknown kind");
  {
    SavedVisualMap map = good;
    map.camera.width = 0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 73: camera width", "found 0"}, "no width");
    map = good;
    map.camera.height = -480;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 77: camera height", "found -480"}, "negative height");
    map = good;
    map.camera.fy = -516.0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 1: camera calibration", "fy must be a positive number"},
                       "negative fy");
    map = good;
    map.camera.k2 = kNaN;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 41: camera k2", "finite"}, "NaN k2");
    map = good;
    map.camera.virtual_baseline_m = 0.0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 1: camera calibration", "RGB-D", "virtual_baseline_m"},
                       "RGB-D without a virtual baseline");
    map = good;
    map.kind = io::SequenceKind::kStereo;
    map.camera.baseline_m = 0.0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 1: camera calibration", "stereo", "baseline_m"},
                       "stereo without a baseline");
  }
  {
    SavedVisualMap map = good;
    map.orb.levels = 0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 105: ORB options", "levels must be in [1, 16]"}, "ORB levels");
    map = good;
    map.orb.min_fast_threshold = 25;  // above the initial 19
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 105: ORB options", "FAST thresholds"}, "FAST thresholds");
  }
  {
    SavedVisualMap map = good;
    map.close_depth_m = -1.0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 133: close_depth_m", ">= 0"}, "negative close depth");
  }
  {
    SavedVisualMap map = good;
    map.vocabulary.words = 0;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 141: vocabulary", "0 words"}, "half a vocabulary");
    map = good;
    map.vocabulary.branching = 1;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 153: vocabulary branching", "[2, 64]", "found 1"},
                       "vocabulary branching");
    map = good;
    map.vocabulary.depth = 13;
    expect_parse_error(file_of(payload_by_hand(map)), {"payload byte 157: vocabulary depth", "[1, 12]"}, "vocabulary depth");
  }
  {
    SavedVisualMap map = good;
    map.source = std::string("a\0b", 3);
    expect_parse_error(file_of(payload_by_hand(map)), {"source: a NUL byte"}, "NUL in the source");
    map = good;
    map.source = std::string(65537, 's');
    expect_parse_error(file_of(payload_by_hand(map)), {"source length", "at most 65536"}, "long source");
  }
}

TEST(MapFileVisual, BadKeyframesBehindAValidChecksumAreNamed) {
  const SavedVisualMap good = hand_map();
  {
    SavedVisualMap map = good;
    map.keyframes.clear();
    map.points.clear();
    map.covisibility.clear();
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(keyframes_offset(map) - 4) + ": keyframe count 0", "at least one keyframe"},
                       "no keyframes");
  }
  Tamper count;
  count.keyframe_count = 1000000;
  expect_parse_error(file_of(payload_by_hand(good, count)), {"keyframe count 1000000 needs"}, "huge keyframe count");
  Tamper quaternion;
  quaternion.keyframe_1_quaternion_scale = 1.01;
  expect_parse_error(file_of(payload_by_hand(good, quaternion)), {"keyframe 1 pose quaternion", "unit quaternion"},
                     "non-unit quaternion");
  {
    SavedVisualMap map = good;
    map.keyframes[2].T_world_camera = core::SE3(core::SO3(), Eigen::Vector3d(0.0, kNaN, 0.0));
    expect_parse_error(file_of(payload_by_hand(map)), {"keyframe 2 pose y", "finite"}, "NaN translation");
  }
  {
    SavedVisualMap map = good;
    keypoint(map, 0, 2).octave = kOrbLevels;
    const std::size_t at = keypoint_offset(map, 0, 2) + 20;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(at) + ": keyframe 0 keypoint 2 octave", "[0, 5]", "found 6"},
                       "octave past the levels");
    keypoint(map, 0, 2).octave = -1;
    expect_parse_error(file_of(payload_by_hand(map)), {"keyframe 0 keypoint 2 octave", "found -1"}, "negative octave");
  }
  {
    SavedVisualMap map = good;
    keypoint(map, 1, 3).response = std::numeric_limits<float>::quiet_NaN();
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(keypoint_offset(map, 1, 3) + 16) + ": keyframe 1 keypoint 3 response",
                        "finite"},
                       "NaN response");
    map = good;
    keypoint(map, 2, 4).depth = kNaN;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(keypoint_offset(map, 2, 4) + 48) + ": keyframe 2 keypoint 4 depth"},
                       "NaN depth");
  }
}

TEST(MapFileVisual, BadPointsAndLinksBehindAValidChecksumAreNamed) {
  const SavedVisualMap good = hand_map();
  {
    // Keyframe 1's keypoint 1 observes no point; 4 points exist.
    SavedVisualMap map = good;
    keypoint(map, 1, 1).map_point = 4;
    const std::size_t at = keypoint_offset(map, 1, 1) + 56;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(at) + ": keyframe 1 keypoint 1 map_point", "[0, 3]", "found 4"},
                       "map point past the points");
    keypoint(map, 1, 1).map_point = -2;
    expect_parse_error(file_of(payload_by_hand(map)), {"keyframe 1 keypoint 1 map_point", "found -2"}, "map point -2");
    keypoint(map, 1, 1).map_point = 3;  // point 3 observes only keyframe 2's keypoint 0
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(at) + ": keyframe 1 keypoint 1 map_point 3", "no observation of this keypoint"},
                       "keypoint claims a point that does not observe it");
  }
  {
    // Point 1's second observation (keyframe 1, keypoint 0) moved to keypoints observing nothing, and point 0.
    SavedVisualMap map = good;
    map.points[1].observations[1].keypoint = 1;
    const std::size_t at = point_offset(map, 1) + 112 + 8;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(at) + ": point 1 observation 1: keyframe 1 keypoint 1 observes no map point"},
                       "observation of a keypoint without a point");
    map.points[1].observations[1].keypoint = 2;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 1 observation 1: keyframe 1 keypoint 2 observes map point 0, not this one"},
                       "observation of another point's keypoint");
  }
  {
    SavedVisualMap map = good;
    map.points[2].observations[0].keyframe = 3;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 2 observation 0 keyframe", "[0, 2]", "found 3"},
                       "observation in a missing keyframe");
    map = good;
    map.points[0].observations[1].keypoint = 6;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"point 0 observation 1 keypoint", "[0, 5]", "found 6"}, "observation of a missing keypoint");
    map = good;
    map.points[0].observations.push_back({0, 1});
    keypoint(map, 0, 1).map_point = 0;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 0 observation 3: a second observation in keyframe 0"},
                       "two observations in a keyframe");
    map = good;
    map.points[3].observations.clear();
    keypoint(map, 2, 0).map_point = -1;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(point_offset(map, 3) + 108) + ": point 3 observation count 0"},
                       "point without observations");
    Tamper count;
    count.point_2_observation_count = 100000;
    expect_parse_error(file_of(payload_by_hand(good, count)), {"point 2 observation count 100000 needs"}, "huge observation count");
  }
  {
    SavedVisualMap map = good;
    map.points[1].p_world.z() = kNaN;
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(point_offset(map, 1) + 16) + ": point 1 p_world z", "finite"}, "NaN point");
    map = good;
    map.points[2].normal = Eigen::Vector3d(0.5, 0.0, 0.0);
    expect_parse_error(file_of(payload_by_hand(map)), {"point 2 normal", "unit vector"}, "short normal");
    map = good;
    map.points[0].min_distance = 9.0;  // max 7.5
    expect_parse_error(file_of(payload_by_hand(map)),
                       {"payload byte " + std::to_string(point_offset(map, 0) + 48) + ": point 0 distances",
                        "0 <= min_distance <= max_distance"},
                       "min above max");
    map = good;
    map.points[0].min_distance = -0.5;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 0 distances"}, "negative min distance");
    map = good;
    map.points[3].reference_keyframe = 3;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 3 reference_keyframe", "[0, 2]"}, "missing reference keyframe");
    map = good;
    map.points[2].found = map.points[2].visible + 1;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 2 found", "at most visible"}, "found above visible");
    map = good;
    map.points[1].found = -1;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 1 found", "found -1"}, "negative found");
    map = good;
    map.points[1].visible = 0;
    map.points[1].found = 0;
    expect_parse_error(file_of(payload_by_hand(map)), {"point 1 visible", ">= 1"}, "never visible");
  }
}

TEST(MapFileVisual, BadCovisibilityBehindAValidChecksumIsNamed) {
  const SavedVisualMap good = hand_map();
  SavedVisualMap map = good;
  map.covisibility[0] = {1, 0, 3};
  expect_parse_error(file_of(payload_by_hand(map)), {"covisibility 0: expected keyframes a < b, found 1 and 0"}, "a > b");
  map.covisibility[0] = {1, 1, 3};
  expect_parse_error(file_of(payload_by_hand(map)), {"covisibility 0: expected keyframes a < b"}, "a == b");
  map = good;
  map.covisibility[1].b = 3;
  expect_parse_error(file_of(payload_by_hand(map)), {"covisibility 1 b", "[0, 2]"}, "missing keyframe");
  map = good;
  map.covisibility[2].shared = 0;
  expect_parse_error(file_of(payload_by_hand(map)), {"covisibility 2 shared", ">= 1"}, "nothing shared");
  map = good;
  map.covisibility[2] = map.covisibility[0];
  expect_parse_error(file_of(payload_by_hand(map)), {"covisibility 2: keyframes 0 and 1 are already a covisibility pair"}, "pair twice");
  expect_parse_error(file_of(payload_by_hand(good) + "x"), {"1 bytes after the last covisibility edge"}, "trailing payload");
}

// Random payload bytes behind a valid checksum, many times: errors, never a crash.
TEST(MapFileVisual, RandomPayloadCorruptionsAreErrorsOrMaps) {
  const std::string payload = payload_by_hand(hand_map());
  std::mt19937 random(11);
  for (int trial = 0; trial < 1000; ++trial) {
    std::string p = payload;
    for (int c = 0; c < 1 + trial % 4; ++c) {
      p[std::uniform_int_distribution<std::size_t>(0, p.size() - 1)(random)] = static_cast<char>(random() & 0xff);
    }
    try {
      // Accepted (a changed descriptor byte, say): what it writes reads back to the same bytes.
      const std::string again = encode_saved_map(decode_saved_map(file_of(p), "map.cvsm"));
      EXPECT_EQ(encode_saved_map(decode_saved_map(again, "again.cvsm")), again) << "trial " << trial;
    } catch (const io::ParseError&) {
    }
  }
}

}  // namespace
}  // namespace cairn::vslam
