// The pipelines in Python (bindings.hpp): LidarSlam, Slam2d and VisualSlam fed one measurement at a
// time, as `cairn slam3d`, `cairn slam2d` and `cairn vslam` feed them, and the readers that give
// exactly what those commands feed (scan_sequence, read_carmen_log, read_image_sequence,
// read_gray_image, read_depth_image). The GIL is released while a pipeline works; each pipeline
// object serialises its own calls with a mutex, taken without the GIL (a thread waiting for it
// must not hold up the others), so Python threads may share one.

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "cairn/core/health.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/io/calibration_yaml.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parameters.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/config.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/report.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"
#include "cairn/slam2d/config.hpp"
#include "cairn/slam2d/outputs.hpp"
#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/slam2d/slam.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "cairn/vslam/config.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::python {
namespace {

// ---------------------------------------------------------------------------------------------
// Shared helpers

/// A str or os.PathLike as the path string the readers take.
std::string fspath(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

double finite_or_throw(double value, const char* what) {
  if (!std::isfinite(value)) throw_value_error(std::string(what) + ": not a finite number");
  return value;
}

/// Seconds as core::Timestamp (from_seconds' precondition checked: finite, within +-9.2e9 s).
core::Timestamp timestamp_of(double seconds, const char* what) {
  if (!(std::abs(seconds) < 9.2e9)) throw_value_error(std::string(what) + ": expected finite seconds within +-9.2e9");
  return core::Timestamp::from_seconds(seconds);
}

py::array_t<double> matrix_to_array(const Matrix4& T) {
  py::array_t<double> out({py::ssize_t{4}, py::ssize_t{4}});
  auto view = out.mutable_unchecked<2>();
  for (py::ssize_t r = 0; r < 4; ++r) {
    for (py::ssize_t c = 0; c < 4; ++c) view(r, c) = T(r, c);
  }
  return out;
}

py::array_t<std::int64_t> indices_to_array(const std::vector<std::size_t>& indices) {
  py::array_t<std::int64_t> out(static_cast<py::ssize_t>(indices.size()));
  auto view = out.mutable_unchecked<1>();
  for (std::size_t k = 0; k < indices.size(); ++k) view(static_cast<py::ssize_t>(k)) = static_cast<std::int64_t>(indices[k]);
  return out;
}

std::string health_word(core::Health health) { return std::string(core::to_string(health)); }

/// A `set` value as the text of `--set key=value`: booleans true/false (Python prints True),
/// numbers shortest round trip, sequences space-separated (scan_context.lateral_offsets_m).
std::string setting_text(const std::string& key, const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  const py::module_ numbers = py::module_::import("numbers");
  if (py::isinstance(value, numbers.attr("Integral"))) return py::str(py::int_(py::reinterpret_borrow<py::object>(value)));
  if (py::isinstance(value, numbers.attr("Real"))) return py::repr(py::float_(py::reinterpret_borrow<py::object>(value)));
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    std::string text;
    for (const py::handle item : value) text += (text.empty() ? "" : " ") + setting_text(key, item);
    return text;
  }
  throw_value_error("set['" + key + "']: expected a bool, number, string or list of numbers, found " +
                    py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>());
}

/// The configuration file, then each key of `set` in order: `cairn <command> --config FILE --set
/// key=value ...`. Unknown keys and bad values raise ValueError naming the key (io::set_parameter),
/// a bad file cairn.ParseError.
template <class Options>
void apply_configuration(const io::Configuration<Options>& configuration, Options& options, const py::object& config,
                         const py::object& set) {
  if (!config.is_none()) configuration.load(fspath(config), options);
  if (set.is_none()) return;
  if (!py::isinstance<py::dict>(set)) throw py::type_error("set: expected a dict of key -> value");
  for (const auto& [key, value] : set.cast<py::dict>()) {
    const std::string name = py::str(key).cast<std::string>();
    configuration.set(name + "=" + setting_text(name, value), options);
  }
}

/// Runs `work` without the GIL and under `mutex`; what it returns is C++ data, converted after.
template <class Work>
auto locked(std::mutex& mutex, Work&& work) {
  const py::gil_scoped_release release;
  const std::lock_guard<std::mutex> lock(mutex);
  return work();
}

/// A 1-D array of `n` values (or none), converted once; ValueError naming `what` otherwise.
template <class T>
py::array_t<T, py::array::c_style | py::array::forcecast> vector_argument(const py::object& values, std::size_t n,
                                                                           const char* what) {
  auto array = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!array || array.ndim() != 1 || static_cast<std::size_t>(array.shape(0)) != n) {
    throw_value_error(std::string(what) + ": expected a 1-D array of " + std::to_string(n) + " numbers (one per point)");
  }
  return array;
}

// ---------------------------------------------------------------------------------------------
// 3D LiDAR SLAM

/// The preset, the file and the keys, validated as `cairn slam3d` does (slam3d_flags.cpp).
lidar3d::SlamConfiguration lidar_configuration(const std::string& preset, const py::object& config, const py::object& set) {
  lidar3d::SlamConfiguration options;
  options.slam.odometry = lidar3d::preset_options(preset);
  apply_configuration(lidar3d::configuration(), options, config, set);
  std::string error;
  if (!options.is_valid(&error)) throw_value_error("invalid configuration: " + error);
  return options;
}

/// A scan from arrays: points N x 3 plus optional per-point times (seconds from the sweep's
/// start), intensities and rings, as io::PointCloud holds them.
io::PointCloud cloud_from_arrays(const FloatArray& points, const py::object& point_times, const py::object& intensity,
                                 const py::object& ring) {
  io::PointCloud cloud;
  cloud.points = points_from_array(points, "points");
  const std::size_t n = cloud.size();
  if (!point_times.is_none()) {
    const auto times = vector_argument<float>(point_times, n, "point_times");
    cloud.time_s.assign(times.data(), times.data() + n);
    if (!std::all_of(cloud.time_s.begin(), cloud.time_s.end(), [](float t) { return std::isfinite(t); })) {
      throw_value_error("point_times: a value is not finite");
    }
  }
  if (!intensity.is_none()) {
    const auto values = vector_argument<float>(intensity, n, "intensity");
    cloud.intensity.assign(values.data(), values.data() + n);
  }
  if (!ring.is_none()) {
    const auto rings = vector_argument<std::int64_t>(ring, n, "ring");
    cloud.ring.reserve(n);
    for (std::size_t k = 0; k < n; ++k) {
      const std::int64_t r = rings.data()[k];
      if (r < 0 || r > 65535) throw_value_error("ring: value " + std::to_string(r) + " at " + std::to_string(k) + " is not in 0..65535");
      cloud.ring.push_back(static_cast<std::uint16_t>(r));
    }
  }
  return cloud;
}

nlohmann::json lidar_candidate_json(const lidar3d::LoopCandidateRecord& c) {
  return {{"query_keyframe", c.query_keyframe},     {"candidate_keyframe", c.candidate_keyframe},
          {"query_time_s", c.query_time_s},         {"candidate_time_s", c.candidate_time_s},
          {"descriptor_distance", c.descriptor_distance}, {"fitness", c.fitness},
          {"rms_m", c.rms_m},                       {"gate_translation_m", c.gate_translation_m},
          {"gate_limit_m", c.gate_limit_m},         {"decision", c.decision},
          {"accepted", c.accepted},                 {"rejected_by_gnc", c.rejected_by_gnc}};
}

