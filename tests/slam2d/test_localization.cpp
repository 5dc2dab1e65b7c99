// Map reuse and pure localisation: the saved-map file (round trip, every kind of corruption) and
// Localizer2d on the Intel log (a map of the first half, the second half localised in it from no
// prior; a kidnapped robot). docs/slam2d.md ("Map reuse and localisation") records the numbers.

#include <gtest/gtest.h>

#include <zlib.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <random>

#include "cairn/eval/relations.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/localization.hpp"
#include "cairn/slam2d/map_file.hpp"
#include "cairn/slam2d/slam.hpp"
#include "test_data.hpp"

namespace cairn::slam2d {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn-test-localization-" + name + "-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

// ---------------------------------------------------------------------------------------------
// The map file.

// A small map by hand: two submaps with rays inserted, points, keyframes, unusual settings (so a
// reader that ignored a field would be caught).
SavedMap2D small_map() {
  SavedMap2D map;
  map.grid.resolution_m = 0.1;
  map.grid.hit_probability = 0.6;
  map.grid.miss_probability = 0.45;
  map.grid.min_probability = 0.1;
  map.grid.max_probability = 0.95;
  map.map_points.cell_size_m = 0.5;
  map.map_points.normal_radius_m = 0.3;
  map.map_points.normal_min_neighbours = 4;
  map.map_points.normal_max_eigenvalue_ratio = 0.2;
  map.filter.min_range_m = 0.2;
  map.filter.max_range_m = 25.0;
  map.filter.missing_ray_length_m = 4.0;
  map.filter.voxel_size_m = 0.03;
  map.filter.adaptive_min_points = 120;
  map.filter.adaptive_max_voxel_size_m = 0.4;
  map.source = "synthetic/öffice.clf";
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int k = 0; k < 5; ++k) {
    map.keyframes.push_back({core::Timestamp::from_nanoseconds(1000000000LL * k + 123), core::SE2(unit(random), unit(random), 3.0 * unit(random)), k / 3});
  }
  for (int s = 0; s < 2; ++s) {
    SavedSubmap submap{core::SE2(2.0 * s, -1.0, 0.3 * s), ProbabilityGrid(map.grid), {}, s, 2 * s, 3};
    for (int scan = 0; scan < 3; ++scan) {
      std::vector<Eigen::Vector2d> points;
      std::vector<bool> hit;
      for (int b = 0; b < 40; ++b) {
        const double angle = -1.5 + 0.075 * b;
        const double range = 2.0 + 0.5 * std::sin(3.0 * angle + scan) + s;
        points.emplace_back(range * std::cos(angle), range * std::sin(angle));
        hit.push_back(b % 9 != 0);
        if (hit.back()) submap.points_submap.push_back(core::SE2(0.2 * scan, 0.0, 0.05 * scan) * points.back());
      }
      submap.grid.insert(core::SE2(0.2 * scan, 0.0, 0.05 * scan), points, hit);
    }
    map.submaps.push_back(std::move(submap));
  }
  // An empty submap (no grid, no points) is legal too.
  map.submaps.push_back(SavedSubmap{core::SE2(), ProbabilityGrid(map.grid), {}, 1, 4, 0});
  return map;
}

