// Slam2d in Python (bindings.hpp): fed one laser scan at a time, as `cairn slam2d` feeds it, and
// the reader that gives exactly what that command feeds (read_carmen_log). The GIL is released
// while it works; each Slam2d serialises its own calls (pipeline_support.hpp locked), so Python
// threads may share one.

#include <pybind11/stl.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/config.hpp"
#include "cairn/slam2d/outputs.hpp"
#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/slam2d/slam.hpp"
#include "pipeline_support.hpp"

namespace cairn::python {
namespace {

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
// The Python classes

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

void bind_slam2d_class(py::module_& m) {
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

}  // namespace

void bind_slam2d(py::module_& m) {
  bind_laser_scan(m);
  bind_slam2d_class(m);
}

}  // namespace cairn::python