/// Health counts, map segments and points, and the loop closure's counts, times and candidates.
nlohmann::json lidar_summary_json(const lidar3d::LidarSlam& slam, const lidar3d::SlamRun& run) {
  const lidar3d::HealthCounts health = run.health_counts();
  const lidar3d::LidarSlamSummary& s = slam.summary();
  nlohmann::json candidates = nlohmann::json::array();
  for (const lidar3d::LoopCandidateRecord& c : s.candidates) candidates.push_back(lidar_candidate_json(c));
  return {{"scans", run.scans().size()},
          {"scans_ok", health.ok},
          {"scans_degraded", health.degraded},
          {"scans_lost", health.lost},
          {"scans_with_unusable_point_times", health.unusable_point_times},
          {"map_segments", run.scans().empty() ? 0 : run.scans().back().segment + 1},
          {"map_points", run.global_map().size()},
          {"front_end", std::string(lidar3d::to_string(slam.front_end()))},
          {"keyframes", s.keyframes},
          {"loop_queries", s.loop_queries},
          {"loops_accepted", s.loops_accepted},
          {"loops_rejected_by_gnc", s.loops_rejected_by_gnc},
          {"optimizations", s.optimizations},
          {"loop_search_s", s.loop_search_s},
          {"verification_s", s.verification_s},
          {"optimization_s", s.optimization_s},
          {"candidates", candidates}};
}

/// LidarSlam and the record of its run (SlamRun), held together as `cairn slam3d` holds them: the
/// run keeps the keyframes' points and assembles the global map (map.ply) at finish().
class LidarSession {
 public:
  LidarSession(lidar3d::SlamConfiguration options, std::string preset, double map_voxel_m)
      : options_(std::move(options)),
        preset_(std::move(preset)),
        slam_(options_.slam),
        run_(options_.slam.odometry, map_voxel_m) {
    sequence_.times_from_file = true;  // the caller gives every time
  }

  lidar3d::SlamScanResult add_scan(const io::PointCloud& cloud, double time_s) {
    finite_or_throw(time_s, "time");
    return locked(mutex_, [&] {
      if (finished_) throw std::runtime_error("LidarSlam.finish() was called: no scan may follow it");
      lidar3d::SlamScanResult result = slam_.add_scan(cloud, time_s);
      // No file was read here: 0 s of reading, as the report's read_file times say.
      run_.add_scan(sequence_.files.size(), cloud, result, 0.0);
      sequence_.files.push_back("scan " + std::to_string(sequence_.files.size()));
      sequence_.times_s.push_back(time_s);
      return result;
    });
  }

  void finish() {
    locked(mutex_, [&] {
      if (finished_) return;
      if (run_.scans().empty()) throw std::runtime_error("LidarSlam.finish(): no scan was added");
      slam_.finish();
      run_.finish(slam_);
      finished_ = true;
      wall_time_s_ = core::seconds_since(start_);
    });
  }

  py::array_t<double> trajectory() { return poses_to_array(locked(mutex_, [&] { return slam_.trajectory(); })); }
  py::array_t<double> times() { return vector_to_array(locked(mutex_, [&] { return sequence_.times_s; })); }
  py::array_t<double> keyframe_poses() { return poses_to_array(locked(mutex_, [&] { return slam_.keyframe_poses(); })); }
  py::array_t<std::int64_t> keyframe_scans() { return indices_to_array(locked(mutex_, [&] { return slam_.keyframe_scans(); })); }

  std::vector<std::string> health() {
    return locked(mutex_, [&] {
      std::vector<std::string> words;
      for (const lidar3d::OdometryScanResult& r : run_.scans()) words.push_back(health_word(r.health));
      return words;
    });
  }

  py::array_t<float> map_points() {
    return points_to_array(locked(mutex_, [&] {
      if (!finished_) throw std::runtime_error("LidarSlam.map_points(): the global map is assembled by finish()");
      return run_.global_map().points();
    }));
  }

  py::object summary() { return json_to_python(locked(mutex_, [&] { return lidar_summary_json(slam_, run_); })); }

  py::object report() {
    return json_to_python(locked(mutex_, [&] {
      if (run_.scans().empty()) throw std::runtime_error("LidarSlam.report(): no scan was added");
      const lidar3d::SlamRunInputs inputs{{}, "", preset_, ""};
      const double wall_s = finished_ ? wall_time_s_ : core::seconds_since(start_);
      return lidar3d::report_json(inputs, sequence_, slam_, run_, wall_s, !finished_, std::nullopt);
    }));
  }

  py::object config() const { return json_to_python(lidar3d::configuration().json(options_)); }
  std::size_t scans() { return locked(mutex_, [&] { return sequence_.files.size(); }); }
  bool finished() { return locked(mutex_, [&] { return finished_; }); }
  std::string front_end() { return locked(mutex_, [&] { return std::string(lidar3d::to_string(slam_.front_end())); }); }
  double map_voxel_m() const { return run_.map_voxel_m(); }

 private:
  lidar3d::SlamConfiguration options_;
  std::string preset_;
  lidar3d::LidarSlam slam_;
  lidar3d::SlamRun run_;
  lidar3d::ScanSequence sequence_;  ///< one label and time per scan added, for report()
  bool finished_ = false;
  core::Clock::time_point start_ = core::Clock::now();
  double wall_time_s_ = 0.0;
  std::mutex mutex_;
};

/// The scans and their times as `cairn slam3d SCANS [--times FILE --times-column C]
/// [--max-scans N]` reads them (cmd_slam3d.cpp read_sequence; scan files, not bags): without a
/// times table the scans are 0.1 s apart.
lidar3d::ScanSequence scan_sequence(const py::object& scans, const py::object& times, int times_column, long max_scans) {
  if (times_column < 1) throw_value_error("times_column: expected a column number >= 1");
  if (max_scans < 0) throw_value_error("max_scans: expected >= 0 (0: all)");
  std::vector<std::string> paths;
  if (py::isinstance<py::str>(scans) || py::hasattr(scans, "__fspath__")) {
    paths.push_back(fspath(scans));
  } else {
    for (const py::handle path : scans) paths.push_back(fspath(path));
  }
  const std::string times_path = times.is_none() ? std::string() : fspath(times);
  const py::gil_scoped_release release;
  lidar3d::ScanSequence sequence = lidar3d::make_scan_sequence(paths, "", 1);
  std::size_t n = sequence.files.size();
  if (max_scans > 0) n = std::min(n, static_cast<std::size_t>(max_scans));
  sequence.files.resize(n);
  if (!times_path.empty()) {
    sequence.times_s = lidar3d::read_scan_times(times_path, times_column, n);
    sequence.times_from_file = true;
  } else {
    sequence.times_s.resize(n);
  }
  return sequence;
}

// ---------------------------------------------------------------------------------------------
// 2D LiDAR SLAM

/// (x, y, theta) of a planar pose.
py::array_t<double> pose2_to_array(const core::SE2& T) {
  py::array_t<double> out(3);
  auto view = out.mutable_unchecked<1>();
  view(0) = T.x();
  view(1) = T.y();
  view(2) = T.angle();
  return out;
}

/// (x, y, theta) from a sequence of three finite numbers; ValueError naming `what` otherwise.
core::SE2 pose2_from(const py::object& pose, const char* what) {
  const auto array = DoubleArray::ensure(pose);
  if (!array || array.ndim() != 1 || array.shape(0) != 3) throw_value_error(std::string(what) + ": expected (x, y, theta)");
  const double* v = array.data();
  if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) throw_value_error(std::string(what) + ": not finite");
  return core::SE2(v[0], v[1], v[2]);
}