// Every field equal; grids compared cell by cell at the same global index over the union of
// both extents (the reader keeps the observed part only).
void expect_same_map(const SavedMap2D& a, const SavedMap2D& b) {
  EXPECT_EQ(a.grid.resolution_m, b.grid.resolution_m);
  EXPECT_EQ(a.grid.hit_probability, b.grid.hit_probability);
  EXPECT_EQ(a.grid.miss_probability, b.grid.miss_probability);
  EXPECT_EQ(a.grid.min_probability, b.grid.min_probability);
  EXPECT_EQ(a.grid.max_probability, b.grid.max_probability);
  EXPECT_EQ(a.map_points.cell_size_m, b.map_points.cell_size_m);
  EXPECT_EQ(a.map_points.normal_radius_m, b.map_points.normal_radius_m);
  EXPECT_EQ(a.map_points.normal_min_neighbours, b.map_points.normal_min_neighbours);
  EXPECT_EQ(a.map_points.normal_max_eigenvalue_ratio, b.map_points.normal_max_eigenvalue_ratio);
  EXPECT_EQ(a.filter.min_range_m, b.filter.min_range_m);
  EXPECT_EQ(a.filter.max_range_m, b.filter.max_range_m);
  EXPECT_EQ(a.filter.missing_ray_length_m, b.filter.missing_ray_length_m);
  EXPECT_EQ(a.filter.voxel_size_m, b.filter.voxel_size_m);
  EXPECT_EQ(a.filter.adaptive_min_points, b.filter.adaptive_min_points);
  EXPECT_EQ(a.filter.adaptive_max_voxel_size_m, b.filter.adaptive_max_voxel_size_m);
  EXPECT_EQ(a.source, b.source);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t k = 0; k < a.keyframes.size(); ++k) {
    EXPECT_EQ(a.keyframes[k].time, b.keyframes[k].time);
    EXPECT_EQ(a.keyframes[k].T_world_laser.x(), b.keyframes[k].T_world_laser.x());
    EXPECT_EQ(a.keyframes[k].T_world_laser.y(), b.keyframes[k].T_world_laser.y());
    EXPECT_EQ(a.keyframes[k].T_world_laser.angle(), b.keyframes[k].T_world_laser.angle());
    EXPECT_EQ(a.keyframes[k].segment, b.keyframes[k].segment);
  }
  ASSERT_EQ(a.submaps.size(), b.submaps.size());
  for (std::size_t s = 0; s < a.submaps.size(); ++s) {
    const SavedSubmap& x = a.submaps[s];
    const SavedSubmap& y = b.submaps[s];
    EXPECT_EQ(x.T_world_submap.x(), y.T_world_submap.x());
    EXPECT_EQ(x.T_world_submap.y(), y.T_world_submap.y());
    EXPECT_EQ(x.T_world_submap.angle(), y.T_world_submap.angle());
    EXPECT_EQ(x.segment, y.segment);
    EXPECT_EQ(x.first_keyframe, y.first_keyframe);
    EXPECT_EQ(x.keyframe_count, y.keyframe_count);
    EXPECT_EQ(x.points_submap, y.points_submap);
    EXPECT_EQ(x.grid.resolution(), y.grid.resolution());
    const long i0 = std::min(x.grid.offset_i(), y.grid.offset_i());
    const long j0 = std::min(x.grid.offset_j(), y.grid.offset_j());
    const long i1 = std::max(x.grid.offset_i() + x.grid.width(), y.grid.offset_i() + y.grid.width());
    const long j1 = std::max(x.grid.offset_j() + x.grid.height(), y.grid.offset_j() + y.grid.height());
    std::size_t known = 0, mismatches = 0;
    for (long j = j0; j < j1; ++j) {
      for (long i = i0; i < i1; ++i) {
        const int xi = static_cast<int>(i - x.grid.offset_i()), xj = static_cast<int>(j - x.grid.offset_j());
        const int yi = static_cast<int>(i - y.grid.offset_i()), yj = static_cast<int>(j - y.grid.offset_j());
        const bool kx = x.grid.cell_known(xi, xj), ky = y.grid.cell_known(yi, yj);
        if (kx) ++known;
        if (kx != ky || std::bit_cast<std::uint32_t>(x.grid.cell_log_odds(xi, xj)) !=
                            std::bit_cast<std::uint32_t>(y.grid.cell_log_odds(yi, yj)))
          ++mismatches;
      }
    }
    EXPECT_EQ(mismatches, 0u) << "submap " << s << " (" << known << " known cells)";
  }
}

TEST(MapFile, RoundTripKeepsEveryField) {
  const SavedMap2D map = small_map();
  const fs::path dir = temp_dir("round-trip");
  const std::string path = (dir / "small.cmap").string();
  write_saved_map(path, map);
  const SavedMap2D back = read_saved_map(path);
  expect_same_map(map, back);
  // Writing what was read gives the same bytes.
  EXPECT_EQ(encode_saved_map(back), encode_saved_map(map));
  fs::remove_all(dir);
}

// Expects decode to throw a ParseError naming the file whose message contains `expected`.
void expect_parse_error(const std::string& bytes, const std::string& expected, const std::string& context) {
  try {
    decode_saved_map(bytes, "map.cmap");
    ADD_FAILURE() << context << ": accepted";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.file(), "map.cmap") << context;
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << context << ": " << e.what();
  }
}

