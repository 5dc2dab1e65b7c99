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
#include <random>

#include "cairn/eval/relations.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/localization.hpp"
#include "cairn/slam2d/map_file.hpp"
#include "cairn/slam2d/place_search.hpp"
#include "cairn/slam2d/range_scan.hpp"
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
// Localisation on the Intel log.

struct IntelRuns {
  io::CarmenLog log;
  std::size_t half = 0;     ///< the map is Slam2d on scans [0, half)
  std::size_t end = 0;      ///< the reference covers [0, end)
  SavedMap2D map;
  /// The same Slam2d run continued to `end` and finished again: the reference poses, in the
  /// map's frame (both start at the first scan, whose keyframe the pose graph holds fixed).
  std::vector<ScanResult> reference;
  double map_s = 0.0;
};

const IntelRuns& intel() {
  static std::unique_ptr<IntelRuns> runs;
  if (runs) return *runs;
  runs = std::make_unique<IntelRuns>();
  runs->log = io::read_carmen_log(test::data_path("laser2d/intel/intel.clf.bz2").string());
  runs->half = runs->log.scans.size() / 2;
  runs->end = std::min(runs->log.scans.size(), runs->half + (std::getenv("REFEND") ? std::strtoul(std::getenv("REFEND"), nullptr, 10) : 2700));
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

TEST(LocalizationIntel, SecondHalfFromNoPrior) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const IntelRuns& runs = intel();
  std::printf("map of the first half (%zu scans): %zu submaps, %zu keyframes, %.1f s\n", runs.half, runs.map.submaps.size(),
              runs.map.keyframes.size(), runs.map_s);
  const fs::path dir = temp_dir("intel");
  const std::string path = (dir / "intel-half.cmap").string();
  write_saved_map(path, runs.map);
  std::printf("map file: %ju bytes\n", static_cast<std::uintmax_t>(fs::file_size(path)));
  const SavedMap2D loaded = read_saved_map(path);
  fs::remove_all(dir);
  Localizer2d localizer(loaded);
  std::printf("setup %.2f s, %zu tracking points, %.1f MB precomputation grids\n", localizer.summary().times.setup_s,
              localizer.summary().map_points, static_cast<double>(localizer.summary().precomputation_bytes) / 1e6);
  std::size_t first = 0;
  bool have_first = false;
  double sum_t = 0.0, max_t = 0.0, sum_r = 0.0, max_r = 0.0;
  std::size_t compared = 0, wrong = 0;
  int hist_good[10] = {}, hist_bad[10] = {};
  std::vector<std::pair<std::size_t, core::SE2>> localised;
  std::map<std::size_t, Health> health_of;
  std::map<std::size_t, double> conf_of;
  const std::size_t end = std::getenv("END") ? runs.half + std::strtoul(std::getenv("END"), nullptr, 10) : runs.end;
  for (std::size_t k = runs.half; k < end; ++k) {
    const LocalizationResult r = localizer.add_scan(runs.log.scans[k]);
    if (!r.localised) continue;
    localised.emplace_back(k, r.T_map_laser);
    health_of[k] = r.health;
    conf_of[k] = r.confidence;
    if (!have_first) {
      first = k - runs.half;
      have_first = true;
    }
    const PoseError e = error_of(r.T_map_laser, runs.reference[k].T_world_laser);
    if (r.relocalised && (e.translation_m > 0.3 || e.rotation_rad > 0.05)) ++wrong;
    {
      const int bucket = std::min(9, static_cast<int>(r.confidence * 10));
      if (e.translation_m < 0.2) ++hist_good[bucket]; else ++hist_bad[bucket];
    }
    sum_t += e.translation_m;
    sum_r += e.rotation_rad;
    max_t = std::max(max_t, e.translation_m);
    max_r = std::max(max_r, e.rotation_rad);
    ++compared;
  }
  const auto& s = localizer.summary();
  std::printf("localised at scan %zu of the second half; %zu of %zu scans localised; error vs the full run: mean %.3f m "
              "%.2f deg, max %.3f m %.2f deg\n",
              first, compared, runs.log.scans.size() - runs.half, sum_t / static_cast<double>(std::max<std::size_t>(compared, 1)),
              sum_r / static_cast<double>(std::max<std::size_t>(compared, 1)) * 180.0 / std::numbers::pi, max_t, max_r * 180.0 / std::numbers::pi);
  std::printf("health: %zu ok, %zu degraded, %zu lost; %zu relocalisations, %zu global searches (max %.3f s), %zu "
              "confirmation searches, %zu hypotheses (%zu dropped); time %.2f s, max per scan %.3f s\n",
              s.scans_ok, s.scans_degraded, s.scans_lost, s.relocalisations.size(), s.global_searches, s.max_global_search_s,
              s.confirmation_searches, s.hypotheses, s.hypotheses_dropped, s.total_s, s.max_scan_s);
  for (const auto& e : s.health_events) std::printf("  scan %zu: %s\n", e.scan, e.reason.c_str());
  {
    // Relations metric over relations whose both ends were localised, for the localiser and for
    // the full Slam2d run (the same relations).
    const auto relations = eval::read_relations(test::data_path("laser2d/intel/intel.relations").string());
    io::Trajectory est, ref;
    std::vector<std::pair<core::Timestamp, std::pair<core::SE2, core::SE2>>> rows;
    for (const auto& [k, pose] : localised) rows.push_back({runs.log.scans[k].time, {pose, runs.reference[k].T_world_laser}});
    std::stable_sort(rows.begin(), rows.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    auto lift = [](const core::SE2& T) { return core::SE3(core::SO3::from_rpy(0.0, 0.0, T.angle()), Eigen::Vector3d(T.x(), T.y(), 0.0)); };
    for (const auto& row : rows) {
      if (!est.stamps.empty() && !(est.stamps.back() < row.first)) continue;
      est.stamps.push_back(row.first);
      est.poses.push_back(lift(row.second.first));
      ref.stamps.push_back(row.first);
      ref.poses.push_back(lift(row.second.second));
    }
    auto near = [&](core::Timestamp t) {
      const auto it = std::lower_bound(est.stamps.begin(), est.stamps.end(), t);
      double best = 1e9;
      if (it != est.stamps.end()) best = std::min(best, std::abs(it->seconds() - t.seconds()));
      if (it != est.stamps.begin()) best = std::min(best, std::abs(std::prev(it)->seconds() - t.seconds()));
      return best < 0.02;
    };
    std::vector<eval::Relation> used;
    for (const auto& r : relations) if (near(r.from) && near(r.to)) used.push_back(r);
    const auto a = eval::evaluate_relations(used, est);
    const auto b = eval::evaluate_relations(used, ref);
    std::printf("relations (%zu with both ends localised): localiser %.4f m %.3f deg; full Slam2d run %.4f m %.3f deg\n", used.size(),
                a.translation_absolute_m.mean, a.rotation_absolute_deg.mean, b.translation_absolute_m.mean, b.rotation_absolute_deg.mean);
  }
  {
    // Reference corrected locally: the full run's pose moved by the offset between the map's
    // and the full run's pose of the nearest map keyframe (the two maps differ slightly).
    std::map<std::int64_t, core::SE2> full_by_time;
    for (std::size_t k = 0; k < runs.half; ++k) full_by_time.emplace(runs.log.scans[k].time.nanoseconds(), runs.reference[k].T_world_laser);
    double sum = 0, mx = 0, sumr = 0;
    int bad = 0;
    for (const auto& [k, pose] : localised) {
      std::size_t nearest = 0;
      double d = 1e9;
      for (std::size_t q = 0; q < runs.map.keyframes.size(); ++q) {
        const double dk = (runs.map.keyframes[q].T_world_laser.translation() - pose.translation()).norm();
        if (dk < d) { d = dk; nearest = q; }
      }
      const SavedKeyframe& kf = runs.map.keyframes[nearest];
      const core::SE2 T_map_full = kf.T_world_laser * full_by_time.at(kf.time.nanoseconds()).inverse();
      const PoseError e = error_of(pose, T_map_full * runs.reference[k].T_world_laser);
      sum += e.translation_m; sumr += e.rotation_rad; mx = std::max(mx, e.translation_m);
      if (e.translation_m > 0.2) {
        ++bad;
        if (std::getenv("BAD")) std::printf("   bad scan %zu: %s conf %.2f err %.2f m, nearest kf %.2f m\n", k - runs.half, std::string(to_string(health_of[k])).c_str(), conf_of[k], e.translation_m, d);
      }
    }
    std::printf("locally corrected reference: mean %.3f m %.2f deg, max %.3f m, %d scans > 0.2 m\n", sum / static_cast<double>(localised.size()), sumr / static_cast<double>(localised.size()) * 57.3, mx, bad);
  }
  for (int b = 0; b < 10; ++b) std::printf("confidence %.1f-%.1f: %d good (< 0.2 m), %d bad\n", b / 10.0, (b + 1) / 10.0, hist_good[b], hist_bad[b]);
  EXPECT_TRUE(have_first);
  EXPECT_EQ(wrong, 0u);
}

}  // namespace
}  // namespace cairn::slam2d

namespace cairn::slam2d {
namespace {
}  // namespace
}  // namespace cairn::slam2d

namespace cairn::slam2d {
namespace {
}  // namespace
}  // namespace cairn::slam2d

#include "cairn/slam2d/localization_outputs.hpp"
namespace cairn::slam2d {
namespace {
}  // namespace
}  // namespace cairn::slam2d

namespace cairn::slam2d {
namespace {
}  // namespace
}  // namespace cairn::slam2d

namespace cairn::slam2d {
namespace {
}  // namespace
}  // namespace cairn::slam2d