/// A laser record as a robot would hand it over. Readings that are not finite (ROS' no-return)
/// become no-returns at `max_range` as cairn's bag reader makes them (bag/laser_log.cpp); without
/// a max_range they are refused. Without odometry the prediction is "no motion" (the identity),
/// as for a bag without an odometry topic.
io::LaserScan laser_scan(const FloatArray& ranges, double angle_min, double angle_increment, double time,
                         const py::object& odometry, std::optional<double> max_range) {
  if (ranges.ndim() != 1) throw_value_error("ranges: expected a 1-D array, found " + std::to_string(ranges.ndim()) + " dimensions");
  finite_or_throw(angle_min, "angle_min");
  if (!std::isfinite(angle_increment) || angle_increment == 0.0) throw_value_error("angle_increment: expected a finite, non-zero angle");
  if (max_range && !(*max_range > 0.0 && std::isfinite(*max_range))) throw_value_error("max_range: expected a finite range > 0");
  io::LaserScan scan;
  scan.tag = "python";
  scan.time = timestamp_of(time, "time");
  scan.geometry.start_angle_rad = angle_min;
  scan.geometry.angular_resolution_rad = angle_increment;
  scan.geometry.max_range_m = max_range;
  scan.ranges_m.assign(ranges.data(), ranges.data() + ranges.shape(0));
  for (std::size_t k = 0; k < scan.ranges_m.size(); ++k) {
    float& r = scan.ranges_m[k];
    if (!std::isfinite(r) && max_range) r = static_cast<float>(*max_range);
    if (!std::isfinite(r) || r < 0.0f) {
      throw_value_error("ranges: reading " + std::to_string(k) + " is " + std::to_string(r) +
                        " (no-returns may be inf or NaN only when max_range is given)");
    }
  }
  scan.T_odom_laser = odometry.is_none() ? core::SE2() : pose2_from(odometry, "odometry");
  scan.T_odom_robot = scan.T_odom_laser;
  return scan;
}

py::object optional_range(const std::optional<double>& range) { return range ? py::object(py::float_(*range)) : py::object(py::none()); }

slam2d::Slam2dOptions slam2d_configuration(const std::string& preset, const py::object& config, const py::object& set) {
  slam2d::Slam2dOptions options = slam2d::preset_options(preset);
  apply_configuration(slam2d::configuration(), options, config, set);
  std::string error;
  if (!options.is_valid(&error)) throw_value_error("invalid configuration: " + error);
  return options;
}

/// The bounding box of the grid's observed cells (the grid itself grows by doubling and is mostly
/// unknown): probabilities with NaN where unobserved, rows from the lowest y up.
struct OccupancyGrid {
  py::array_t<double> probability;
  double origin_x_m = 0.0;  ///< lower-left corner of cell [0, 0]
  double origin_y_m = 0.0;
  double resolution_m = 0.0;
};

OccupancyGrid occupancy_grid_of(const slam2d::ProbabilityGrid& grid) {
  OccupancyGrid out;
  out.resolution_m = grid.resolution();
  int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
  if (!grid.known_bounds(i0, j0, i1, j1)) {  // nothing observed: an empty grid
    i0 = j0 = 0;
    i1 = j1 = -1;
  }
  out.origin_x_m = grid.origin().x() + i0 * grid.resolution();
  out.origin_y_m = grid.origin().y() + j0 * grid.resolution();
  const py::ssize_t width = i1 - i0 + 1, height = j1 - j0 + 1;
  out.probability = py::array_t<double>({height, width});
  auto view = out.probability.mutable_unchecked<2>();
  for (py::ssize_t j = 0; j < height; ++j) {
    for (py::ssize_t i = 0; i < width; ++i) {
      const int ci = i0 + static_cast<int>(i), cj = j0 + static_cast<int>(j);
      view(j, i) = grid.cell_known(ci, cj) ? grid.cell_probability(ci, cj) : std::nan("");
    }
  }
  return out;
}

/// Slam2d fed as `cairn slam2d` feeds it (cmd_slam2d.cpp).
class Slam2dSession {
 public:
  explicit Slam2dSession(slam2d::Slam2dOptions options) : options_(std::move(options)), slam_(options_) {}

  slam2d::ScanResult add_scan(const io::LaserScan& scan) {
    return locked(mutex_, [&] { return slam_.add_scan(scan); });
  }
  void finish() {
    locked(mutex_, [&] { slam_.finish(); });
  }
  std::vector<slam2d::ScanResult> results() { return locked(mutex_, [&] { return slam_.trajectory(); }); }

  py::array_t<double> trajectory() {
    const std::vector<slam2d::ScanResult> scans = results();
    py::array_t<double> out({static_cast<py::ssize_t>(scans.size()), py::ssize_t{3}});
    auto view = out.mutable_unchecked<2>();
    for (std::size_t k = 0; k < scans.size(); ++k) {
      const auto row = static_cast<py::ssize_t>(k);
      view(row, 0) = scans[k].T_world_laser.x();
      view(row, 1) = scans[k].T_world_laser.y();
      view(row, 2) = scans[k].T_world_laser.angle();
    }
    return out;
  }
  py::array_t<double> times() {
    std::vector<double> seconds;
    for (const slam2d::ScanResult& s : results()) seconds.push_back(s.time.seconds());
    return vector_to_array(seconds);
  }
  std::vector<std::string> health() {
    std::vector<std::string> words;
    for (const slam2d::ScanResult& s : results()) words.push_back(health_word(s.health));
    return words;
  }
  std::string current_health() { return locked(mutex_, [&] { return health_word(slam_.health()); }); }

  /// At `resolution_m` (default output_map_resolution_m, as map.pgm) with the grid options in effect.
  OccupancyGrid occupancy_grid(std::optional<double> resolution_m) {
    slam2d::ProbabilityGridOptions grid_options = options_.grid;
    grid_options.resolution_m = resolution_m.value_or(options_.output_map_resolution_m);
    if (!(grid_options.resolution_m > 0.0) || !std::isfinite(grid_options.resolution_m)) {
      throw_value_error("resolution_m: expected a finite value > 0");
    }
    const slam2d::ProbabilityGrid grid = locked(mutex_, [&] { return slam_.render_map(grid_options); });
    return occupancy_grid_of(grid);
  }
  py::object summary() { return json_to_python(locked(mutex_, [&] { return slam2d::report_json(slam_, options_)["summary"]; })); }
  py::object report() { return json_to_python(locked(mutex_, [&] { return slam2d::report_json(slam_, options_); })); }
  py::object config() const { return json_to_python(slam2d::configuration().json(options_)); }

 private:
  slam2d::Slam2dOptions options_;
  slam2d::Slam2d slam_;
  std::mutex mutex_;
};

/// The laser records of a CARMEN log as `cairn slam2d LOG [--lenient] [--max-scans N]` reads
/// them (replay_flags.cpp read_log; logs, not bags).
std::vector<io::LaserScan> read_carmen_scans(const py::object& path, bool lenient, long max_scans) {
  if (max_scans < 0) throw_value_error("max_scans: expected >= 0 (0: all)");
  const std::string file = fspath(path);
  const py::gil_scoped_release release;
  io::CarmenReadOptions options;
  options.skip_malformed_records = lenient;
  io::CarmenLog log = io::read_carmen_log(file, nullptr, options);
  if (log.scans.empty()) throw io::ParseError(file, 0, "no laser records (FLASER, RLASER, ROBOTLASER1) in the log");
  if (max_scans > 0 && log.scans.size() > static_cast<std::size_t>(max_scans)) log.scans.resize(static_cast<std::size_t>(max_scans));
  return std::move(log.scans);
}

// ---------------------------------------------------------------------------------------------
// Visual SLAM

io::SequenceKind sequence_kind(const std::string& word) {
  if (word == "stereo") return io::SequenceKind::kStereo;
  if (word == "rgbd" || word == "rgb-d") return io::SequenceKind::kRgbd;
  if (word == "monocular" || word == "mono") return io::SequenceKind::kMonocular;
  throw_value_error("kind: expected 'stereo', 'rgbd' or 'monocular', found '" + word + "'");
}

/// A numpy image and the cv::Mat viewing its buffer (the array keeps the buffer alive).
struct ImageView {
  py::array array;
  cv::Mat mat;
};