std::uint32_t load_u32(const std::string& bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (int b = 3; b >= 0; --b) v = (v << 8) | static_cast<unsigned char>(bytes[at + static_cast<std::size_t>(b)]);
  return v;
}
void store_u32(std::string& bytes, std::size_t at, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) bytes[at + static_cast<std::size_t>(b)] = static_cast<char>((v >> (8 * b)) & 0xff);
}
void store_u64(std::string& bytes, std::size_t at, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) bytes[at + static_cast<std::size_t>(b)] = static_cast<char>((v >> (8 * b)) & 0xff);
}
void fix_crc(std::string& bytes) {
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size() - 4));
  store_u32(bytes, bytes.size() - 4, static_cast<std::uint32_t>(crc));
}

// The payload of a map file, and a valid file around a (changed) payload: for corruptions that
// a checksum cannot catch (a file written wrongly, or on purpose).
std::string payload_of(const std::string& file) {
  std::string payload(load_u32(file, 24), '\0');
  uLongf size = payload.size();
  EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(payload.data()), &size, reinterpret_cast<const Bytef*>(file.data() + 32),
                       file.size() - 36),
            Z_OK);
  return payload;
}
std::string file_of(const std::string& payload) {
  uLongf size = compressBound(payload.size());
  std::string compressed(size, '\0');
  EXPECT_EQ(compress(reinterpret_cast<Bytef*>(compressed.data()), &size, reinterpret_cast<const Bytef*>(payload.data()),
                     payload.size()),
            Z_OK);
  compressed.resize(size);
  std::string file = std::string("CAIRNMAP") + std::string(24, '\0') + compressed + std::string(4, '\0');
  store_u32(file, 8, kMapFileVersion);
  store_u64(file, 16, file.size());
  store_u64(file, 24, payload.size());
  fix_crc(file);
  return file;
}

