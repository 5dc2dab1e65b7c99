// LidarSlam in Python (bindings.hpp): fed one scan at a time, as `cairn slam3d` feeds it, and the
// reader that gives exactly what that command feeds (scan_sequence). The GIL is released while it
// works; each LidarSlam serialises its own calls (pipeline_support.hpp locked), so Python threads
// may share one.

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/config.hpp"
#include "cairn/lidar3d/inertial_input.hpp"
#include "cairn/lidar3d/inertial_outputs.hpp"
#include "cairn/lidar3d/lidar_inertial_slam.hpp"
#include "cairn/lidar3d/localization.hpp"
#include "cairn/lidar3d/localization_outputs.hpp"
#include "cairn/lidar3d/map_file.hpp"
#include "cairn/lidar3d/odometry.hpp"
#include "cairn/lidar3d/pairwise_registration.hpp"
#include "cairn/lidar3d/report.hpp"
#include "cairn/lidar3d/saved_map.hpp"
#include "cairn/lidar3d/scan_sequence.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"
#include "pipeline_support.hpp"

namespace cairn::python {
namespace {

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
  /// `imu`: the IMU as `cairn slam3d --imu ...` reads it (inertial_input.hpp), or none.
  LidarSession(lidar3d::SlamConfiguration options, std::string preset, double map_voxel_m,
               const std::optional<lidar3d::InertialInputRequest>& imu, bool remap_forced)
      : options_(std::move(options)),
        preset_(std::move(preset)),
        slam_(options_.slam),
        run_(options_.slam.odometry, map_voxel_m) {
    sequence_.times_from_file = true;  // the caller gives every time
    remap_forced_ = remap_forced;
    if (imu) start_inertial(*imu);
  }