/// A 2-D array of T as a cv::Mat of `type` over the same memory: no copy when the array is
/// C-contiguous, else one. Another dtype or shape is a ValueError naming `what`.
template <class T>
ImageView image_view(const py::array& image, int type, const char* what, const char* dtype) {
  if (!py::isinstance<py::array_t<T>>(image)) {
    throw_value_error(std::string(what) + ": expected a " + dtype + " array, found dtype " + py::str(image.dtype()).cast<std::string>());
  }
  if (image.ndim() != 2) {
    throw_value_error(std::string(what) + ": expected a 2-D (grey) image, found " + std::to_string(image.ndim()) +
                      " dimensions (colour: convert to grey, e.g. with cairn.read_gray_image)");
  }
  ImageView view;
  view.array = py::array_t<T, py::array::c_style>::ensure(image);
  if (!view.array) throw_value_error(std::string(what) + ": could not be read as a contiguous array");
  view.mat = cv::Mat(static_cast<int>(view.array.shape(0)), static_cast<int>(view.array.shape(1)), type,
                     const_cast<void*>(view.array.data()));  // read only: VisualSlam takes const cv::Mat&
  return view;
}

ImageView gray_view(const py::array& image, const char* what) { return image_view<std::uint8_t>(image, CV_8UC1, what, "uint8"); }

/// A depth image: uint16 in the calibration's depth units, viewed; float metres converted once
/// to those units as cairn converts a 32FC1 depth message (vslam/image_message.cpp): rounded,
/// NaN, infinity, <= 0 and beyond 16 bits as 0 (no depth).
ImageView depth_view(const py::array& depth, double units_per_m) {
  if (py::isinstance<py::array_t<std::uint16_t>>(depth)) return image_view<std::uint16_t>(depth, CV_16UC1, "depth", "uint16");
  if (!py::isinstance<py::array_t<float>>(depth) && !py::isinstance<py::array_t<double>>(depth)) {
    throw_value_error("depth: expected a uint16 (depth units) or float (metres) array, found dtype " +
                      py::str(depth.dtype()).cast<std::string>());
  }
  const auto metres = DoubleArray::ensure(depth);
  if (!metres) throw_value_error("depth: could not be read as an array of numbers");
  if (metres.ndim() != 2) throw_value_error("depth: expected a 2-D image, found " + std::to_string(metres.ndim()) + " dimensions");
  ImageView view;
  view.mat = cv::Mat(static_cast<int>(metres.shape(0)), static_cast<int>(metres.shape(1)), CV_16UC1);
  const double* in = metres.data();
  for (int y = 0; y < view.mat.rows; ++y) {
    auto* out = view.mat.ptr<std::uint16_t>(y);
    for (int x = 0; x < view.mat.cols; ++x) {
      const double units = std::round(*in++ * units_per_m);
      out[x] = std::isfinite(units) && units > 0.0 && units <= 65535.0 ? static_cast<std::uint16_t>(units) : std::uint16_t{0};
    }
  }
  return view;
}

/// A cv::Mat as a 2-D numpy array over its memory (the array owns the Mat).
template <class T>
py::array_t<T> mat_to_array(cv::Mat mat) {
  auto* owner = new cv::Mat(std::move(mat));
  const py::capsule free_when_done(owner, [](void* p) { delete static_cast<cv::Mat*>(p); });
  return py::array_t<T>({static_cast<py::ssize_t>(owner->rows), static_cast<py::ssize_t>(owner->cols)},
                        {static_cast<py::ssize_t>(owner->step[0]), static_cast<py::ssize_t>(sizeof(T))}, owner->ptr<T>(),
                        free_when_done);
}

/// The options `cairn vslam` starts from for the dataset (vslam::dataset_options), then the file
/// and the keys; the vocabulary, when given, for loop closure and relocalisation.
vslam::VisualSlamOptions vslam_configuration(const std::string& dataset, io::SequenceKind kind, const py::object& config,
                                             const py::object& set, const py::object& vocabulary) {
  vslam::VisualSlamOptions options = vslam::dataset_options(dataset, kind);
  apply_configuration(vslam::configuration(), options, config, set);
  if (std::string problems; !options.is_valid(&problems)) throw_value_error("invalid configuration: " + problems);
  if (!vocabulary.is_none()) {
    options.vocabulary = std::make_shared<const vision::Vocabulary>(vision::Vocabulary::load(fspath(vocabulary)));
  }
  return options;
}

nlohmann::json vslam_summary_json(const vslam::VisualSlamSummary& s) {
  nlohmann::json loops = nlohmann::json::array();
  for (const vslam::LoopRecord& l : s.loops) {
    loops.push_back({{"keyframe", l.keyframe}, {"candidate", l.candidate}, {"frame", l.frame},
                     {"candidate_frame", l.candidate_frame}, {"score", l.score}, {"pnp_inliers", l.pnp_inliers},
                     {"matches", l.matches}, {"decision", l.decision}, {"reason", l.reason}, {"merge", l.merge},
                     {"correction_m", l.correction_m}, {"correction_deg", l.correction_deg}});
  }
  return {{"frames", s.frames}, {"frames_ok", s.frames_ok}, {"frames_degraded", s.frames_degraded},
          {"frames_lost", s.frames_lost}, {"keyframes", s.keyframes}, {"keyframes_culled", s.keyframes_culled},
          {"map_points", s.map_points}, {"map_points_culled", s.map_points_culled}, {"local_bas", s.local_bas},
          {"relocalisations", s.relocalisations}, {"loop_queries", s.loop_queries}, {"loops_accepted", s.loops_accepted},
          {"revisits_verified", s.revisits_verified}, {"maps_started", s.maps_started}, {"maps_merged", s.maps_merged},
          {"global_bas", s.global_bas}, {"local_ba_s", s.local_ba_s}, {"loop_s", s.loop_s},
          {"global_ba_s", s.global_ba_s}, {"loops", loops}};
}

/// VisualSlam fed as `cairn vslam` feeds it (cmd_vslam.cpp, vslam/image_input.hpp add_frame).
class VisualSession {
 public:
  VisualSession(const io::CameraCalibration& camera, io::SequenceKind kind, vslam::VisualSlamOptions options)
      : camera_(camera), kind_(kind), options_(std::move(options)), slam_(camera_, kind_, options_) {}

  /// `second`: the right image (stereo), the depth image (RGB-D) or empty (monocular).
  vslam::FrameResult add(double time_s, const cv::Mat& image, const cv::Mat& second) {
    const core::Timestamp time = timestamp_of(time_s, "time");
    check_plausible(image);
    return locked(mutex_, [&] {
      vslam::FrameResult r = kind_ == io::SequenceKind::kStereo ? slam_.add_stereo(time, image, second)
                             : kind_ == io::SequenceKind::kRgbd ? slam_.add_rgbd(time, image, second)
                                                                : slam_.add_monocular(time, image);
      times_.push_back(time_s);
      return r;
    });
  }

  vslam::FrameResult add_frame(const py::array& image, double time_s, const py::object& depth) {
    if (kind_ == io::SequenceKind::kStereo) throw_value_error("a stereo VisualSlam takes add_frame(left, right, time)");
    if (kind_ == io::SequenceKind::kRgbd && depth.is_none()) throw_value_error("depth: an RGB-D VisualSlam needs the depth image");
    if (kind_ == io::SequenceKind::kMonocular && !depth.is_none()) throw_value_error("depth: a monocular VisualSlam takes no depth");
    const ImageView gray = gray_view(image, "image");
    const ImageView second = depth.is_none() ? ImageView{} : depth_view(depth.cast<py::array>(), camera_.depth_units_per_m);
    return add(time_s, gray.mat, second.mat);
  }