TEST(MapFile, CorruptFilesGiveClearErrors) {
  const std::string good = encode_saved_map(small_map());
  ASSERT_NO_THROW(decode_saved_map(good, "map.cmap"));
  ASSERT_NO_THROW(decode_saved_map(file_of(payload_of(good)), "map.cmap"));  // the helpers are right

  expect_parse_error("", "empty file", "empty");
  expect_parse_error("VERTEX_SE2 0 0 0 0\n", "not a cairn 2D map file", "a g2o file");
  std::string magic = good;
  magic[3] = 'X';
  expect_parse_error(magic, "magic", "wrong magic");
  std::string future = good;
  store_u32(future, 8, kMapFileVersion + 1);
  fix_crc(future);
  expect_parse_error(future, "written by a newer cairn", "future version");
  std::string flags = good;
  store_u32(flags, 12, 4);
  fix_crc(flags);
  expect_parse_error(flags, "flags", "unknown flags");

  // Truncated at every length: always an error, never a crash.
  for (std::size_t n = 1; n < good.size(); ++n) {
    EXPECT_THROW(decode_saved_map(good.substr(0, n), "map.cmap"), io::ParseError) << "truncated to " << n;
  }
  expect_parse_error(good.substr(0, good.size() - 10), "(truncated)", "truncated");
  expect_parse_error(good + "x", "data appended", "appended");
  // Every bit of every byte flipped: the checksum (or the header check before it) catches it.
  for (std::size_t at = 0; at < good.size(); ++at) {
    for (int bit = 0; bit < 8; ++bit) {
      std::string flipped = good;
      flipped[at] = static_cast<char>(flipped[at] ^ (1 << bit));
      EXPECT_THROW(decode_saved_map(flipped, "map.cmap"), io::ParseError) << "byte " << at << " bit " << bit;
    }
  }
  std::string flipped = good;
  flipped[good.size() / 2] = static_cast<char>(flipped[good.size() / 2] ^ 0x10);
  expect_parse_error(flipped, "checksum mismatch", "one flipped bit");

  // Corrupt content behind a valid checksum: each field is checked.
  const std::string payload = payload_of(good);
  // Payload layout: 13 f64 + 2 i32 = 112 bytes of settings, then the source string.
  const std::size_t source_at = 112;
  const std::size_t keyframes_at = source_at + 4 + small_map().source.size();
  {
    std::string p = payload;
    store_u32(p, keyframes_at, 0xffffffffu);
    expect_parse_error(file_of(p), "keyframe count 4294967295 needs", "huge keyframe count");
  }
  {
    std::string p = payload;
    store_u32(p, keyframes_at + 4, 0xfffffff0u);
    expect_parse_error(file_of(p), "submap count", "huge submap count");
  }
  {
    std::string p = payload;
    store_u32(p, source_at, 0x7fffffffu);
    expect_parse_error(file_of(p), "source length", "huge source length");
  }
  {
    std::string p = payload;
    store_u64(p, 0, std::bit_cast<std::uint64_t>(std::numeric_limits<double>::quiet_NaN()));
    expect_parse_error(file_of(p), "grid resolution_m: expected a finite number", "NaN resolution");
  }
  {
    std::string p = payload;
    store_u64(p, 8, std::bit_cast<std::uint64_t>(0.3));  // hit probability below 0.5
    expect_parse_error(file_of(p), "grid hit_probability", "hit probability");
  }
  {
    // The first keyframe's x: infinite.
    std::string p = payload;
    store_u64(p, keyframes_at + 8 + 8, std::bit_cast<std::uint64_t>(std::numeric_limits<double>::infinity()));
    expect_parse_error(file_of(p), "keyframe 0 pose x", "infinite pose");
  }
  const std::size_t submap_at = keyframes_at + 8 + 5 * 36;
  {
    std::string p = payload;
    store_u32(p, submap_at + 24 + 4, 99);  // first keyframe beyond the keyframes
    expect_parse_error(file_of(p), "submap 0 first_keyframe", "keyframe index");
  }
  {
    std::string p = payload;
    store_u32(p, submap_at + 24 + 12 + 16, 70000);  // width
    expect_parse_error(file_of(p), "submap 0 grid width", "huge width");
  }
  {
    std::string p = payload;
    store_u32(p, submap_at + 24 + 12 + 16, 65536);  // width and height in range, too many cells
    store_u32(p, submap_at + 24 + 12 + 20, 65536);
    expect_parse_error(file_of(p), "2^28", "too many cells");
  }
  {
    std::string p = payload;
    store_u32(p, submap_at + 24 + 12 + 16, 4000);  // fits the cell limit, not the file
    store_u32(p, submap_at + 24 + 12 + 20, 4000);
    expect_parse_error(file_of(p), "file ends early", "grid larger than the file");
  }
  expect_parse_error(file_of(payload + "extra"), "bytes after the last submap", "trailing payload");
  expect_parse_error(file_of(payload.substr(0, payload.size() - 3)), "file ends early", "short payload");
  // A declared payload size that disagrees with the compressed stream.
  {
    std::string f = file_of(payload);
    store_u64(f, 24, payload.size() + 1);
    fix_crc(f);
    expect_parse_error(f, "payload", "payload size too large");
    store_u64(f, 24, payload.size() - 1);
    fix_crc(f);
    expect_parse_error(f, "longer than", "payload size too small");
    store_u64(f, 24, std::uint64_t{1} << 50);
    fix_crc(f);
    expect_parse_error(f, "at most 16 GiB", "huge payload size");
  }
  // Corrupt compressed bytes behind a valid checksum.
  {
    std::string f = good;
    for (std::size_t at = 40; at < 60 && at + 4 < f.size(); ++at) f[at] = static_cast<char>(0xff);
    fix_crc(f);
    expect_parse_error(f, "compressed payload", "corrupt zlib");
  }
  // Random payload bytes behind a valid checksum, many times: errors, never a crash.
  std::mt19937 random(11);
  for (int trial = 0; trial < 300; ++trial) {
    std::string p = payload;
    const int changes = 1 + trial % 4;
    for (int c = 0; c < changes; ++c) {
      p[std::uniform_int_distribution<std::size_t>(0, p.size() - 1)(random)] = static_cast<char>(random() & 0xff);
    }
    try {
      decode_saved_map(file_of(p), "map.cmap");
    } catch (const io::ParseError&) {
    }
  }
}

