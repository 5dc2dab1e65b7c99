// `cairn info FILE`: what a pose graph or trajectory file holds.

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cairn/bag/bag.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/graph_statistics.hpp"

namespace cairn::cli {
namespace {

struct InfoFlags {
  std::string path;
  std::string format;
  std::string times;
  std::string json;
  GraphReadFlags graph;
};

void emit_json(const std::string& destination, const nlohmann::json& j) {
  if (destination.empty()) return;
  io::write_output(destination, [&](std::ostream& out) { out << io::json_text(j); });
}

int info_graph(const InfoFlags& flags, io::FileFormat format) {
  io::GraphReadOptions options = flags.graph.options();
  options.format = format == io::FileFormat::kG2o ? io::GraphFormat::kG2o : io::GraphFormat::kToro;
  const io::GraphFile file = io::read_graph(flags.path, options);
  const io::GraphStatistics s = io::compute_statistics(file.graph);
  const io::GraphReadReport& r = file.report;

  const nlohmann::json j = io::graph_info_json(flags.path, s, r);

  if (!io::is_standard_output(flags.json)) {
    std::ostringstream o;
    o << "file              " << (flags.path == "-" ? "standard input" : flags.path) << '\n';
    o << "format            " << io::to_string(r.format) << ", " << s.dimension << "D pose graph\n";
    o << "poses             " << s.poses << "  (ids " << s.min_id << ".." << s.max_id
      << (s.contiguous_ids ? ", contiguous" : ", with gaps") << ")\n";
    o << "initial guess     "
      << (s.has_initial_guess ? "yes (" + std::to_string(s.vertices) + " VERTEX lines)"
                              : "no: no VERTEX lines, compute one (odometry or chordal)")
      << '\n';
    o << "edges             " << s.edges << '\n';
    for (const auto& [tag, count] : r.records) {
      if (tag.starts_with("EDGE")) o << "  " << std::left << std::setw(16) << tag << count.count << '\n';
    }
    o << "  odometry chain  " << s.odometry_edges << "  (consecutive ids)\n";
    o << "  loop closures   " << s.loop_closure_edges << '\n';
    if (s.duplicate_edges > 0) o << "  repeated pairs  " << s.duplicate_edges << '\n';
    o << "fixed poses       " << s.fixed << '\n';
    o << "components        " << s.connected_components;
    if (s.connected_components > 1) o << "  (largest " << s.largest_component << " poses: the gauge is not fixed by one pose)";
    o << '\n';
    if (s.isolated_vertices > 0) o << "isolated vertices " << s.isolated_vertices << '\n';
    o << "information       ";
    if (r.information_not_positive_definite == 0) {
      o << "all positive definite";
    } else {
      o << r.information_not_positive_definite << " not positive definite (first at line "
        << r.first_not_positive_definite_line << "): " << r.information_indefinite << " indefinite (policy "
        << io::to_string(r.information_policy) << "), " << r.information_singular << " singular";
    }
    if (!r.toro_information_order.empty()) o << "; EDGE2 read in " << r.toro_information_order << " order";
    o << '\n';
    if (!r.unknown_records.empty()) {
      o << "unknown records   ";
      for (const auto& [tag, count] : r.unknown_records) {
        o << tag << " x" << count.count << " (first at line " << count.first_line << ")  ";
      }
      o << '\n';
    }
    std::cout << o.str();
    for (const auto& w : r.warnings) warn(w);
  }
  emit_json(flags.json, j);
  return 0;
}

int info_trajectory(const InfoFlags& flags, io::FileFormat format) {
  io::TrajectoryReadReport report;
  const io::Trajectory trajectory = read_trajectory(flags.path, format, flags.times, &report);
  double length_m = 0.0;
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d high = -low;
  for (std::size_t i = 0; i < trajectory.poses.size(); ++i) {
    const Eigen::Vector3d& t = trajectory.poses[i].translation();
    low = low.cwiseMin(t);
    high = high.cwiseMax(t);
    if (i > 0) length_m += (t - trajectory.poses[i - 1].translation()).norm();
  }
  nlohmann::json j;
  j["file"] = flags.path;
  j["kind"] = "trajectory";
  j["format"] = io::to_string(format);
  j["poses"] = trajectory.poses.size();
  j["has_timestamps"] = trajectory.has_stamps();
  j["path_length_m"] = length_m;
  j["bounding_box_min_m"] = {low.x(), low.y(), low.z()};
  j["bounding_box_max_m"] = {high.x(), high.y(), high.z()};
  double duration_s = 0.0;
  double max_gap_s = 0.0;
  if (trajectory.has_stamps()) {
    const auto& stamps = trajectory.stamps;
    duration_s = static_cast<double>(stamps.back().nanoseconds() - stamps.front().nanoseconds()) * 1e-9;
    for (std::size_t i = 1; i < stamps.size(); ++i) {
      max_gap_s = std::max(max_gap_s, static_cast<double>(stamps[i].nanoseconds() - stamps[i - 1].nanoseconds()) * 1e-9);
    }
    j["first_timestamp_s"] = stamps.front().to_seconds_string();
    j["last_timestamp_s"] = stamps.back().to_seconds_string();
    j["duration_s"] = duration_s;
    j["largest_time_gap_s"] = max_gap_s;
  }
  j["quaternions_normalised"] = report.quaternions_normalised;
  j["max_rotation_orthonormality_error"] = report.max_rotation_orthonormality_error;
  j["warnings"] = report.warnings;

  if (!io::is_standard_output(flags.json)) {
    std::ostringstream o;
    o << std::fixed;
    o << "file              " << (flags.path == "-" ? "standard input" : flags.path) << '\n';
    o << "format            " << io::to_string(format) << " trajectory\n";
    o << "poses             " << trajectory.poses.size() << '\n';
    if (trajectory.has_stamps()) {
      o << std::setprecision(3);
      o << "time              " << trajectory.stamps.front().to_seconds_string() << " .. "
        << trajectory.stamps.back().to_seconds_string() << " s  (" << duration_s << " s";
      if (duration_s > 0.0) o << ", " << static_cast<double>(trajectory.poses.size() - 1) / duration_s << " Hz mean";
      o << ", largest gap " << max_gap_s << " s)\n";
    } else {
      o << "time              none (KITTI poses without a times file; pass --times)\n";
    }
    o << std::setprecision(3);
    o << "path length       " << length_m << " m\n";
    o << "bounding box      [" << low.x() << ", " << low.y() << ", " << low.z() << "] .. [" << high.x()
      << ", " << high.y() << ", " << high.z() << "] m\n";
    if (format == io::FileFormat::kKitti) {
      o << std::scientific << std::setprecision(2);
      o << "rotation blocks   max |R^T R - I| = " << report.max_rotation_orthonormality_error
        << " (projected onto SO(3))\n";
    }
    std::cout << o.str();
    for (const auto& w : report.warnings) warn(w);
  }
  emit_json(flags.json, j);
  return 0;
}

int info_carmen(const InfoFlags& flags) {
  io::CarmenReadReport report;
  const io::CarmenLog log = io::read_carmen_log(flags.path, &report);
  double path_m = 0.0;
  for (std::size_t k = 1; k < log.scans.size(); ++k) {
    path_m += (log.scans[k].T_odom_robot.translation() - log.scans[k - 1].T_odom_robot.translation()).norm();
  }
  std::map<std::size_t, std::size_t> beams;
  for (const auto& s : log.scans) ++beams[s.ranges_m.size()];
  nlohmann::json j;
  j["file"] = flags.path;
  j["kind"] = "sensor_log";
  j["format"] = "carmen";
  j["records"] = report.records;
  j["unknown_records"] = report.unknown_records;
  j["scans"] = log.scans.size();
  j["odometry_records"] = log.odometry.size();
  nlohmann::json beam_counts = nlohmann::json::object();
  for (const auto& [n, count] : beams) beam_counts[std::to_string(n)] = count;
  j["beams_per_scan"] = beam_counts;
  j["laser_geometry_source"] = report.flaser_geometry_source;
  j["laser_timestamps_backwards"] = report.laser_timestamps_backwards;
  j["odometry_path_length_m"] = path_m;
  if (!log.scans.empty()) {
    j["first_scan_time_s"] = log.scans.front().time.to_seconds_string();
    j["last_scan_time_s"] = log.scans.back().time.to_seconds_string();
  }
  j["warnings"] = report.warnings;
  if (!io::is_standard_output(flags.json)) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(3);
    o << "file              " << (flags.path == "-" ? "standard input" : flags.path) << '\n';
    o << "format            CARMEN log\n";
    o << "records          ";
    for (const auto& [tag, count] : report.records) o << ' ' << tag << ' ' << count;
    o << '\n';
    o << "beams per scan   ";
    for (const auto& [n, count] : beams) o << ' ' << n << " (x" << count << ")";
    o << "; geometry from " << report.flaser_geometry_source << '\n';
    if (!log.scans.empty()) {
      const double duration =
          static_cast<double>(log.scans.back().time.nanoseconds() - log.scans.front().time.nanoseconds()) * 1e-9;
      o << "scan times        " << log.scans.front().time.to_seconds_string() << " .. "
        << log.scans.back().time.to_seconds_string() << " s (" << duration << " s)\n";
    }
    o << "odometry path     " << path_m << " m (from the scans' odometry fields)\n";
    std::cout << o.str();
    for (const auto& w : report.warnings) warn(w);
  }
  emit_json(flags.json, j);
  return 0;
}

}  // namespace