  vslam::FrameResult add_stereo(const py::array& left, const py::array& right, double time_s) {
    if (kind_ != io::SequenceKind::kStereo) throw_value_error("add_frame(left, right, time) needs a stereo VisualSlam");
    const ImageView l = gray_view(left, "left");
    const ImageView r = gray_view(right, "right");
    return add(time_s, l.mat, r.mat);
  }

  py::array_t<double> trajectory() { return poses_to_array(locked(mutex_, [&] { return slam_.trajectory(); })); }
  py::array_t<double> times() { return vector_to_array(locked(mutex_, [&] { return times_; })); }
  py::array_t<double> keyframe_poses() { return poses_to_array(locked(mutex_, [&] { return slam_.keyframe_poses(); })); }
  py::array_t<std::int64_t> keyframe_frames() { return indices_to_array(locked(mutex_, [&] { return slam_.keyframe_frames(); })); }
  std::vector<int> frame_segments() { return locked(mutex_, [&] { return slam_.frame_segments(); }); }
  int main_segment() { return locked(mutex_, [&] { return slam_.main_segment(); }); }
  py::array_t<double> map_points() { return points_to_array(locked(mutex_, [&] { return slam_.map_points(); })); }
  py::object summary() { return json_to_python(locked(mutex_, [&] { return vslam_summary_json(slam_.summary()); })); }
  py::object config() const { return json_to_python(vslam::configuration().json(options_)); }
  const io::CameraCalibration& calibration() const { return camera_; }
  std::string kind() const { return std::string(io::to_string(kind_)); }

 private:
  /// As `cairn vslam` before any work (vslam::check_calibration_plausible): a calibration no real
  /// camera has would be tracked "ok" while measuring nothing. At the first frame, for its size
  /// unless the calibration gives one.
  void check_plausible(const cv::Mat& image) {
    if (checked_) return;
    const int width = camera_.width > 0 ? camera_.width : image.cols;
    const int height = camera_.height > 0 ? camera_.height : image.rows;
    const std::string implausible = camera_.implausibilities(width, height, kind_ == io::SequenceKind::kStereo);
    if (!implausible.empty()) throw_value_error("implausible calibration: " + implausible);
    checked_ = true;
  }

  io::CameraCalibration camera_;
  io::SequenceKind kind_;
  vslam::VisualSlamOptions options_;
  vslam::VisualSlam slam_;
  std::vector<double> times_;
  bool checked_ = false;
  std::mutex mutex_;
};

/// A dataset folder as `cairn vslam FOLDER` reads it (cli/vslam_input.cpp read_sequence). EuRoC
/// pairs need rectifying (vision::StereoRectifier), which these bindings do not do.
io::ImageSequence read_image_sequence(const py::object& folder) {
  const std::string path = fspath(folder);
  const py::gil_scoped_release release;
  const std::string layout = io::detect_image_layout(path);
  if (layout == "euroc") {
    throw std::invalid_argument(path + ": EuRoC's stereo pairs are not rectified, and the Python bindings do not rectify: use cairn vslam");
  }
  return layout == "kitti" ? io::read_kitti_stereo(path) : layout == "folder" ? io::read_image_folder(path) : io::read_tum_rgbd(path);
}

std::vector<std::string> frame_files(const io::ImageSequence& sequence, std::string io::ImageFrame::*file) {
  std::vector<std::string> files;
  for (const io::ImageFrame& frame : sequence.frames) files.push_back(frame.*file);
  return files;
}

// ---------------------------------------------------------------------------------------------
// The Python classes

py::dict stage_times(double preprocess_s, double register_s, double map_s, double total_s) {
  py::dict d;
  d["preprocess_s"] = preprocess_s;
  d["register_s"] = register_s;
  d["map_s"] = map_s;
  d["total_s"] = total_s;
  return d;
}

void bind_lidar_result(py::module_& m) {
  using R = lidar3d::SlamScanResult;
  py::class_<R>(m, "LidarScanResult", "What LidarSlam.add_scan says about one scan (lidar3d::SlamScanResult).")
      .def_property_readonly("time", [](const R& r) { return r.odometry.time_s; }, "The scan's time, seconds.")
      .def_property_readonly("health", [](const R& r) { return health_word(r.odometry.health); },
                             "'ok', 'degraded' (a degenerate direction, few correspondences) or 'lost' (a new map segment starts).")
      .def_property_readonly("pose", [](const R& r) { return matrix_to_array(r.odometry.T_world_sensor.matrix()); },
                             "T_world_scan (4 x 4) at the scan's time, as the odometry placed it (before later loop closures).")
      .def_readonly("keyframe", &R::keyframe, "Whether the scan became a keyframe.")
      .def_property_readonly("degenerate_axis", [](const R& r) { return r.odometry.degenerate_axis; },
                             "The sensor axis the registration could not constrain, or ''.")
      .def_property_readonly("segment", [](const R& r) { return r.odometry.segment; }, "Map segment (one more after each lost scan).")
      .def_property_readonly("points_read", [](const R& r) { return r.odometry.points_read; })
      .def_property_readonly("points_in_range", [](const R& r) { return r.odometry.points_in_range; })
      .def_property_readonly("correspondences", [](const R& r) { return r.odometry.registration.correspondences; })
      .def_property_readonly("rms_m", [](const R& r) { return r.odometry.registration.rms_m; }, "RMS of the correspondences, metres.")
      .def_property_readonly("converged", [](const R& r) { return r.odometry.registration.converged; })
      .def_property_readonly("iterations", [](const R& r) { return r.odometry.registration.iterations; })
      .def_property_readonly("threshold_sigma_m", [](const R& r) { return r.odometry.threshold_sigma_m; },
                             "Adaptive correspondence threshold sigma used (KISS-ICP eq. 3-4).")
      .def_property_readonly("point_times_unusable", [](const R& r) { return r.odometry.point_times_unusable; },
                             "The per-point times were not offsets within one sweep: the scan was not deskewed.")
      .def_property_readonly("local_map_points", [](const R& r) { return r.odometry.local_map_points; })
      .def_property_readonly("timings", [](const R& r) {
            const lidar3d::OdometryStageTimes& t = r.odometry.times;
            return stage_times(t.preprocess_s, t.register_s, t.map_s, t.total_s);
          }, "Seconds per odometry stage: preprocess_s, register_s, map_s, total_s.")
      .def("__repr__", [](const R& r) {
        return "LidarScanResult(time=" + std::to_string(r.odometry.time_s) + ", health='" + health_word(r.odometry.health) +
               "', keyframe=" + (r.keyframe ? "True" : "False") + ", segment=" + std::to_string(r.odometry.segment) + ")";
      });
}