TEST(MapFile, MissingAndDirectoryPathsAreErrors) {
  EXPECT_THROW(read_saved_map("/nonexistent/map.cmap"), io::ParseError);
  const fs::path dir = temp_dir("directory");
  EXPECT_THROW(read_saved_map(dir.string()), io::ParseError);
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Localizer2d.

TEST(Localization, RejectsInvalidOptionsAndMapsWithoutPoints) {
  Localizer2dOptions bad;
  bad.confirmations = 0;
  bad.ok_min_inlier_fraction = 0.2;  // below tracking_min_inlier_fraction
  bad.look_alike_min_observed_fraction = 0.0;
  bad.look_alike_places = -1;
  try {
    Localizer2d localizer(small_map(), bad);
    ADD_FAILURE() << "invalid options accepted";
  } catch (const std::invalid_argument& e) {
    // Every problem at once.
    EXPECT_NE(std::string(e.what()).find("confirmations"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ok_min_inlier_fraction"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("look_alike_min_observed_fraction"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("look_alike_places"), std::string::npos) << e.what();
  }
  SavedMap2D empty = small_map();
  for (auto& submap : empty.submaps) submap.points_submap.clear();
  EXPECT_THROW(Localizer2d localizer(empty), std::invalid_argument);
  EXPECT_NO_THROW(Localizer2d localizer(small_map()));
}

// ---------------------------------------------------------------------------------------------
// Localisation on the Intel log: the map of its first half, scans of its second half.

struct IntelRuns {
  io::CarmenLog log;
  std::size_t half = 0;  ///< the map is Slam2d on scans [0, half)
  std::size_t end = 0;   ///< the reference covers [0, end)
  SavedMap2D map;
  /// The same Slam2d run continued to `end` and finished again: the reference poses, in the
  /// map's frame (both runs start at the first scan, whose keyframe the pose graph holds fixed;
  /// the continued run's optimisation moves the first half by a few centimetres).
  std::vector<ScanResult> reference;
  double map_s = 0.0;
};

const IntelRuns& intel() {
  static std::unique_ptr<IntelRuns> runs;
  if (runs) return *runs;
  runs = std::make_unique<IntelRuns>();
  runs->log = io::read_carmen_log(test::data_path("laser2d/intel/intel.clf.bz2").string());
  runs->half = runs->log.scans.size() / 2;
  runs->end = std::min(runs->log.scans.size(), runs->half + 2500);
  const auto start = std::chrono::steady_clock::now();
  Slam2d slam;
  for (std::size_t k = 0; k < runs->half; ++k) slam.add_scan(runs->log.scans[k]);
  slam.finish();
  runs->map = slam.export_map();
  runs->map.source = "intel.clf.bz2, first half";
  runs->map_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t k = runs->half; k < runs->end; ++k) slam.add_scan(runs->log.scans[k]);
  slam.finish();
  runs->reference = slam.trajectory();
  return *runs;
}

struct PoseError {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
PoseError error_of(const core::SE2& estimate, const core::SE2& reference) {
  const core::SE2 e = reference.inverse() * estimate;
  return {e.translation().norm(), std::abs(e.angle())};
}
// A wrong pose: farther from the reference than the two maps can differ (a few centimetres,
// up to 0.3 m where the first half saw little).
bool wrong(const PoseError& e) { return e.translation_m > 0.5 || e.rotation_rad > 5.0 * std::numbers::pi / 180.0; }

// Scans [from, to) of the log fed to the localiser, their odometry moved by T_odom_fed_odom (a
// kidnapping: the odometry goes on as if nothing happened); T_odom_last follows the last scan
// fed. Counts the wrong relocalisations and the wrong ok and degraded poses against the
// reference; returns after how many scans the localiser first said lost and first relocalised.
struct KidnapCounts {
  std::size_t wrong_ok = 0, wrong_relocalisations = 0, wrong_degraded = 0;
};
std::pair<std::optional<std::size_t>, std::optional<std::size_t>> feed_scans(Localizer2d& localizer, const IntelRuns& runs, std::size_t from,
                                                                             std::size_t to, const core::SE2& T_odom_fed_odom,
                                                                             core::SE2& T_odom_last, KidnapCounts& counts) {
  std::optional<std::size_t> lost, relocalised;
  for (std::size_t k = from; k < to; ++k) {
    io::LaserScan scan = runs.log.scans[k];
    scan.T_odom_laser = T_odom_fed_odom * scan.T_odom_laser;
    T_odom_last = scan.T_odom_laser;
    const LocalizationResult r = localizer.add_scan(scan);
    const PoseError e = error_of(r.T_map_laser, runs.reference[k].T_world_laser);
    if (r.health == Health::kLost && !lost) lost = k - from;
    if (r.relocalised && !relocalised) relocalised = k - from;
    if (r.relocalised && wrong(e)) ++counts.wrong_relocalisations;
    if (r.localised && r.health == Health::kOk && wrong(e)) ++counts.wrong_ok;
    if (r.localised && r.health == Health::kDegraded && wrong(e)) ++counts.wrong_degraded;
  }
  return {lost, relocalised};
}

core::SE3 lift(const core::SE2& T) {
  return core::SE3(core::SO3::from_rpy(0.0, 0.0, T.angle()), Eigen::Vector3d(T.x(), T.y(), 0.0));
}

TEST(LocalizationIntel, MapFileRoundTrip) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const IntelRuns& runs = intel();
  const fs::path dir = temp_dir("intel-map");
  const std::string path = (dir / "intel-half.cmap").string();
  const auto start = std::chrono::steady_clock::now();
  write_saved_map(path, runs.map);
  const double write_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const SavedMap2D back = read_saved_map(path);
  const double read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - write_s;
  const auto bytes = fs::file_size(path);
  std::printf("map of the first half (%zu scans, Slam2d %.1f s): %zu submaps, %zu keyframes; file %ju bytes, written in "
              "%.2f s, read in %.2f s\n",
              runs.half, runs.map_s, runs.map.submaps.size(), runs.map.keyframes.size(), static_cast<std::uintmax_t>(bytes),
              write_s, read_s);
  expect_same_map(runs.map, back);
  EXPECT_LT(bytes, 20u << 20);
  fs::remove_all(dir);
}

// The second pass: the first 1,200 scans of the second half localised in the first half's map
// from no prior (global relocalisation, then tracking), against the continued Slam2d run.
TEST(LocalizationIntel, SecondHalfFromNoPrior) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const IntelRuns& runs = intel();
  Localizer2d localizer(runs.map);
  const std::size_t end = std::min(runs.end, runs.half + 1200);
  io::Trajectory estimate;
  std::vector<std::pair<core::Timestamp, core::SE3>> localised;
  std::vector<double> errors_m;
  double rotation_sum_rad = 0.0;
  std::size_t wrong_ok = 0, wrong_relocalisations = 0;
  std::optional<std::size_t> first;
  for (std::size_t k = runs.half; k < end; ++k) {
    const LocalizationResult r = localizer.add_scan(runs.log.scans[k]);
    if (!r.localised) continue;
    if (!first) first = k - runs.half;
    const PoseError e = error_of(r.T_map_laser, runs.reference[k].T_world_laser);
    errors_m.push_back(e.translation_m);
    rotation_sum_rad += e.rotation_rad;
    if (r.relocalised && wrong(e)) ++wrong_relocalisations;
    if (r.health == Health::kOk && wrong(e)) ++wrong_ok;
    localised.emplace_back(r.time, lift(r.T_map_laser));
  }
  const Localizer2dSummary& s = localizer.summary();
  ASSERT_TRUE(first.has_value()) << "never localised";
  std::vector<double> sorted = errors_m;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0.0;
  for (const double e : errors_m) mean += e / static_cast<double>(errors_m.size());
  // The relations metric over the relations whose both ends were localised (frame-free).
  std::stable_sort(localised.begin(), localised.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [time, pose] : localised) {
    if (!estimate.stamps.empty() && !(estimate.stamps.back() < time)) continue;
    estimate.stamps.push_back(time);
    estimate.poses.push_back(pose);
  }
  auto near = [&](core::Timestamp t) {
    const auto it = std::lower_bound(estimate.stamps.begin(), estimate.stamps.end(), t);
    return (it != estimate.stamps.end() && std::abs(it->seconds() - t.seconds()) < 0.02) ||
           (it != estimate.stamps.begin() && std::abs(std::prev(it)->seconds() - t.seconds()) < 0.02);
  };
  std::vector<eval::Relation> relations;
  for (const auto& r : eval::read_relations(test::data_path("laser2d/intel/intel.relations").string()))
    if (near(r.from) && near(r.to)) relations.push_back(r);
  const eval::RelationsResult metric = eval::evaluate_relations(relations, estimate);
  ASSERT_TRUE(metric.outcome.ok()) << metric.outcome.message;
  std::printf("second half, scans %zu..%zu from no prior: localised at scan %zu; %zu of %zu scans localised (%zu ok, %zu "
              "degraded), %zu relocalisations\n",
              runs.half, end - 1, *first, s.scans_localised, s.scans, s.scans_ok, s.scans_degraded, s.relocalisations.size());
  std::printf("error against the continued Slam2d run: mean %.3f m, median %.3f m, max %.3f m, rotation mean %.2f deg; "
              "relations (%zu with both ends localised) %.4f m %.3f deg\n",
              mean, sorted[sorted.size() / 2], sorted.back(),
              rotation_sum_rad / static_cast<double>(errors_m.size()) * 180.0 / std::numbers::pi, relations.size(),
              metric.translation_absolute_m.mean, metric.rotation_absolute_deg.mean);
  std::printf("time: %.1f s for %zu scans (%.1f ms per scan, slowest %.0f ms); tracking %.2f s, %zu global searches %.2f s "
              "(slowest %.0f ms), %zu rankings %.2f s; setup %.2f s\n",
              s.total_s, s.scans, 1e3 * s.total_s / static_cast<double>(s.scans), 1e3 * s.max_scan_s, s.times.tracking_s,
              s.global_searches, s.times.global_search_s, 1e3 * s.max_global_search_s, s.rankings, s.times.ranking_s,
              s.times.setup_s);
  EXPECT_LE(*first, 10u) << "global relocalisation from no prior should take a few scans";
  EXPECT_EQ(wrong_relocalisations, 0u);
  EXPECT_EQ(wrong_ok, 0u);
  EXPECT_GT(s.scans_localised, s.scans * 95 / 100);
  EXPECT_LT(mean, 0.12);
  EXPECT_LT(metric.translation_absolute_m.mean, 0.04);
}

// Kidnapping: the robot is localised on the first 103 scans of the second half, then carried to
// two other places of the log in turn (the odometry continues as if it had not moved). Each
// time the localiser must say lost within a few scans, relocalise at the right place within a
// few more, and never report an ok pose that is wrong.
TEST(LocalizationIntel, KidnappedRobotIsRelocalised) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const IntelRuns& runs = intel();
  Localizer2d localizer(runs.map);
  KidnapCounts counts;
  core::SE2 T_odom_last;
  auto feed = [&](std::size_t from, std::size_t to, const core::SE2& T_odom_fed_odom) {
    return feed_scans(localizer, runs, from, to, T_odom_fed_odom, T_odom_last, counts);
  };
  const auto [start_lost, start_fix] = feed(runs.half, runs.half + 103, core::SE2());
  ASSERT_TRUE(start_fix.has_value()) << "never localised at the start";
  for (const std::size_t b : {runs.half + 1769, runs.half + 2334}) {
    ASSERT_LT(b + 41, runs.end);
    // Odometry continues from the last scan fed: T_odom_fed = T_odom_last * T_odom(b - 1)^-1 * T_odom(k).
    const core::SE2 T_odom_fed_odom = T_odom_last * runs.log.scans[b - 1].T_odom_laser.inverse();
    const double distance =
        (runs.reference[b].T_world_laser.translation() - localizer.map().keyframes.front().T_world_laser.translation()).norm();
    const auto [lost, relocalised] = feed(b, b + 41, T_odom_fed_odom);
    std::printf("kidnapped to scan %zu (%.1f m from the map's start): lost after %d scans, relocalised after %d\n", b,
                distance, lost ? static_cast<int>(*lost) : -1, relocalised ? static_cast<int>(*relocalised) : -1);
    ASSERT_TRUE(lost.has_value()) << "the kidnapping to scan " << b << " went unnoticed";
    EXPECT_LE(*lost, 6u);
    ASSERT_TRUE(relocalised.has_value()) << "not relocalised after the kidnapping to scan " << b;
    EXPECT_LE(*relocalised, 20u);
  }
  const Localizer2dSummary& s = localizer.summary();
  for (const HealthEvent& e : s.health_events)
    if (e.to == Health::kLost || e.from == Health::kLost) std::printf("  scan %zu: %s\n", e.scan, e.reason.c_str());
  std::printf("%zu relocalisations, %zu global searches (slowest %.0f ms), slowest scan %.0f ms\n", s.relocalisations.size(),
              s.global_searches, 1e3 * s.max_global_search_s, 1e3 * s.max_scan_s);
  EXPECT_EQ(counts.wrong_relocalisations, 0u);
  EXPECT_EQ(counts.wrong_ok, 0u);
}

}  // namespace
}  // namespace cairn::slam2d