  lidar3d::SlamScanResult add_scan(const io::PointCloud& cloud, double time_s) {
    finite_or_throw(time_s, "time");
    return locked(mutex_, [&] {
      if (finished_) throw std::runtime_error("LidarSlam.finish() was called: no scan may follow it");
      lidar3d::SlamScanResult result = slam_scan(cloud, time_s);
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
      if (inertial_run_) inertial_run_->finish(inertial_->fusion());
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

  /// The finished map as `cairn slam3d --save-map PATH` writes it.
  void save_map(const std::string& path) {
    locked(mutex_, [&] {
      if (!finished_) throw std::runtime_error("LidarSlam.save_map(): the map is made by finish()");
      const lidar3d::SavedMap3D map =
          lidar3d::make_saved_map(slam_, run_, lidar3d::configuration().json(options_).dump(), "cairn.LidarSlam (Python)");
      lidar3d::write_saved_map(path, map);
    });
  }

  std::size_t scans() { return locked(mutex_, [&] { return sequence_.files.size(); }); }
  bool finished() { return locked(mutex_, [&] { return finished_; }); }
  std::string front_end() { return locked(mutex_, [&] { return std::string(lidar3d::to_string(slam_.front_end())); }); }
  double map_voxel_m() const { return run_.map_voxel_m(); }
  bool has_imu() const { return inertial_run_ != nullptr; }

 private:
  /// The IMU read and its samples given to the fusion before any scan, as the CLI does.
  void start_inertial(const lidar3d::InertialInputRequest& request) {
    lidar3d::InertialInput input = lidar3d::read_inertial_input(request);
    const lidar3d::InertialFusionOptions fusion = lidar3d::inertial_fusion_options(options_.imu, input);
    inertial_run_ = std::make_unique<lidar3d::InertialRun>(std::move(input), fusion, remap_forced_);
    inertial_.emplace(slam_, inertial_run_->options());
    for (const inertial::ImuSample& sample : inertial_run_->input().samples) inertial_->add_imu(sample);
  }

  lidar3d::SlamScanResult slam_scan(const io::PointCloud& cloud, double time_s) {
    if (!inertial_) return slam_.add_scan(cloud, time_s);
    lidar3d::LidarInertialScan scan = inertial_->add_scan(cloud, time_s);
    inertial_run_->add_scan(sequence_.files.size(), scan.inertial);
    return scan.slam;
  }

  lidar3d::SlamConfiguration options_;
  std::string preset_;
  lidar3d::LidarSlam slam_;
  lidar3d::SlamRun run_;
  lidar3d::ScanSequence sequence_;  ///< one label and time per scan added, for report()
  bool finished_ = false;
  core::Clock::time_point start_ = core::Clock::now();
  double wall_time_s_ = 0.0;
  std::mutex mutex_;
  bool remap_forced_ = false;
  std::unique_ptr<lidar3d::InertialRun> inertial_run_;
  std::optional<lidar3d::LidarInertialSlam> inertial_;  // after slam_, which it refers to
};

/// Localizer3d with its results, one call at a time (the localiser is not thread-safe).
class LocalizerSession {
 public:
  LocalizerSession(const std::string& map_path, const lidar3d::Localizer3dOptions& options)
      : localizer_(lidar3d::read_saved_map(map_path), options) {}

  py::dict add_scan(const io::PointCloud& cloud, double time_s) {
    finite_or_throw(time_s, "time");
    const lidar3d::Localization3dResult r = locked(mutex_, [&] {
      results_.push_back(localizer_.add_scan(cloud, time_s));
      return results_.back();
    });
    py::dict d;
    d["state"] = std::string(lidar3d::to_string(r.state));
    d["health"] = health_word(r.health);
    d["localised"] = r.localised;
    d["pose"] = r.localised ? py::object(matrix_to_array(r.T_map_sensor.matrix())) : py::object(py::none());
    d["relocalised"] = r.relocalised;
    d["dead_reckoning"] = r.dead_reckoning;
    d["fitness"] = r.fitness;
    d["inlier_rmse_m"] = r.inlier_rmse_m;
    d["degenerate_axis"] = r.degenerate_axis;
    d["reason"] = r.reason;
    d["total_s"] = r.total_s;
    return d;
  }

  py::object report() {
    return json_to_python(locked(mutex_, [&] { return lidar3d::localization_report_json(localizer_); }));
  }
  py::object trajectory() {
    const io::Trajectory t = locked(mutex_, [&] { return lidar3d::localized_trajectory(results_); });
    std::vector<double> times;
    for (const core::Timestamp& stamp : t.stamps) times.push_back(stamp.seconds());
    return py::make_tuple(poses_to_array(t.poses), vector_to_array(times));
  }
  std::size_t scans() { return locked(mutex_, [&] { return results_.size(); }); }

 private:
  lidar3d::Localizer3d localizer_;
  std::vector<lidar3d::Localization3dResult> results_;
  std::mutex mutex_;
};

void bind_localizer3d(py::module_& m) {
  py::class_<LocalizerSession>(m, "Localizer3d",
                               "Localisation in a map saved by `cairn slam3d --save-map` or LidarSlam.save_map "
                               "(lidar3d::Localizer3d, as `cairn localize3d` runs it); the map is never changed.")
      .def(py::init([](const py::object& map, int confirmations, int threads, bool odometry_while_tracking) {
             if (confirmations < 1) throw_value_error("confirmations: expected >= 1");
             if (threads < 0) throw_value_error("threads: expected >= 0 (0: all)");
             lidar3d::Localizer3dOptions options;
             options.confirmations = confirmations;
             options.threads = threads;
             options.odometry_while_tracking = odometry_while_tracking;
             const std::string path = fspath(map);
             const py::gil_scoped_release release;
             return std::make_unique<LocalizerSession>(path, options);
           }),
           py::arg("map"), py::kw_only(), py::arg("confirmations") = 2, py::arg("threads") = 0,
           py::arg("odometry_while_tracking") = false,
           "Reads the map (cairn.ParseError naming the file when it is damaged) and builds its search structures. "
           "odometry_while_tracking: an odometry step on every tracked scan, as `--odometry-while-tracking`.")
      .def("add_scan", &LocalizerSession::add_scan, py::arg("cloud"), py::arg("time"),
           "Localises one scan taken at `time` (seconds, strictly increasing): a dict with state, health, localised, "
           "pose (4 x 4 in the map frame, or None while searching), relocalised, dead_reckoning, fitness, inlier_rmse_m, "
           "degenerate_axis, reason and total_s. Releases the GIL.")
      .def("add_scan",
           [](LocalizerSession& s, const FloatArray& points, double time, const py::object& point_times,
              const py::object& intensity, const py::object& ring) {
             return s.add_scan(cloud_from_arrays(points, point_times, intensity, ring), time);
           },
           py::arg("points"), py::arg("time"), py::arg("point_times") = py::none(), py::arg("intensity") = py::none(),
           py::arg("ring") = py::none(), "One scan from arrays, as LidarSlam.add_scan takes them.")
      .def("report", &LocalizerSession::report,
           "report.json of `cairn localize3d` without its input fields: map, options, summary, relocalisations, attempts.")
      .def("trajectory", &LocalizerSession::trajectory,
           "The localised scans: (poses K x 4 x 4 in the map frame, times K), what trajectory.tum holds.")
      .def("__len__", &LocalizerSession::scans, "Scans added.");
}

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
  return lidar3d::open_scan_sequence(paths, times_path, times_column, "", static_cast<std::size_t>(max_scans));
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
      .def(py::init([](const py::object& config, const py::object& set, const std::string& preset, double map_voxel_m,
                       const std::optional<std::string>& imu, const std::string& imu_topic, const std::string& imu_calibration,
                       const std::string& lidar_extrinsic, double imu_time_offset) {
             if (!(map_voxel_m > 0.0) || !std::isfinite(map_voxel_m)) throw_value_error("map_voxel_m: expected a finite value > 0");
             lidar3d::SlamConfiguration options = lidar_configuration(preset, config, set);
             std::optional<lidar3d::InertialInputRequest> request;
             bool remap_forced = false;
             if (imu) {
               finite_or_throw(imu_time_offset, "imu_time_offset");
               // A topic names a sensor_msgs/Imu topic of the bag `imu` (InertialInputRequest's bag + topic).
               const bool topic = !imu_topic.empty();
               request = lidar3d::InertialInputRequest{{topic ? "" : *imu, topic ? *imu : "", imu_topic, imu_calibration, imu_time_offset},
                                                       lidar_extrinsic};
               remap_forced = lidar3d::prepare_for_inertial(options.slam);  // as slam3d_options does with --imu
             } else if (!imu_topic.empty() || !imu_calibration.empty() || !lidar_extrinsic.empty() || imu_time_offset != 0.0) {
               throw_value_error("imu_topic, imu_calibration, lidar_extrinsic and imu_time_offset go with imu=PATH");
             }
             py::gil_scoped_release release;  // reading the IMU can take a while
             return std::make_unique<LidarSession>(std::move(options), preset, map_voxel_m, request, remap_forced);
           }),
           py::arg("config") = py::none(), py::arg("set") = py::none(), py::kw_only(), py::arg("preset") = "default",
           py::arg("map_voxel_m") = 0.25, py::arg("imu") = py::none(), py::arg("imu_topic") = "",
           py::arg("imu_calibration") = "", py::arg("lidar_extrinsic") = "", py::arg("imu_time_offset") = 0.0,
           "The options as `cairn slam3d --preset PRESET --config CONFIG --set key=value ...` makes them ('default' or "
           "'kitti'; keys as `cairn slam3d --print-config` lists them); map_voxel_m as --map-voxel. With imu=PATH "
           "(EuRoC imu0 folder or data.csv, a plain IMU CSV, or a bag with imu_topic), LiDAR-inertial SLAM as "
           "`cairn slam3d --imu PATH [--imu-calibration] [--lidar-extrinsic] [--imu-time-offset]`.")
      .def_property_readonly("has_imu", &LidarSession::has_imu, "Whether an IMU is fused (imu=PATH).")
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
      .def("save_map", [](LidarSession& s, const py::object& path) { s.save_map(fspath(path)); }, py::arg("path"),
           "After finish(): the map for cairn.Localizer3d and `cairn localize3d --map`, as `cairn slam3d --save-map` writes it.")
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

/// `cairn register` as a call: the result as its --json dict.
py::object register_clouds(const io::PointCloud& source, const io::PointCloud& target,
                           const std::optional<DoubleArray>& guess, bool global, const std::string& method,
                           double max_distance_m) {
  lidar3d::PairwiseRegistrationOptions options;
  if (method != "gicp" && method != "icp") throw_value_error("method: expected 'gicp' or 'icp', found '" + method + "'");
  options.method = method == "icp" ? lidar3d::PairwiseMethod::kPointToPlane : lidar3d::PairwiseMethod::kGicp;
  options.max_correspondence_m = max_distance_m;
  if (std::string why; !options.is_valid(&why)) throw_value_error(why);
  if (global && guess) throw_value_error("global=True registers from nothing: give no guess");
  const core::SE3 T_guess = guess ? core::SE3::from_matrix(matrix4_from_array(*guess, "guess")) : core::SE3();
  lidar3d::PairwiseRegistrationResult result;
  {
    py::gil_scoped_release release;
    result = global ? lidar3d::register_pair_globally(source, target, options)
                    : lidar3d::register_pair(source, target, T_guess, options);
  }
  return json_to_python(lidar3d::pairwise_registration_json(result));
}

void bind_register(py::module_& m) {
  m.def("register", &register_clouds, py::arg("source"), py::arg("target"), py::arg("guess") = py::none(),
        py::kw_only(), py::arg("global_") = false, py::arg("method") = "gicp", py::arg("max_distance") = 1.0,
        "Registers source onto target as `cairn register` does (GICP, or method='icp' for point-to-plane; from the 4 x 4 "
        "guess T_target_source, identity without one, or from nothing with global_=True: Scan Context's yaws refined, "
        "refused when ambiguous). Returns its --json dict: T_target_source, fitness, inlier_rmse_m, degeneracy, "
        "covariance, accepted and refusal.");
}

}  // namespace

void bind_lidar3d(py::module_& m) {
  bind_lidar_result(m);
  bind_lidar_slam(m);
  bind_scan_sequence(m);
  bind_register(m);
  bind_localizer3d(m);
}

}  // namespace cairn::python