void bind_lidar_slam(py::module_& m) {
  py::class_<LidarSession>(m, "LidarSlam",
                           "3D LiDAR SLAM (lidar3d::LidarSlam with the run record SlamRun, as `cairn slam3d` holds them): "
                           "odometry after KISS-ICP, Scan Context loop candidates verified by ICP, a pose graph with GNC.")
      .def(py::init([](const py::object& config, const py::object& set, const std::string& preset, double map_voxel_m) {
             if (!(map_voxel_m > 0.0) || !std::isfinite(map_voxel_m)) throw_value_error("map_voxel_m: expected a finite value > 0");
             return std::make_unique<LidarSession>(lidar_configuration(preset, config, set), preset, map_voxel_m);
           }),
           py::arg("config") = py::none(), py::arg("set") = py::none(), py::kw_only(), py::arg("preset") = "default",
           py::arg("map_voxel_m") = 0.25,
           "The options as `cairn slam3d --preset PRESET --config CONFIG --set key=value ...` makes them ('default' or "
           "'kitti'; keys as `cairn slam3d --print-config` lists them); map_voxel_m as --map-voxel.")
      .def("add_scan", &LidarSession::add_scan, py::arg("cloud"), py::arg("time"),
           "One scan (a cairn.PointCloud, e.g. from cairn.read_point_cloud) taken at `time` (seconds, strictly increasing). "
           "Releases the GIL.")
      .def("add_scan",
           [](LidarSession& s, const FloatArray& points, double time, const py::object& point_times, const py::object& intensity,
              const py::object& ring) { return s.add_scan(cloud_from_arrays(points, point_times, intensity, ring), time); },
           py::arg("points"), py::arg("time"), py::arg("point_times") = py::none(), py::arg("intensity") = py::none(),
           py::arg("ring") = py::none(),
           "One scan from arrays: points N x 3 (sensor frame, metres, finite), optional per-point times (seconds from the "
           "sweep's start), intensities and rings (N each).")
      .def("finish", &LidarSession::finish,
           "The final GNC over the loop closures, then the global map at the final poses. Call once after the last scan.")
      .def("trajectory", &LidarSession::trajectory, "T_world_scan of every scan so far (N x 4 x 4), after the latest solve.")
      .def("times", &LidarSession::times, "Every scan's time, seconds (N).")
      .def("health", &LidarSession::health, "Every scan's health: 'ok', 'degraded' or 'lost'.")
      .def("keyframe_poses", &LidarSession::keyframe_poses, "The keyframes' poses at their registration instant (K x 4 x 4).")
      .def("keyframe_scans", &LidarSession::keyframe_scans, "The index (in add_scan order) of each keyframe's scan (K).")
      .def("map_points", &LidarSession::map_points,
           "The global map after finish(), M x 3 float32, one point per voxel of map_voxel_m: what `cairn slam3d` writes as map.ply.")
      .def_property_readonly("summary", &LidarSession::summary, "Health counts, map segments and loop closure, as a dict.")
      .def("report", &LidarSession::report, "report.json of `cairn slam3d` for the scans so far, as a dict.")
      .def("config", &LidarSession::config, "The options in effect, {section: {key: value}} (report.json's \"options\").")
      .def_property_readonly("front_end", &LidarSession::front_end, "'dense' or 'loam' (what 'auto' chose), 'auto' before the first scan.")
      .def_property_readonly("finished", &LidarSession::finished)
      .def_property_readonly("map_voxel_m", &LidarSession::map_voxel_m)
      .def("__len__", &LidarSession::scans, "Scans added.");
}

void bind_scan_sequence(py::module_& m) {
  py::class_<lidar3d::ScanSequence>(m, "ScanSequence", "Scan files and their times, in the order `cairn slam3d` reads them.")
      .def_readonly("files", &lidar3d::ScanSequence::files)
      .def_property_readonly("times", [](const lidar3d::ScanSequence& s) { return vector_to_array(s.times_s); }, "Seconds, one per file.")
      .def_readonly("times_from_file", &lidar3d::ScanSequence::times_from_file, "False: made up, 0.1 s apart.")
      .def("__len__", [](const lidar3d::ScanSequence& s) { return s.files.size(); })
      .def("__iter__", [](const lidar3d::ScanSequence& s) {
        return py::iter(py::module_::import("builtins").attr("zip")(py::cast(s.files), py::cast(s.times_s)));
      }, "(file, time) pairs.");
  m.def("scan_sequence", &scan_sequence, py::arg("scans"), py::arg("times") = py::none(), py::arg("times_column") = 1,
        py::arg("max_scans") = 0,
        "The scans of a folder (.pcd/.ply/.bin, optionally compressed, natural name order) or a list of files, with their "
        "times from a table (column times_column, 1-based) or 0.1 s apart: what `cairn slam3d SCANS --times TIMES "
        "--times-column C --max-scans N` feeds. Each file read with cairn.read_point_cloud and given to LidarSlam.add_scan "
        "with its time reproduces that run.");
}