namespace cairn::slam2d {
namespace {

// The kidnapping sweep (issue 20): localised on the first 103 scans of the second half, then
// carried in turn to 16 places of it, the scans half + 200 + 400 (7 j mod 16) for j = 1..16 (a
// fixed order that makes the jumps long; odometry continuing as if nothing happened), 150 scans
// at each, against a Slam2d run of the whole log. Per jump: how many scans until `lost`, until
// relocalised, and every relocalisation or ok pose more than 0.5 m / 5 degrees off (wrong()). Disabled (run
// with --gtest_also_run_disabled_tests): 5-10 minutes, a measurement for docs/slam2d.md.
TEST(LocalizationIntel, DISABLED_KidnapSweepOverTheSecondHalf) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  // Its own runs: the map of the first half, the reference over the whole log.
  IntelRuns runs;
  runs.log = io::read_carmen_log(test::data_path("laser2d/intel/intel.clf.bz2").string());
  runs.half = runs.log.scans.size() / 2;
  runs.end = runs.log.scans.size();
  {
    Slam2d slam;
    for (std::size_t k = 0; k < runs.half; ++k) slam.add_scan(runs.log.scans[k]);
    slam.finish();
    runs.map = slam.export_map();
    for (std::size_t k = runs.half; k < runs.end; ++k) slam.add_scan(runs.log.scans[k]);
    slam.finish();
    runs.reference = slam.trajectory();
  }
  Localizer2d localizer(runs.map);
  core::SE2 T_odom_last;
  KidnapCounts start_counts, counts;
  const auto [start_lost, start_fix] = feed_scans(localizer, runs, runs.half, runs.half + 103, core::SE2(), T_odom_last, start_counts);
  ASSERT_TRUE(start_fix.has_value()) << "never localised at the start";
  std::size_t jumps = 0, noticed = 0, relocalised_within_20 = 0, relocalised_at_all = 0;
  core::SE2 T_world_before = runs.reference[runs.half + 102].T_world_laser;
  for (std::size_t j = 1; j <= 16; ++j) {
    const std::size_t b = runs.half + 200 + 400 * ((7 * j) % 16);
    if (b + 150 > runs.end) continue;
    ++jumps;
    const core::SE2 T_odom_fed_odom = T_odom_last * runs.log.scans[b - 1].T_odom_laser.inverse();
    const double distance = (runs.reference[b].T_world_laser.translation() - T_world_before.translation()).norm();
    const KidnapCounts before = counts;
    const auto [lost, relocalised] = feed_scans(localizer, runs, b, b + 150, T_odom_fed_odom, T_odom_last, counts);
    T_world_before = runs.reference[b + 149].T_world_laser;
    noticed += lost ? 1 : 0;
    relocalised_at_all += relocalised ? 1 : 0;
    relocalised_within_20 += lost && relocalised && *relocalised <= *lost + 20 ? 1 : 0;
    const std::size_t wrong_reloc = counts.wrong_relocalisations - before.wrong_relocalisations, wrong_ok = counts.wrong_ok - before.wrong_ok;
    std::printf("jump %2zu to scan %zu (%.1f m): lost after %d scans, relocalised after %d; %zu wrong relocalisations, %zu wrong ok poses\n",
                jumps, b, distance, lost ? static_cast<int>(*lost) : -1, relocalised ? static_cast<int>(*relocalised) : -1, wrong_reloc,
                wrong_ok);
  }
  const Localizer2dSummary& s = localizer.summary();
  std::printf("kidnap sweep: %zu jumps, %zu noticed (lost), %zu relocalised (%zu within 20 scans of being lost), %zu wrong "
              "relocalisations, %zu wrong ok poses, %zu wrong degraded poses; %zu relocalisations in all, %.0f s\n",
              jumps, noticed, relocalised_at_all, relocalised_within_20, counts.wrong_relocalisations, counts.wrong_ok, counts.wrong_degraded,
              s.relocalisations.size(), s.total_s);
  // Measured 2026-11-25 (docs/slam2d.md): every jump noticed, 12 of 16 relocalised, none wrong.
  EXPECT_EQ(jumps, 16u);
  EXPECT_EQ(noticed, jumps);
  EXPECT_GE(relocalised_at_all, jumps / 2);
  EXPECT_EQ(counts.wrong_ok, 0u);
}

}  // namespace
}  // namespace cairn::slam2d
