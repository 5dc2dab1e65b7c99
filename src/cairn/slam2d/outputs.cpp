#include "cairn/slam2d/map_picture.hpp"
#include "cairn/slam2d/outputs.hpp"

#include <cairo.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <memory>
#include <numeric>
#include <ostream>

#include "cairn/io/output_file.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/config.hpp"

namespace cairn::slam2d {
namespace {

namespace fs = std::filesystem;

core::SE3 to_se3(const core::SE2& T) {
  return core::SE3(core::SO3::from_rpy(0.0, 0.0, T.angle()), Eigen::Vector3d(T.x(), T.y(), 0.0));
}

// Occupancy class of a cell for the map files: 0 free, 1 occupied, 2 unknown.
int cell_class(const ProbabilityGrid& grid, int i, int j) {
  if (!grid.cell_known(i, j)) return 2;
  const double p = grid.cell_probability(i, j);
  if (p >= 0.65) return 1;
  if (p <= 0.196) return 0;
  return 2;
}

void append_float(std::string& out, float value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

// The observed part of the grid plus a margin of `margin` cells (the grid itself grows by
// doubling and is mostly unknown).
}  // namespace

io::Trajectory to_trajectory(const Slam2d& slam) {
  std::vector<ScanResult> scans = slam.trajectory();
  std::stable_sort(scans.begin(), scans.end(), [](const ScanResult& a, const ScanResult& b) { return a.time < b.time; });
  io::Trajectory trajectory;
  for (const ScanResult& s : scans) {
    if (!trajectory.stamps.empty() && !(trajectory.stamps.back() < s.time)) continue;
    trajectory.stamps.push_back(s.time);
    trajectory.poses.push_back(to_se3(s.T_world_laser));
  }
  return trajectory;
}

eval::MatrixTrajectory to_matrix_trajectory(const Slam2d& slam) { return eval::MatrixTrajectory(to_trajectory(slam)); }

void write_map_pgm(const ProbabilityGrid& grid, const std::string& pgm_path, const std::string& yaml_path) {
  const GridCrop crop = known_crop(grid, 10);
  const int width = crop.width, height = crop.height;
  io::write_output(pgm_path, [&](std::ostream& out) {
    out << "P5\n# cairn slam2d occupancy grid, resolution " << grid.resolution() << " m\n"
        << width << ' ' << height << "\n255\n";
    std::string row(static_cast<std::size_t>(width), '\0');
    for (int j = height - 1; j >= 0; --j) {  // first row = top = largest y
      for (int i = 0; i < width; ++i) {
        const int c = cell_class(grid, i + crop.i0, j + crop.j0);
        row[static_cast<std::size_t>(i)] = static_cast<char>(c == 0 ? 254 : c == 1 ? 0 : 205);
      }
      out.write(row.data(), static_cast<std::streamsize>(row.size()));
    }
  });
  io::write_output(yaml_path, [&](std::ostream& out) {
    std::string x, y, r;
    io::append_number(x, grid.origin().x() + crop.i0 * grid.resolution());
    io::append_number(y, grid.origin().y() + crop.j0 * grid.resolution());
    io::append_number(r, grid.resolution());
    out << "image: " << fs::path(pgm_path).filename().string() << "\nresolution: " << r << "\norigin: [" << x << ", " << y
        << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  });
}

SegmentMarks segment_marks(const Slam2d& slam, const std::vector<ScanResult>& trajectory) {
  SegmentMarks marks;
  const Slam2dSummary& s = slam.summary();
  if (s.segments.size() < 2) return marks;
  for (const SegmentInfo& segment : s.segments) {
    if (segment.first_scan >= trajectory.size()) continue;
    const bool merged = segment.merged_with != segment.id ||
                        std::any_of(s.segments.begin(), s.segments.end(), [&](const SegmentInfo& other) {
                          return other.id != segment.id && other.merged_with == segment.id;
                        });
    marks.starts.push_back({trajectory[segment.first_scan].T_world_laser.translation(),
                            "S" + std::to_string(segment.id) + (merged ? "" : " unmerged"), merged});
  }
  const io::PoseGraph2D graph = slam.pose_graph();
  for (const MergeEvent& merge : s.merges) {
    for (const int c : merge.candidates) {
      const LoopCandidate& candidate = s.candidates[static_cast<std::size_t>(c)];
      if (candidate.rejected_by_gnc) continue;
      marks.merges.emplace_back(graph.vertices[static_cast<std::size_t>(candidate.anchor_keyframe)].T_world_pose.translation(),
                                graph.vertices[static_cast<std::size_t>(candidate.keyframe)].T_world_pose.translation());
    }
  }
  return marks;
}

void write_map_png(const ProbabilityGrid& grid, const std::vector<ScanResult>& trajectory,
                   const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& loops, const std::string& path,
                   const SegmentMarks& segments) {
  MapPicture picture(grid, path);
  cairo_t* cr = picture.cr();
  auto to_image = [&](const Eigen::Vector2d& p) { return picture.to_image(p); };
  // Loop closures: thin green lines between the two poses.
  // Many loop closures would hide the map: the more there are, the fainter each line.
  cairo_set_line_width(cr, 1.0);
  cairo_set_source_rgba(cr, 0.1, 0.7, 0.2, std::clamp(60.0 / static_cast<double>(std::max<std::size_t>(loops.size(), 1)), 0.1, 0.6));
  for (const auto& [a, b] : loops) {
    const auto pa = to_image(a), pb = to_image(b);
    cairo_move_to(cr, pa.x(), pa.y());
    cairo_line_to(cr, pb.x(), pb.y());
    cairo_stroke(cr);
  }
  // Trajectory: blue when ok, orange when degraded, red when lost.
  cairo_set_line_width(cr, 1.5);
  for (std::size_t k = 1; k < trajectory.size(); ++k) {
    const Health h = trajectory[k].health;
    if (h == Health::kOk) cairo_set_source_rgb(cr, 0.12, 0.35, 0.85);
    else if (h == Health::kDegraded) cairo_set_source_rgb(cr, 0.95, 0.55, 0.05);
    else cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
    const auto pa = to_image(trajectory[k - 1].T_world_laser.translation());
    const auto pb = to_image(trajectory[k].T_world_laser.translation());
    cairo_move_to(cr, pa.x(), pa.y());
    cairo_line_to(cr, pb.x(), pb.y());
    cairo_stroke(cr);
  }
  // Map segments: the matches that merged them, and where each began.
  cairo_set_line_width(cr, 3.0);
  cairo_set_source_rgba(cr, 0.55, 0.1, 0.75, 0.9);
  for (const auto& [a, b] : segments.merges) {
    const auto pa = to_image(a), pb = to_image(b);
    cairo_move_to(cr, pa.x(), pa.y());
    cairo_line_to(cr, pb.x(), pb.y());
    cairo_stroke(cr);
  }
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
  cairo_set_font_size(cr, 13.0);
  cairo_set_line_width(cr, 2.0);
  for (const auto& start : segments.starts) {
    const auto p = to_image(start.position);
    if (start.merged) cairo_set_source_rgb(cr, 0.55, 0.1, 0.75);
    else cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
    cairo_new_sub_path(cr);
    cairo_arc(cr, p.x(), p.y(), 6.0, 0.0, 2.0 * std::numbers::pi);
    cairo_stroke(cr);
    cairo_move_to(cr, p.x() + 8.0, p.y() - 8.0);
    cairo_show_text(cr, start.label.c_str());
  }
  // Legend and scale bar.
  picture.legend_swatch(0.12, 0.35, 0.85, "ok");
  picture.legend_swatch(0.95, 0.55, 0.05, "degraded");
  picture.legend_swatch(0.9, 0.1, 0.1, "lost");
  picture.legend_swatch(0.1, 0.7, 0.2, "loop closure");
  if (!segments.starts.empty()) picture.legend_swatch(0.55, 0.1, 0.75, "segment start / merge");
  picture.scale_bar();
  picture.write(path);
}

nlohmann::json health_events_json(const std::vector<HealthEvent>& events) {
  nlohmann::json out = nlohmann::json::array();
  for (const HealthEvent& e : events) {
    out.push_back({{"time", e.time.to_seconds_string()},
                   {"scan", e.scan},
                   {"from", std::string(to_string(e.from))},
                   {"to", std::string(to_string(e.to))},
                   {"reason", e.reason}});
  }
  return out;
}

OutputFiles output_files(const std::string& directory) {
  OutputFiles files;
  const fs::path dir(directory);
  files.map_pgm = (dir / "map.pgm").string();
  files.map_yaml = (dir / "map.yaml").string();
  files.map_png = (dir / "map.png").string();
  files.trajectory = (dir / "trajectory.tum").string();
  files.scans = (dir / "scans.csv").string();
  files.graph = (dir / "graph.g2o").string();
  files.corrected_log = (dir / "corrected.clf").string();
  files.report = (dir / "report.json").string();
  return files;
}

OutputFiles write_outputs(const Slam2d& slam, const io::CarmenLog& log, std::size_t scans_used,
                          const std::string& directory, const Slam2dOptions& options) {
  const OutputFiles files = output_files(directory);

  ProbabilityGridOptions map_options = options.grid;
  map_options.resolution_m = options.output_map_resolution_m;
  const ProbabilityGrid grid = slam.render_map(map_options);
  write_map_pgm(grid, files.map_pgm, files.map_yaml);
  const std::vector<ScanResult> trajectory = slam.trajectory();
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> loops;
  const io::PoseGraph2D graph = slam.pose_graph();
  for (const auto& edge : graph.edges) {
    if (edge.to == edge.from + 1) continue;
    loops.emplace_back(graph.vertices[static_cast<std::size_t>(edge.from)].T_world_pose.translation(),
                       graph.vertices[static_cast<std::size_t>(edge.to)].T_world_pose.translation());
  }
  write_map_png(grid, trajectory, loops, files.map_png, segment_marks(slam, trajectory));
  io::write_tum(files.trajectory, to_trajectory(slam));
  io::write_output(files.scans, [&](std::ostream& out) {
    out << "time_s,x_m,y_m,theta_rad,health,inlier_fraction,degeneracy,sigma_x_m,sigma_y_m,sigma_theta_rad,keyframe,segment\n";
    std::string line;
    for (const ScanResult& s : trajectory) {
      line = s.time.to_seconds_string();
      for (const double v : {s.T_world_laser.x(), s.T_world_laser.y(), s.T_world_laser.angle()}) {
        line += ',';
        io::append_number(line, v);
      }
      line += ',';
      line += to_string(s.health);
      for (const double v : {s.inlier_fraction, s.degeneracy, std::sqrt(s.covariance(0, 0)), std::sqrt(s.covariance(1, 1)),
                             std::sqrt(s.covariance(2, 2))}) {
        line += ',';
        io::append_number(line, v);
      }
      line += s.keyframe ? ",1," : ",0,";
      line += std::to_string(s.segment);
      line += '\n';
      out << line;
    }
  });
  io::write_graph(files.graph, io::PoseGraph(graph), io::GraphFormat::kG2o);
  io::write_output(files.corrected_log, [&](std::ostream& out) {
    out << "# cairn slam2d: FLASER x y theta = corrected laser pose, odom_x odom_y odom_theta = odometry\n";
    std::string line;
    for (std::size_t k = 0; k < scans_used && k < trajectory.size(); ++k) {
      const io::LaserScan& scan = log.scans[k];
      line = "FLASER ";
      line += std::to_string(scan.ranges_m.size());
      for (const float range : scan.ranges_m) {
        line += ' ';
        append_float(line, range);
      }
      const core::SE2& T = trajectory[k].T_world_laser;
      for (const double v : {T.x(), T.y(), T.angle(), scan.T_odom_laser.x(), scan.T_odom_laser.y(), scan.T_odom_laser.angle()}) {
        line += ' ';
        io::append_number(line, v);
      }
      const std::string stamp = scan.time.to_seconds_string();
      line += ' ' + stamp + " cairn " + stamp + '\n';
      out << line;
    }
  });
  return files;
}

/// Per map segment: where and why it started, what it merged with, and why not (SegmentInfo).
nlohmann::json segments_json(const Slam2dSummary& s) {
  nlohmann::json segments = nlohmann::json::array();
  for (const SegmentInfo& g : s.segments) {
    segments.push_back({{"id", g.id},
                        {"first_scan", g.first_scan},
                        {"scans", g.scans},
                        {"first_keyframe", g.first_keyframe},
                        {"keyframes", g.keyframes},
                        {"path_length_m", g.path_length_m},
                        {"extent_m", {{"min", {g.min_world.x(), g.min_world.y()}}, {"max", {g.max_world.x(), g.max_world.y()}}}},
                        {"merged_with", g.merged_with},
                        {"started_because", g.started_because},
                        {"odometry_link_trusted", g.odometry_link_trusted},
                        {"merge_searches", g.merge_searches},
                        {"why_not_merged", g.why_not_merged}});
  }
  return segments;
}

nlohmann::json report_json(const Slam2d& slam, const Slam2dOptions& options) {
  const Slam2dSummary& s = slam.summary();
  nlohmann::json report;
  report["summary"] = {{"scans", s.scans},
                       {"keyframes", s.keyframes},
                       {"submaps", s.submaps},
                       {"optimizations", s.optimizations},
                       {"loop_searches", s.loop_searches},
                       {"loop_candidates", s.candidates.size()},
                       {"loops_accepted", s.loops_accepted},
                       {"loops_rejected_by_gnc", s.loops_rejected_by_gnc},
                       {"scans_ok", s.scans_ok},
                       {"scans_degraded", s.scans_degraded},
                       {"scans_lost", s.scans_lost},
                       {"relocalisations", s.relocalisations},
                       {"scans_new_space", s.scans_new_space},
                       {"merge_searches", s.merge_searches},
                       {"global_searches", s.global_searches},
                       {"searches_skipped_by_budget", s.searches_skipped_by_budget},
                       {"uniqueness_searches", s.uniqueness_searches},
                       {"merges_refused_as_ambiguous", s.merges_refused_as_ambiguous},
                       {"segments", s.segments.size()},
                       {"merges", s.merges.size()},
                       {"final_health", std::string(to_string(slam.health()))}};
  report["time_s"] = {{"preprocess", s.times.preprocess_s}, {"local_match", s.times.local_match_s},
                      {"local_map", s.times.local_map_s},   {"submaps", s.times.submap_s},
                      {"loop_search", s.times.loop_search_s}, {"of_which_global_search", s.times.global_search_s}, {"optimize", s.times.optimize_s},
                      {"slam_total", s.total_s}};
  nlohmann::json candidates = nlohmann::json::array();
  for (const LoopCandidate& c : s.candidates) {
    candidates.push_back({{"keyframe", c.keyframe},
                          {"submap", c.submap},
                          {"anchor_keyframe", c.anchor_keyframe},
                          {"time", c.time.to_seconds_string()},
                          {"anchor_time", c.anchor_time.to_seconds_string()},
                          {"search_window_m", c.search_window_m},
                          {"score", c.score},
                          {"second_score", c.second_score},
                          {"inlier_fraction", c.inlier_fraction},
                          {"rms_m", c.rms_m},
                          {"degeneracy", c.degeneracy},
                          {"T_anchor_keyframe", {c.T_anchor_keyframe.x(), c.T_anchor_keyframe.y(), c.T_anchor_keyframe.angle()}},
                          {"accepted", c.accepted && !c.rejected_by_gnc},
                          {"verified", c.accepted},
                          {"rejected_by_gnc", c.rejected_by_gnc},
                          {"relocalisation", c.relocalisation},
                          {"merge", c.merge},
                          {"merge_decision", c.merge_decision},
                          {"global", c.global},
                          {"reason", c.rejected_by_gnc ? std::string("rejected by GNC in the back end") : c.reason}});
  }
  report["loop_candidates"] = candidates;
  report["health_events"] = health_events_json(s.health_events);
  report["segments"] = segments_json(s);
  // Segment groups that nothing joined to segment 0: their placement rests on odometry alone.
  nlohmann::json unmerged = nlohmann::json::array();
  for (const SegmentInfo& g : s.segments)
    if (g.merged_with != 0) unmerged.push_back(g.id);
  report["segments_not_merged_with_segment_0"] = unmerged;
  nlohmann::json merges = nlohmann::json::array();
  for (const MergeEvent& m : s.merges) {
    merges.push_back({{"time", m.time.to_seconds_string()},
                      {"scan", m.scan},
                      {"group_a", m.segment_a},
                      {"group_b", m.segment_b},
                      {"evidence_candidates", m.candidates},
                      {"moved_m", m.moved_m}});
  }
  report["merges"] = merges;
  report["options"] = config_json(options);
  report["config_yaml"] = config_to_yaml(options);
  return report;
}

}  // namespace cairn::slam2d