void bind_laser_scan(py::module_& m) {
  using S = io::LaserScan;
  py::class_<S>(m, "LaserScan", "One 2D laser record (io::LaserScan): ranges over beams at angle_min + k angle_increment.")
      .def(py::init(&laser_scan), py::arg("ranges"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("time"),
           py::arg("odometry") = py::none(), py::arg("max_range") = py::none(),
           "ranges in metres (inf/NaN: no return, with max_range); angles in radians; time in seconds; odometry the laser's "
           "pose (x, y, theta) in the odometry frame (None: no motion); max_range: readings at or beyond are no-returns.")
      .def_readonly("tag", &S::tag, "FLASER, RLASER, ROBOTLASER1, or 'python'.")
      .def_property_readonly("time", [](const S& s) { return s.time.seconds(); }, "Seconds.")
      .def_property_readonly("time_ns", [](const S& s) { return s.time.nanoseconds(); }, "The exact stamp, nanoseconds.")
      .def_property_readonly("ranges", [](const S& s) {
            py::array_t<float> out(static_cast<py::ssize_t>(s.ranges_m.size()));
            if (!s.ranges_m.empty()) std::memcpy(out.mutable_data(), s.ranges_m.data(), s.ranges_m.size() * sizeof(float));
            return out;
          }, "Metres (float32).")
      .def_property_readonly("angle_min", [](const S& s) { return s.geometry.start_angle_rad; })
      .def_property_readonly("angle_increment", [](const S& s) { return s.geometry.angular_resolution_rad; })
      .def_property_readonly("max_range", [](const S& s) { return optional_range(s.geometry.max_range_m); })
      .def_property_readonly("odometry", [](const S& s) { return pose2_to_array(s.T_odom_laser); }, "The laser's (x, y, theta) in the odometry frame.")
      .def_property_readonly("robot_odometry", [](const S& s) { return pose2_to_array(s.T_odom_robot); })
      .def_readonly("line", &S::line, "Line in the log (0: not from a file).")
      .def("__len__", [](const S& s) { return s.ranges_m.size(); });
  m.def("read_carmen_log", &read_carmen_scans, py::arg("path"), py::arg("lenient") = false, py::arg("max_scans") = 0,
        "The laser records of a CARMEN log (.clf/.log, also .gz/.bz2) in file order, as `cairn slam2d LOG [--lenient] "
        "[--max-scans N]` feeds them. Raises cairn.ParseError for a malformed record (lenient: skipped).");
}

void bind_slam2d_results(py::module_& m) {
  using R = slam2d::ScanResult;
  py::class_<R>(m, "Slam2dScanResult", "What Slam2d.add_scan says about one scan (slam2d::ScanResult).")
      .def_property_readonly("time", [](const R& r) { return r.time.seconds(); }, "Seconds.")
      .def_property_readonly("time_ns", [](const R& r) { return r.time.nanoseconds(); })
      .def_property_readonly("pose", [](const R& r) { return pose2_to_array(r.T_world_laser); },
                             "(x, y, theta) of the laser in the world, at the time of the call.")
      .def_property_readonly("health", [](const R& r) { return health_word(r.health); }, "'ok', 'degraded' or 'lost'.")
      .def_readonly("inlier_fraction", &R::inlier_fraction, "Of the local match.")
      .def_readonly("degeneracy", &R::degeneracy, "Of the local match (icp.hpp): small when a direction is unconstrained.")
      .def_property_readonly("covariance", [](const R& r) {
            py::array_t<double> out({py::ssize_t{3}, py::ssize_t{3}});
            auto view = out.mutable_unchecked<2>();
            for (py::ssize_t i = 0; i < 3; ++i) {
              for (py::ssize_t j = 0; j < 3; ++j) view(i, j) = r.covariance(i, j);
            }
            return out;
          }, "Of the local match, (x, y, theta), 3 x 3.")
      .def_readonly("keyframe", &R::keyframe)
      .def_readonly("segment", &R::segment, "Map segment.")
      .def("__repr__", [](const R& r) {
        return "Slam2dScanResult(time=" + r.time.to_seconds_string() + ", health='" + health_word(r.health) +
               "', keyframe=" + (r.keyframe ? "True" : "False") + ", segment=" + std::to_string(r.segment) + ")";
      });
  py::class_<OccupancyGrid>(m, "OccupancyGrid", "The observed part of a probability grid (slam2d::ProbabilityGrid).")
      .def_readonly("probability", &OccupancyGrid::probability,
                    "Occupancy probability, rows from the lowest y up (row j, column i: the cell at origin + (i, j) * "
                    "resolution); NaN where unobserved. map.pgm calls >= 0.65 occupied and <= 0.196 free.")
      .def_property_readonly("origin", [](const OccupancyGrid& g) { return py::make_tuple(g.origin_x_m, g.origin_y_m); },
                             "(x, y) of the lower-left corner of cell [0, 0], metres.")
      .def_readonly("resolution_m", &OccupancyGrid::resolution_m, "Cell side, metres.");
}

void bind_slam2d(py::module_& m) {
  bind_slam2d_results(m);
  py::class_<Slam2dSession>(m, "Slam2d",
                            "2D LiDAR SLAM (slam2d::Slam2d): point-to-line ICP against a local map, submaps, branch-and-bound "
                            "loop closure, a pose graph with GNC, map segments when lost.")
      .def(py::init([](const py::object& config, const py::object& set, const std::string& preset) {
             return std::make_unique<Slam2dSession>(slam2d_configuration(preset, config, set));
           }),
           py::arg("config") = py::none(), py::arg("set") = py::none(), py::kw_only(), py::arg("preset") = "default",
           "The options as `cairn slam2d --preset PRESET --config CONFIG --set key=value ...` makes them.")
      .def("add_scan", &Slam2dSession::add_scan, py::arg("scan"),
           "One cairn.LaserScan (e.g. from cairn.read_carmen_log). Releases the GIL.")
      .def("add_scan",
           [](Slam2dSession& s, const FloatArray& ranges, double angle_min, double angle_increment, double time,
              const py::object& odometry, std::optional<double> max_range) {
             return s.add_scan(laser_scan(ranges, angle_min, angle_increment, time, odometry, max_range));
           },
           py::arg("ranges"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("time"), py::arg("odometry") = py::none(),
           py::arg("max_range") = py::none(), "One scan from arrays (as cairn.LaserScan takes them).")
      .def("finish", &Slam2dSession::finish, "The final optimisation (GNC over the loop closures). Further scans may follow.")
      .def("trajectory", &Slam2dSession::trajectory, "(x, y, theta) of every scan in input order, N x 3, current estimate.")
      .def("times", &Slam2dSession::times, "Every scan's time, seconds (N).")
      .def("health", &Slam2dSession::health, "Every scan's health: 'ok', 'degraded' or 'lost'.")
      .def_property_readonly("current_health", &Slam2dSession::current_health, "The state now.")
      .def("occupancy_grid", &Slam2dSession::occupancy_grid, py::arg("resolution_m") = py::none(),
           "The map of every keyframe at its current pose (default resolution: output.map_resolution_m, as map.pgm).")
      .def_property_readonly("summary", &Slam2dSession::summary, "report.json's \"summary\" of `cairn slam2d`, as a dict.")
      .def("report", &Slam2dSession::report, "Summary, options, loop candidates and health events, as a dict.")
      .def("config", &Slam2dSession::config, "The options in effect, {section: {key: value}}.");
}

void bind_calibration(py::module_& m) {
  using C = io::CameraCalibration;
  py::class_<C>(m, "CameraCalibration", "A pinhole camera with Brown-Conrady distortion (io::CameraCalibration).")
      .def(py::init([](double fx, double fy, double cx, double cy, double k1, double k2, double p1, double p2, double k3, int width,
                       int height, double baseline_m, double depth_units_per_m, double virtual_baseline_m) {
             return C{fx, fy, cx, cy, k1, k2, p1, p2, k3, width, height, baseline_m, depth_units_per_m, virtual_baseline_m};
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::kw_only(), py::arg("k1") = 0.0, py::arg("k2") = 0.0,
           py::arg("p1") = 0.0, py::arg("p2") = 0.0, py::arg("k3") = 0.0, py::arg("width") = 0, py::arg("height") = 0,
           py::arg("baseline_m") = 0.0, py::arg("depth_units_per_m") = 0.0, py::arg("virtual_baseline_m") = 0.0)
      .def_readwrite("fx", &C::fx).def_readwrite("fy", &C::fy).def_readwrite("cx", &C::cx).def_readwrite("cy", &C::cy)
      .def_readwrite("k1", &C::k1).def_readwrite("k2", &C::k2).def_readwrite("p1", &C::p1).def_readwrite("p2", &C::p2)
      .def_readwrite("k3", &C::k3)
      .def_readwrite("width", &C::width, "Pixels; 0: from the first image.").def_readwrite("height", &C::height)
      .def_readwrite("baseline_m", &C::baseline_m, "Stereo: between the rectified cameras, metres.")
      .def_readwrite("depth_units_per_m", &C::depth_units_per_m, "RGB-D: depth units per metre (TUM: 5000).")
      .def_readwrite("virtual_baseline_m", &C::virtual_baseline_m, "RGB-D: ORB-SLAM's bf / fx.")
      .def("problems", [](const C& c) { std::string why; c.is_valid(&why); return why; }, "'' when usable, else every problem.")
      .def("implausibilities", &C::implausibilities, py::arg("width"), py::arg("height"), py::arg("stereo"),
           "'' when plausible for a real camera taking width x height images.")
      .def("__repr__", [](const C& c) {
        return "CameraCalibration(fx=" + std::to_string(c.fx) + ", fy=" + std::to_string(c.fy) + ", cx=" + std::to_string(c.cx) +
               ", cy=" + std::to_string(c.cy) + ", baseline_m=" + std::to_string(c.baseline_m) + ")";
      });
  m.def("read_calibration_yaml", [](const py::object& path) { return io::read_calibration_yaml(fspath(path)); }, py::arg("path"),
        "A calibration YAML as `cairn vslam --calib` reads it (fx, fy, cx, cy; k1..k3, p1, p2, width, height, baseline_m, ...).");
  m.def("read_kitti_calibration", [](const py::object& path) { return io::read_kitti_calibration(fspath(path)); }, py::arg("path"),
        "KITTI odometry's calib.txt (P0, P1): fx, fy, cx, cy and the baseline.");
  m.def("tum_calibration", &io::tum_calibration_preset, py::arg("name"),
        "The published calibration of a TUM RGB-D Kinect: 'tum-fr1', 'tum-fr2' or 'tum-fr3' (`cairn vslam --camera`).");
}

void bind_image_input(py::module_& m) {
  using Q = io::ImageSequence;
  py::class_<Q>(m, "ImageSequence", "An image dataset on disk (io::ImageSequence): KITTI stereo, TUM RGB-D or a plain folder.")
      .def_property_readonly("kind", [](const Q& q) { return std::string(io::to_string(q.kind)); }, "'stereo', 'rgbd' or 'monocular'.")
      .def_readonly("layout", &Q::layout, "'kitti', 'tum' or 'folder'.")
      .def_readonly("folder", &Q::folder)
      .def_readonly("calibration", &Q::calibration, "The dataset's (KITTI); zero where the dataset ships none (give one).")
      .def_readonly("calibration_from_dataset", &Q::calibration_from_dataset)
      .def_property_readonly("times", [](const Q& q) {
            std::vector<double> seconds;
            for (const io::ImageFrame& f : q.frames) seconds.push_back(f.time.seconds());
            return vector_to_array(seconds);
          }, "Seconds, one per frame.")
      .def_property_readonly("images", [](const Q& q) { return frame_files(q, &io::ImageFrame::image); }, "Left, colour or only image files.")
      .def_property_readonly("right_images", [](const Q& q) { return frame_files(q, &io::ImageFrame::right_image); })
      .def_property_readonly("depth_images", [](const Q& q) { return frame_files(q, &io::ImageFrame::depth_image); })
      .def_readonly("ground_truth_path", &Q::ground_truth_path)
      .def_readonly("notes", &Q::notes, "How the folder was read (assumed times, skipped lines).")
      .def("__len__", [](const Q& q) { return q.frames.size(); });
  m.def("read_image_sequence", &read_image_sequence, py::arg("folder"),
        "A KITTI odometry, TUM RGB-D or plain image folder as `cairn vslam FOLDER` reads it (EuRoC: not here).");
  m.def("read_gray_image", [](const py::object& path) {
          const std::string file = fspath(path);
          return mat_to_array<std::uint8_t>([&] { const py::gil_scoped_release release; return vision::read_gray_image(file); }());
        }, py::arg("path"), "A PNG or JPEG as the 8-bit grey image `cairn vslam` makes of it (H x W uint8).");
  m.def("read_depth_image", [](const py::object& path) {
          const std::string file = fspath(path);
          return mat_to_array<std::uint16_t>([&] { const py::gil_scoped_release release; return vision::read_depth_image(file); }());
        }, py::arg("path"), "A 16-bit depth PNG as `cairn vslam` reads it (H x W uint16, the file's units; 0: no depth).");
}

void bind_vslam_result(py::module_& m) {
  using R = vslam::FrameResult;
  py::class_<R>(m, "VisualFrameResult", "What VisualSlam.add_frame says about one frame (vslam::FrameResult).")
      .def_readonly("frame", &R::frame, "Index in add_frame order.")
      .def_property_readonly("time", [](const R& r) { return r.time.seconds(); }, "Seconds.")
      .def_readonly("tracked", &R::tracked, "False: the pose is the motion model's guess.")
      .def_property_readonly("health", [](const R& r) { return health_word(r.health); }, "'ok', 'degraded' or 'lost'.")
      .def_property_readonly("pose", [](const R& r) { return matrix_to_array(r.T_world_camera.matrix()); },
                             "T_world_camera (4 x 4) when tracked; world = the first camera (x right, y down, z forward).")
      .def_readonly("features", &R::features)
      .def_readonly("stereo_points", &R::stereo_points, "Keypoints with a stereo match or depth.")
      .def_readonly("inliers", &R::inliers, "Map-point matches after the local map's pose optimisation.")
      .def_readonly("inlier_ratio", &R::inlier_ratio)
      .def_readonly("keyframe", &R::keyframe)
      .def_readonly("relocalised", &R::relocalised)
      .def_readonly("loop_closed", &R::loop_closed)
      .def_readonly("new_map", &R::new_map, "This frame started a new map segment.")
      .def_readonly("segment", &R::segment)
      .def_readonly("sigma_position_m", &R::sigma_position_m)
      .def_readonly("note", &R::note, "Why lost or degraded.")
      .def_property_readonly("keypoints", [](const R& r) {
            py::array_t<float> out({static_cast<py::ssize_t>(r.keypoints.size()), py::ssize_t{2}});
            auto view = out.mutable_unchecked<2>();
            for (std::size_t k = 0; k < r.keypoints.size(); ++k) {
              view(static_cast<py::ssize_t>(k), 0) = r.keypoints[k].pt.x;
              view(static_cast<py::ssize_t>(k), 1) = r.keypoints[k].pt.y;
            }
            return out;
          }, "Keypoint positions (K x 2, pixels).")
      .def_property_readonly("keypoint_states", [](const R& r) {
            py::array_t<std::int8_t> out(static_cast<py::ssize_t>(r.keypoint_states.size()));
            if (!r.keypoint_states.empty()) std::memcpy(out.mutable_data(), r.keypoint_states.data(), r.keypoint_states.size());
            return out;
          }, "Per keypoint: 0 unmatched, 1 stereo/depth point only, 2 matched to a map point.")
      .def_property_readonly("timings", [](const R& r) {
            py::dict d;
            d["features_s"] = r.times.features_s;
            d["stereo_s"] = r.times.stereo_s;
            d["tracking_s"] = r.times.tracking_s;
            d["mapping_s"] = r.times.mapping_s;
            d["total_s"] = r.times.total_s;
            return d;
          }, "Seconds per stage.")
      .def("__repr__", [](const R& r) {
        return "VisualFrameResult(frame=" + std::to_string(r.frame) + ", health='" + health_word(r.health) +
               "', inliers=" + std::to_string(r.inliers) + ", keyframe=" + (r.keyframe ? "True" : "False") + ")";
      });
}

void bind_visual_slam(py::module_& m) {
  bind_vslam_result(m);
  py::class_<VisualSession>(m, "VisualSlam",
                            "Stereo, RGB-D or monocular visual SLAM after ORB-SLAM2 (vslam::VisualSlam), one frame at a time.")
      .def(py::init([](const io::CameraCalibration& calibration, const std::string& kind, const py::object& config,
                       const py::object& set, const std::string& dataset, const py::object& vocabulary) {
             const io::SequenceKind k = sequence_kind(kind);
             return std::make_unique<VisualSession>(calibration, k, vslam_configuration(dataset, k, config, set, vocabulary));
           }),
           py::arg("calibration"), py::arg("kind") = "stereo", py::arg("config") = py::none(), py::arg("set") = py::none(),
           py::kw_only(), py::arg("dataset") = "folder", py::arg("vocabulary") = py::none(),
           "calibration: a cairn.CameraCalibration (rectified stereo needs baseline_m; RGB-D depth_units_per_m and "
           "virtual_baseline_m); kind 'stereo', 'rgbd' or 'monocular'; the options as `cairn vslam` makes them from the "
           "dataset's layout ('kitti': 2000 features, others 1000), --config and --set; vocabulary: a bag-of-words file "
           "(loop closure, relocalisation).")
      .def("add_frame", &VisualSession::add_frame, py::arg("image"), py::arg("time"), py::arg("depth") = py::none(),
           "A grey image (H x W uint8, viewed without a copy) at `time` seconds; RGB-D: with its depth (uint16 in "
           "depth_units_per_m, or float metres). Releases the GIL.")
      .def("add_frame", &VisualSession::add_stereo, py::arg("left"), py::arg("right"), py::arg("time"),
           "A rectified stereo pair (H x W uint8 each).")
      .def("trajectory", &VisualSession::trajectory,
           "Every frame's T_world_camera (N x 4 x 4) through its reference keyframe's current pose (trajectory.kitti).")
      .def("times", &VisualSession::times, "Every frame's time, seconds (N).")
      .def("keyframe_poses", &VisualSession::keyframe_poses, "The keyframes in the map (K x 4 x 4).")
      .def("keyframe_frames", &VisualSession::keyframe_frames, "The frame index of each keyframe (K).")
      .def("frame_segments", &VisualSession::frame_segments, "Per frame, its map segment now (-1: before the first keyframe).")
      .def_property_readonly("main_segment", &VisualSession::main_segment)
      .def("map_points", &VisualSession::map_points, "The good map points in the world frame (M x 3 float64).")
      .def_property_readonly("summary", &VisualSession::summary, "Frame and keyframe counts, loops and their decisions, as a dict.")
      .def("config", &VisualSession::config, "The options in effect, {section: {key: value}}.")
      .def_property_readonly("calibration", &VisualSession::calibration)
      .def_property_readonly("kind", &VisualSession::kind);
}

}  // namespace

void bind_pipelines(py::module_& m) {
  bind_lidar_result(m);
  bind_lidar_slam(m);
  bind_scan_sequence(m);
  bind_laser_scan(m);
  bind_slam2d(m);
  bind_calibration(m);
  bind_image_input(m);
  bind_visual_slam(m);
}

}  // namespace cairn::python
