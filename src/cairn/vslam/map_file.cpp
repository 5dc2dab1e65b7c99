#include "cairn/vslam/map_file.hpp"

#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include "cairn/core/assert.hpp"
#include "cairn/io/map_container.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::vslam {
namespace {

// The framing (magic, version, flags, sizes, zlib, CRC-32) and the checked little-endian writer and
// reader are io/map_container.hpp's, shared with the 2D and 3D LiDAR maps (lidar3d/map_file.cpp is
// the model); this file holds the payload, laid out in docs/formats.md ("cairn visual map").
constexpr std::uint32_t kMaxSourceBytes = 65536;
constexpr std::uint32_t kMaxConfigurationBytes = std::uint32_t{1} << 20;
constexpr double kMaxTranslation = 1e9;  // metres, poses and map points (as the 2D and 3D maps' poses)
constexpr double kUnitQuaternionTolerance = 1e-6;
constexpr double kUnitNormalTolerance = 1e-3;
constexpr std::size_t kDescriptorBytes = 32;
constexpr std::size_t kPoseBytes = 24 + 32;                          // f64 translation, f64 quaternion x y z w
constexpr std::size_t kKeyframeFixedBytes = 8 + 8 + kPoseBytes + 4;  // then the keypoints
constexpr std::size_t kKeypointBytes = 5 * 4 + 4 + 4 * 8 + 4 + kDescriptorBytes;  // 92
constexpr std::size_t kPointFixedBytes = 24 + 24 + 8 + 8 + kDescriptorBytes + 4 + 4 + 4 + 4;  // 112, then the observations
constexpr std::size_t kObservationBytes = 4 + 4;
constexpr std::size_t kCovisibilityBytes = 4 + 4 + 4;

// Offsets within a keypoint record and a point's fixed part (docs/formats.md).
constexpr std::size_t kKeypointOctave = 20, kKeypointUndistorted = 24, kKeypointURight = 40, kKeypointDepth = 48,
                      kKeypointMapPoint = 56, kKeypointDescriptor = 60;
constexpr std::size_t kPointNormal = 24, kPointMinDistance = 48, kPointMaxDistance = 56, kPointDescriptor = 64,
                      kPointReference = 96, kPointVisible = 100, kPointFound = 104, kPointObservations = 108;

// Enum codes of the file, index = code: the file's numbering never follows a reordering of the enum.
constexpr io::SequenceKind kKindCodes[] = {io::SequenceKind::kStereo, io::SequenceKind::kRgbd, io::SequenceKind::kMonocular};

static_assert(kKeypointDescriptor + kDescriptorBytes == kKeypointBytes);
static_assert(kPointObservations + 4 == kPointFixedBytes);

io::ContainerKind container_kind() { return io::known_container_kind("CAIRNVSM", kVisualMapFileVersion); }

std::string text(double v) {
  std::string out;
  io::append_number(out, v);
  return out;
}

template <typename Enum, std::size_t N>
std::uint8_t code_of(const Enum (&codes)[N], Enum value, const char* what) {
  for (std::size_t c = 0; c < N; ++c) {
    if (codes[c] == value) return static_cast<std::uint8_t>(c);
  }
  CAIRN_ASSERT(false, what);
  return 0;
}

std::uint32_t count_of(std::size_t n, const char* what) {
  CAIRN_ASSERT(n <= std::numeric_limits<std::uint32_t>::max(), what);
  return static_cast<std::uint32_t>(n);
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

void encode_settings(io::BinaryWriter& w, const SavedVisualMap& map) {
  w.u8(code_of(kKindCodes, map.kind, "a sequence kind without a file code"));
  const io::CameraCalibration& c = map.camera;
  for (const double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3}) w.f64(v);
  w.i32(c.width);
  w.i32(c.height);
  w.f64(c.baseline_m);
  w.f64(c.depth_units_per_m);
  w.f64(c.virtual_baseline_m);
  const vision::OrbOptions& o = map.orb;
  w.i32(o.features);
  w.f64(o.scale_factor);
  w.i32(o.levels);
  w.i32(o.initial_fast_threshold);
  w.i32(o.min_fast_threshold);
  w.i32(o.cell_px);
  w.f64(map.close_depth_m);
  w.u64(map.vocabulary.fingerprint);
  w.u32(map.vocabulary.words);
  w.i32(map.vocabulary.branching);
  w.i32(map.vocabulary.depth);
  CAIRN_ASSERT(map.configuration_json.size() <= kMaxConfigurationBytes, "map configuration JSON longer than 1 MiB");
  w.string(map.configuration_json);
  CAIRN_ASSERT(map.source.size() <= kMaxSourceBytes, "map source name longer than 64 KiB");
  w.string(map.source);
}

void encode_keyframes(io::BinaryWriter& w, const SavedVisualMap& map) {
  w.u32(count_of(map.keyframes.size(), "more than 2^32 - 1 keyframes"));
  for (const SavedKeyframe& kf : map.keyframes) {
    w.i64(kf.time_ns);
    w.u64(kf.frame);
    write_pose(w, kf.T_world_camera);
    w.u32(count_of(kf.keypoints.size(), "more than 2^32 - 1 keypoints in a keyframe"));
    for (const SavedKeypoint& kp : kf.keypoints) {
      w.f32(kp.x);
      w.f32(kp.y);
      w.f32(kp.size);
      w.f32(kp.angle);
      w.f32(kp.response);
      w.i32(kp.octave);
      w.f64(kp.undistorted_x);
      w.f64(kp.undistorted_y);
      w.f64(kp.u_right);
      w.f64(kp.depth);
      w.i32(kp.map_point);
      w.raw(kp.descriptor.data(), kp.descriptor.size());
    }
  }
}

void encode_points(io::BinaryWriter& w, const SavedVisualMap& map) {
  w.u32(count_of(map.points.size(), "more than 2^32 - 1 map points"));
  for (const SavedMapPoint& p : map.points) {
    for (int i = 0; i < 3; ++i) w.f64(p.p_world[i]);
    for (int i = 0; i < 3; ++i) w.f64(p.normal[i]);
    w.f64(p.min_distance);
    w.f64(p.max_distance);
    w.raw(p.descriptor.data(), p.descriptor.size());
    w.i32(p.reference_keyframe);
    w.i32(p.visible);
    w.i32(p.found);
    w.u32(count_of(p.observations.size(), "more than 2^32 - 1 observations of a map point"));
    for (const SavedObservation& o : p.observations) {
      w.i32(o.keyframe);
      w.i32(o.keypoint);
    }
  }
}

void encode_covisibility(io::BinaryWriter& w, const SavedVisualMap& map) {
  w.u32(count_of(map.covisibility.size(), "more than 2^32 - 1 covisibility edges"));
  for (const SavedCovisibility& c : map.covisibility) {
    w.i32(c.a);
    w.i32(c.b);
    w.i32(c.shared);
  }
}

std::string encode_payload(const SavedVisualMap& map) {
  io::BinaryWriter w;
  encode_settings(w, map);
  encode_keyframes(w, map);
  encode_points(w, map);
  encode_covisibility(w, map);
  return std::move(w.bytes());
}

// ---------------------------------------------------------------------------------------------
// Reading.

// Little-endian loads from a block taken whole (keypoints, points): fields decoded in place, their
// names built only for an error.
float load_f32(const unsigned char* p) { return std::bit_cast<float>(io::load_u32(p)); }
double load_f64(const unsigned char* p) { return std::bit_cast<double>(io::load_u64(p)); }
std::int32_t load_i32(const unsigned char* p) { return static_cast<std::int32_t>(io::load_u32(p)); }

std::string range_text(std::int64_t low, std::int64_t high) {
  return "[" + std::to_string(low) + ", " + std::to_string(high) + "]";
}

template <typename Enum, std::size_t N>
Enum read_code(io::BinaryReader& r, const std::string& field, const Enum (&codes)[N]) {
  const std::uint8_t code = r.u8(field);
  if (code >= N) {
    std::string known;
    for (std::size_t c = 0; c < N; ++c) {
      known += (c == 0 ? "" : ", ") + std::to_string(c) + " (" + std::string(to_string(codes[c])) + ")";
    }
    r.fail(field + ": expected one of " + known + ", found " + std::to_string(code));
  }
  return codes[code];
}

// CameraCalibration::is_valid decides, with width and height set and what VisualSlam requires of
// the kind, so a map holds only a camera the SLAM would have run with.
io::CameraCalibration decode_camera(io::BinaryReader& r, io::SequenceKind kind) {
  const std::size_t at = r.offset();
  io::CameraCalibration c;
  c.fx = r.finite_f64("camera fx");
  c.fy = r.finite_f64("camera fy");
  c.cx = r.finite_f64("camera cx");
  c.cy = r.finite_f64("camera cy");
  c.k1 = r.finite_f64("camera k1");
  c.k2 = r.finite_f64("camera k2");
  c.p1 = r.finite_f64("camera p1");
  c.p2 = r.finite_f64("camera p2");
  c.k3 = r.finite_f64("camera k3");
  c.width = static_cast<int>(r.integer32("camera width", 1, std::numeric_limits<std::int32_t>::max()));
  c.height = static_cast<int>(r.integer32("camera height", 1, std::numeric_limits<std::int32_t>::max()));
  c.baseline_m = r.finite_f64("camera baseline_m");
  c.depth_units_per_m = r.finite_f64("camera depth_units_per_m");
  c.virtual_baseline_m = r.finite_f64("camera virtual_baseline_m");
  if (std::string why; !c.is_valid(&why)) r.fail_at(at, "camera calibration: " + why);
  if (kind == io::SequenceKind::kStereo && !(c.baseline_m > 0.0)) {
    r.fail_at(at, "camera calibration: a stereo map needs baseline_m > 0, found " + text(c.baseline_m));
  }
  if (kind == io::SequenceKind::kRgbd && !(c.depth_units_per_m > 0.0 && c.virtual_baseline_m > 0.0)) {
    r.fail_at(at, "camera calibration: an RGB-D map needs depth_units_per_m and virtual_baseline_m > 0, found " +
                      text(c.depth_units_per_m) + " and " + text(c.virtual_baseline_m));
  }
  return c;
}

// OrbOptions::is_valid decides (levels in [1, 16] bounds the keypoints' octaves).
vision::OrbOptions decode_orb_options(io::BinaryReader& r) {
  const std::size_t at = r.offset();
  vision::OrbOptions o;
  o.features = r.i32("ORB features");
  o.scale_factor = r.finite_f64("ORB scale_factor");
  o.levels = r.i32("ORB levels");
  o.initial_fast_threshold = r.i32("ORB initial_fast_threshold");
  o.min_fast_threshold = r.i32("ORB min_fast_threshold");
  o.cell_px = r.i32("ORB cell_px");
  if (std::string why; !o.is_valid(&why)) r.fail_at(at, "ORB options: " + why);
  return o;
}

// None (every field 0) or a vocabulary's, with the limits vision::Vocabulary loads with.
VocabularyIdentity decode_vocabulary(io::BinaryReader& r) {
  const std::size_t at = r.offset();
  VocabularyIdentity v;
  v.fingerprint = r.u64("vocabulary fingerprint");
  v.words = r.u32("vocabulary words");
  v.branching = r.i32("vocabulary branching");
  v.depth = r.i32("vocabulary depth");
  if (v.words == 0) {
    if (v.fingerprint != 0 || v.branching != 0 || v.depth != 0) {
      r.fail_at(at, "vocabulary: 0 words (a map made without a vocabulary) needs fingerprint, branching and depth 0");
    }
    return v;
  }
  if (v.branching < 2 || v.branching > 64) {
    r.fail_at(at + 12, "vocabulary branching: expected an integer in [2, 64], found " + std::to_string(v.branching));
  }
  if (v.depth < 1 || v.depth > 12) {
    r.fail_at(at + 16, "vocabulary depth: expected an integer in [1, 12], found " + std::to_string(v.depth));
  }
  return v;
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

// The keypoints of keyframe k, a block of records taken whole (the count was checked against the
// bytes left) and decoded in place. map_point is checked against the point count once the points
// are read (they come after the keyframes).
void decode_keypoints(io::BinaryReader& r, std::size_t k, SavedKeyframe& kf, int levels) {
  const std::string field = "keyframe " + std::to_string(k);
  const std::size_t keypoints = r.count(field + " keypoint count", kKeypointBytes);
  const std::size_t base = r.offset();
  const unsigned char* block = r.take(kKeypointBytes * keypoints, field + " keypoints");
  kf.keypoints.resize(keypoints);
  static constexpr const char* kF32Names[] = {"x", "y", "size", "angle", "response"};
  static constexpr const char* kF64Names[] = {"undistorted_x", "undistorted_y", "u_right", "depth"};
  for (std::size_t j = 0; j < keypoints; ++j) {
    const unsigned char* p = block + kKeypointBytes * j;
    const std::size_t at = base + kKeypointBytes * j;
    auto fail = [&](std::size_t offset, const std::string& what) {
      r.fail_at(at + offset, field + " keypoint " + std::to_string(j) + " " + what);
    };
    float f32s[5];
    for (std::size_t i = 0; i < 5; ++i) {
      f32s[i] = load_f32(p + 4 * i);
      if (!std::isfinite(f32s[i])) {
        fail(4 * i, std::string(kF32Names[i]) + ": expected a finite number, found " + text(static_cast<double>(f32s[i])));
      }
    }
    double f64s[4];
    for (std::size_t i = 0; i < 4; ++i) {
      f64s[i] = load_f64(p + kKeypointUndistorted + 8 * i);
      if (!std::isfinite(f64s[i])) {
        fail(kKeypointUndistorted + 8 * i, std::string(kF64Names[i]) + ": expected a finite number, found " + text(f64s[i]));
      }
    }
    static_assert(kKeypointUndistorted + 16 == kKeypointURight && kKeypointURight + 8 == kKeypointDepth);
    const std::int32_t octave = load_i32(p + kKeypointOctave);
    if (octave < 0 || octave >= levels) {
      fail(kKeypointOctave, "octave: expected an integer in " + range_text(0, levels - 1) + " (the ORB options' levels), found " +
                                std::to_string(octave));
    }
    const std::int32_t map_point = load_i32(p + kKeypointMapPoint);
    if (map_point < -1) fail(kKeypointMapPoint, "map_point: expected -1 or a point index, found " + std::to_string(map_point));
    SavedKeypoint& kp = kf.keypoints[j];
    kp.x = f32s[0];
    kp.y = f32s[1];
    kp.size = f32s[2];
    kp.angle = f32s[3];
    kp.response = f32s[4];
    kp.octave = octave;
    kp.undistorted_x = f64s[0];
    kp.undistorted_y = f64s[1];
    kp.u_right = f64s[2];
    kp.depth = f64s[3];
    kp.map_point = map_point;
    std::memcpy(kp.descriptor.data(), p + kKeypointDescriptor, kDescriptorBytes);
  }
}

SavedKeyframe decode_keyframe(io::BinaryReader& r, std::size_t k, int levels) {
  const std::string field = "keyframe " + std::to_string(k);
  SavedKeyframe kf;
  kf.time_ns = r.i64(field + " time");
  kf.frame = r.u64(field + " frame");
  kf.T_world_camera = read_pose(r, field + " pose");
  decode_keypoints(r, k, kf, levels);
  return kf;
}

// What the points' checks need of the keyframes: where each keyframe's keypoint records start (for
// errors about a keypoint found after the points) and which keypoints an observation has claimed.
struct KeypointIndex {
  std::vector<std::size_t> keypoints_at;  // payload offset of keyframe k's first keypoint record
  std::vector<std::size_t> first;         // keyframe k's keypoints are claimed[first[k] ...]
  std::vector<char> claimed;
  std::vector<std::int64_t> last_point;   // the last point observed in keyframe k (at most one observation each)
};

// A point's `observations` records after its fixed part (which starts at payload offset `at`):
// each names an existing keyframe (at most once) and a keypoint of it that observes this point.
void decode_observations(io::BinaryReader& r, std::size_t index, std::size_t at, std::uint32_t observations, const SavedVisualMap& map,
                         KeypointIndex& keypoints, SavedMapPoint& point) {
  const std::string field = "point " + std::to_string(index);
  auto fail = [&](std::size_t offset, const std::string& what) { r.fail_at(at + offset, field + " " + what); };
  const std::int64_t last_keyframe = static_cast<std::int64_t>(map.keyframes.size()) - 1;
  if (static_cast<std::uint64_t>(observations) * kObservationBytes > r.left()) {
    fail(kPointObservations, "observation count " + std::to_string(observations) + " needs " +
                                 std::to_string(static_cast<std::uint64_t>(observations) * kObservationBytes) + " bytes, only " +
                                 std::to_string(r.left()) + " left");
  }
  const std::size_t observations_at = r.offset();
  const unsigned char* o = r.take(kObservationBytes * observations, field + " observations");
  point.observations.resize(observations);
  const std::int64_t self = static_cast<std::int64_t>(index);
  for (std::size_t n = 0; n < observations; ++n) {
    const unsigned char* record = o + kObservationBytes * n;
    const std::size_t record_at = observations_at - at + kObservationBytes * n;
    auto which = [n] { return "observation " + std::to_string(n); };
    SavedObservation& obs = point.observations[n];
    obs.keyframe = load_i32(record);
    if (obs.keyframe < 0 || obs.keyframe > last_keyframe) {
      fail(record_at, which() + " keyframe: expected an integer in " + range_text(0, last_keyframe) + ", found " +
                          std::to_string(obs.keyframe));
    }
    const std::size_t kf = static_cast<std::size_t>(obs.keyframe);
    if (keypoints.last_point[kf] == self) fail(record_at, which() + ": a second observation in keyframe " + std::to_string(kf));
    keypoints.last_point[kf] = self;
    obs.keypoint = load_i32(record + 4);
    const std::vector<SavedKeypoint>& in = map.keyframes[kf].keypoints;
    const std::int64_t last_keypoint = static_cast<std::int64_t>(in.size()) - 1;
    if (obs.keypoint < 0 || obs.keypoint > last_keypoint) {
      fail(record_at + 4, which() + " keypoint: expected an integer in " + range_text(0, last_keypoint) + " (keyframe " +
                              std::to_string(kf) + "'s keypoints), found " + std::to_string(obs.keypoint));
    }
    const std::size_t j = static_cast<std::size_t>(obs.keypoint);
    if (in[j].map_point != self) {
      fail(record_at, which() + ": keyframe " + std::to_string(kf) + " keypoint " + std::to_string(j) + " observes " +
                          (in[j].map_point < 0 ? std::string("no map point") : "map point " + std::to_string(in[j].map_point)) +
                          ", not this one");
    }
    keypoints.claimed[keypoints.first[kf] + j] = 1;
  }
}

SavedMapPoint decode_point(io::BinaryReader& r, std::size_t index, const SavedVisualMap& map, KeypointIndex& keypoints) {
  const std::string field = "point " + std::to_string(index);
  const std::size_t at = r.offset();
  const unsigned char* p = r.take(kPointFixedBytes, field);
  auto fail = [&](std::size_t offset, const std::string& what) { r.fail_at(at + offset, field + " " + what); };
  const std::int64_t last_keyframe = static_cast<std::int64_t>(map.keyframes.size()) - 1;
  SavedMapPoint point;
  for (std::size_t i = 0; i < 3; ++i) {
    const double v = load_f64(p + 8 * i);
    if (!(std::abs(v) <= kMaxTranslation)) {
      fail(8 * i, std::string("p_world ") + "xyz"[i] + ": expected a finite coordinate within 1e9 m, found " + text(v));
    }
    point.p_world[static_cast<Eigen::Index>(i)] = v;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const double v = load_f64(p + kPointNormal + 8 * i);
    if (!std::isfinite(v)) {
      fail(kPointNormal + 8 * i, std::string("normal ") + "xyz"[i] + ": expected a finite number, found " + text(v));
    }
    point.normal[static_cast<Eigen::Index>(i)] = v;
  }
  const double norm = point.normal.norm();
  if (!(std::abs(norm - 1.0) <= kUnitNormalTolerance)) {
    fail(kPointNormal, "normal: expected a unit vector (norm within 1e-3 of 1), found norm " + text(norm));
  }
  point.min_distance = load_f64(p + kPointMinDistance);
  point.max_distance = load_f64(p + kPointMaxDistance);
  if (!std::isfinite(point.min_distance)) {
    fail(kPointMinDistance, "min_distance: expected a finite number, found " + text(point.min_distance));
  }
  if (!std::isfinite(point.max_distance)) {
    fail(kPointMaxDistance, "max_distance: expected a finite number, found " + text(point.max_distance));
  }
  if (!(point.min_distance >= 0.0 && point.min_distance <= point.max_distance)) {
    fail(kPointMinDistance, "distances: expected 0 <= min_distance <= max_distance, found " + text(point.min_distance) + " and " +
                                text(point.max_distance));
  }
  std::memcpy(point.descriptor.data(), p + kPointDescriptor, kDescriptorBytes);
  point.reference_keyframe = load_i32(p + kPointReference);
  if (point.reference_keyframe < 0 || point.reference_keyframe > last_keyframe) {
    fail(kPointReference, "reference_keyframe: expected an integer in " + range_text(0, last_keyframe) + ", found " +
                              std::to_string(point.reference_keyframe));
  }
  point.visible = load_i32(p + kPointVisible);
  if (point.visible < 1) fail(kPointVisible, "visible: expected an integer >= 1, found " + std::to_string(point.visible));
  point.found = load_i32(p + kPointFound);
  if (point.found < 0 || point.found > point.visible) {
    fail(kPointFound, "found: expected an integer in " + range_text(0, point.visible) + " (at most visible), found " +
                          std::to_string(point.found));
  }
  const std::uint32_t observations = io::load_u32(p + kPointObservations);
  if (observations == 0) fail(kPointObservations, "observation count 0: a map point has at least one observation");
  decode_observations(r, index, at, observations, map, keypoints, point);
  return point;
}

// Every keypoint's map point, now that the points are known: an existing point that observes it.
void check_keypoint_links(io::BinaryReader& r, const SavedVisualMap& map, const KeypointIndex& keypoints) {
  const std::int64_t points = static_cast<std::int64_t>(map.points.size());
  for (std::size_t k = 0; k < map.keyframes.size(); ++k) {
    const std::vector<SavedKeypoint>& in = map.keyframes[k].keypoints;
    for (std::size_t j = 0; j < in.size(); ++j) {
      const std::int32_t m = in[j].map_point;
      if (m < 0) continue;
      const std::size_t at = keypoints.keypoints_at[k] + kKeypointBytes * j + kKeypointMapPoint;
      const std::string field = "keyframe " + std::to_string(k) + " keypoint " + std::to_string(j) + " map_point";
      if (m >= points) {
        r.fail_at(at, field + ": expected -1 or a point index in " + range_text(0, points - 1) + ", found " + std::to_string(m) +
                          (points == 0 ? " (the map has no points)" : ""));
      }
      if (!keypoints.claimed[keypoints.first[k] + j]) {
        r.fail_at(at, field + " " + std::to_string(m) + ": that point has no observation of this keypoint");
      }
    }
  }
}

SavedCovisibility decode_covisibility(io::BinaryReader& r, std::size_t e, std::size_t keyframes,
                                      std::set<std::pair<std::int32_t, std::int32_t>>& seen) {
  const std::string field = "covisibility " + std::to_string(e);
  const std::int64_t last = static_cast<std::int64_t>(keyframes) - 1;
  SavedCovisibility c;
  c.a = static_cast<std::int32_t>(r.integer32(field + " a", 0, last));
  c.b = static_cast<std::int32_t>(r.integer32(field + " b", 0, last));
  if (c.a >= c.b) r.fail(field + ": expected keyframes a < b, found " + std::to_string(c.a) + " and " + std::to_string(c.b));
  if (!seen.emplace(c.a, c.b).second) {
    r.fail(field + ": keyframes " + std::to_string(c.a) + " and " + std::to_string(c.b) + " are already a covisibility pair");
  }
  c.shared = r.i32(field + " shared");
  if (c.shared < 1) r.fail(field + " shared: expected an integer >= 1, found " + std::to_string(c.shared));
  return c;
}

SavedVisualMap decode_payload(const std::string& payload, const std::string& name) {
  io::BinaryReader r(payload, name);
  SavedVisualMap map;
  map.kind = read_code(r, "kind", kKindCodes);
  map.camera = decode_camera(r, map.kind);
  map.orb = decode_orb_options(r);
  map.close_depth_m = r.finite_f64("close_depth_m");
  if (!(map.close_depth_m >= 0.0)) r.fail("close_depth_m: expected a number >= 0, found " + text(map.close_depth_m));
  map.vocabulary = decode_vocabulary(r);
  map.configuration_json = r.string("configuration_json", kMaxConfigurationBytes);
  map.source = r.string("source", kMaxSourceBytes);
  if (map.source.find('\0') != std::string::npos) r.fail("source: a NUL byte in the name");

  const std::size_t keyframes = r.count("keyframe count", kKeyframeFixedBytes);
  if (keyframes == 0) r.fail("keyframe count 0: a visual map has at least one keyframe");
  map.keyframes.reserve(keyframes);
  KeypointIndex index;
  index.keypoints_at.reserve(keyframes);
  index.first.reserve(keyframes);
  std::size_t total_keypoints = 0;
  for (std::size_t k = 0; k < keyframes; ++k) {
    map.keyframes.push_back(decode_keyframe(r, k, map.orb.levels));
    const std::size_t n = map.keyframes.back().keypoints.size();
    index.keypoints_at.push_back(r.offset() - kKeypointBytes * n);
    index.first.push_back(total_keypoints);
    total_keypoints += n;
  }
  index.claimed.assign(total_keypoints, 0);  // one byte per keypoint, 92 of which the file holds
  index.last_point.assign(keyframes, -1);

  const std::size_t points = r.count("point count", kPointFixedBytes + kObservationBytes);
  map.points.reserve(points);
  for (std::size_t m = 0; m < points; ++m) map.points.push_back(decode_point(r, m, map, index));
  check_keypoint_links(r, map, index);

  const std::size_t edges = r.count("covisibility count", kCovisibilityBytes);
  map.covisibility.reserve(edges);
  std::set<std::pair<std::int32_t, std::int32_t>> seen;
  for (std::size_t e = 0; e < edges; ++e) map.covisibility.push_back(decode_covisibility(r, e, keyframes, seen));
  r.expect_end("covisibility edge");
  return map;
}

}  // namespace

std::string encode_saved_map(const SavedVisualMap& map) { return io::encode_container(container_kind(), encode_payload(map)); }

void write_saved_map(const std::string& path, const SavedVisualMap& map) {
  const std::string bytes = encode_saved_map(map);
  io::write_output(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

SavedVisualMap decode_saved_map(const std::string& bytes, const std::string& name) {
  return decode_payload(io::decode_container(bytes, name, container_kind()), name);
}

SavedVisualMap read_saved_map(const std::string& path) {
  return decode_saved_map(io::read_container_file(path, "a map file"), path == "-" ? "standard input" : path);
}

}  // namespace cairn::vslam