Runner register_info(CLI::App& app) {
  auto flags = std::make_shared<InfoFlags>();
  app.add_option("FILE", flags->path, "Pose graph (.g2o, .graph), trajectory (TUM, KITTI, EuRoC .csv), CARMEN log (.clf, .log, also .gz/.bz2), or a bag: ROS 1 .bag, .mcap, rosbag2 .db3 or folder")
      ->required();
  app.add_option("--format", flags->format, "Override the format: g2o, toro, tum, kitti, euroc, carmen");
  app.add_option("--times", flags->times, "KITTI times file (one time in seconds per pose)");
  app.add_option("--json", flags->json, "Also write the facts as JSON to this file ('-' for stdout only)");
  flags->graph.add_to(app);
  return [flags]() {
    claim_standard_output(flags->json);
    if (flags->format.empty() && bag::is_bag(flags->path)) return info_bag(flags->path, flags->json);
    const io::FileFormat format = resolve_format(flags->path, flags->format, "--format");
    if (!flags->times.empty() && format != io::FileFormat::kKitti) {
      throw UsageError("--times goes with a KITTI trajectory, and " + flags->path + " is " + std::string(io::to_string(format)));
    }
    if (io::kind_of(format) == io::FileKind::kPoseGraph) return info_graph(*flags, format);
    if (io::kind_of(format) == io::FileKind::kSensorLog) return info_carmen(*flags);
    return info_trajectory(*flags, format);
  };
}

}  // namespace cairn::cli
