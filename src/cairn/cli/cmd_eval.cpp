// `cairn eval ape|rpe|kitti|relations`: trajectory metrics (src/cairn/eval/, docs/evaluation.md)
// with a table on the terminal, JSON and plots (src/cairn/viz/).
//
//   cairn eval ape GT EST [--align se3] [--relation trans_part]     evo_ape's APE
//   cairn eval rpe GT EST --delta 10 --unit m [--all-pairs]         evo_rpe's RPE
//   cairn eval kitti GT EST                                          KITTI devkit t_err / r_err
//   cairn eval relations RELATIONS EST                               Kuemmerle et al. 2009

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/viz/render.hpp"

namespace cairn::cli {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

struct EvalFlags {
  std::string reference;  // GT, or the relations file
  std::string estimate;
  std::string format;
  std::string reference_format;
  std::string estimate_format;
  std::string reference_times;
  std::string estimate_times;
  std::string align = "none";
  std::string relation = "trans_part";
  double max_diff_s = -1;  // < 0: the metric's default (0.01 s; relations 0.1 s)
  double offset_s = 0;
  double delta = 1;
  std::string unit = "frames";
  bool all_pairs = false;
  std::string json;
  std::string plot;
  std::string plot_plane = "auto";
};

// ---------------------------------------------------------------------------------------------
// Input

eval::MatrixTrajectory read_matrices(const std::string& path, const std::string& own_format,
                                     const std::string& shared_format, const char* flag_name,
                                     const std::string& times) {
  const std::string& flag = own_format.empty() ? shared_format : own_format;
  const io::FileFormat format = resolve_format(path, flag, flag_name);
  if (io::kind_of(format) != io::FileKind::kTrajectory) {
    throw io::ParseError(path, 0,
                         "expected a trajectory (TUM, KITTI or EuRoC), found a " + std::string(io::to_string(format)) +
                             " file; name the format with " + flag_name + " if it was guessed wrongly");
  }
  if (!times.empty() && format != io::FileFormat::kKitti) {
    throw io::ParseError(times, 0, "a times file goes with a KITTI trajectory only; " + path + " is " +
                                       std::string(io::to_string(format)));
  }
  // KITTI: the 3x4 blocks as written, as evo and the devkit use them (eval/matrix_trajectory.hpp).
  if (format == io::FileFormat::kKitti) return eval::read_kitti_matrices(path, times);
  io::TrajectoryReadReport report;
  const io::Trajectory trajectory = read_trajectory(path, format, times, &report);
  if (report.repeated_stamps_dropped > 0) {
    warn(path + ": " + std::to_string(report.repeated_stamps_dropped) +
         " poses dropped because their timestamp repeated the previous one");
  }
  if (report.quaternions_normalised > 0) {
    warn(path + ": " + std::to_string(report.quaternions_normalised) + " quaternions were not unit and were normalised");
  }
  return eval::MatrixTrajectory(trajectory);
}

eval::MatrixTrajectory read_reference(const EvalFlags& f) {
  return read_matrices(f.reference, f.reference_format, f.format, "--gt-format", f.reference_times);
}
eval::MatrixTrajectory read_estimate(const EvalFlags& f) {
  return read_matrices(f.estimate, f.estimate_format, f.format, "--est-format", f.estimate_times);
}

eval::AssociationOptions association_options(const EvalFlags& f) {
  eval::AssociationOptions a;
  if (f.max_diff_s >= 0) a.max_time_difference_s = f.max_diff_s;
  a.offset_s = f.offset_s;
  return a;
}

eval::AlignmentOptions alignment_options(const EvalFlags& f) {
  eval::AlignmentOptions a;
  a.method = *eval::alignment_method_from_name(f.align);  // CLI11 checked the name
  return a;
}

[[noreturn]] void fail(const EvalFlags& f, const eval::Outcome& outcome) {
  throw std::runtime_error(f.estimate + " against " + f.reference + ": " + outcome.message + " [" +
                           std::string(eval::to_string(outcome.status)) + "]");
}

// ---------------------------------------------------------------------------------------------
// Terminal and JSON

std::string number(double v, int significant = 9) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, v);
  return buffer;
}

void print_row(const std::string& name, const std::string& value) {
  std::cout << "  " << name << std::string(name.size() < 14 ? 14 - name.size() : 1, ' ') << value << '\n';
}

void print_statistics(const eval::Statistics& s, std::string_view unit) {
  const std::string u = unit.empty() ? "" : " " + std::string(unit);
  const std::string u2 = unit.empty() ? "" : " " + std::string(unit) + "^2";
  print_row("rmse", number(s.rmse) + u);
  print_row("mean", number(s.mean) + u);
  print_row("median", number(s.median) + u);
  print_row("std", number(s.std) + u);
  print_row("min", number(s.min) + u);
  print_row("max", number(s.max) + u);
  print_row("sse", number(s.sse) + u2);
  print_row("count", std::to_string(s.count));
}

nlohmann::json statistics_json(const eval::Statistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"sse", s.sse},       {"count", s.count}};
}

std::string describe_pairs(const eval::Association& a) {
  return std::to_string(a.size()) + " of " + std::to_string(a.max_pairs) +
         (a.by_time ? " poses associated by time" : " poses paired by index");
}

nlohmann::json association_json(const eval::Association& a, const eval::AssociationOptions& options) {
  return {{"pairs", a.size()},
          {"max_pairs", a.max_pairs},
          {"by_time", a.by_time},
          {"max_time_difference_s", options.max_time_difference_s},
          {"offset_s", options.offset_s}};
}

void print_alignment(const eval::Alignment& a) {
  if (a.method == eval::AlignmentMethod::kNone) {
    print_row("alignment", "none");
    return;
  }
  const core::SE3 T = a.T_reference_estimate();
  print_row("alignment", std::string(eval::to_string(a.method)) + " from " + std::to_string(a.pairs_used) +
                             " pairs: rotation " + number(T.so3().log().norm() * kRadToDeg, 6) + " deg, translation " +
                             number(a.t.norm(), 6) + " m, scale " + number(a.scale, 9));
}

nlohmann::json alignment_json(const eval::Alignment& a) {
  nlohmann::json R = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) R.push_back({a.R(r, 0), a.R(r, 1), a.R(r, 2)});
  return {{"method", eval::to_string(a.method)},
          {"pairs_used", a.pairs_used},
          {"R", R},
          {"t", {a.t.x(), a.t.y(), a.t.z()}},
          {"scale", a.scale}};
}

// The files of one evaluation (--json and every --plot) form one result: each is produced in
// memory as the run goes and all are written at its end, after the last was produced
// (io::write_outputs), so a run that fails half way replaces none of them.
std::vector<io::PlannedOutput> g_pending_outputs;

void queue_output(const std::string& path, std::string bytes) {
  g_pending_outputs.push_back({path, [bytes = std::move(bytes)](std::ostream& out) { out << bytes; }});
}

void write_queued_outputs() {
  io::write_outputs(g_pending_outputs);
  for (const io::PlannedOutput& o : g_pending_outputs) {
    if (!io::is_standard_output(o.path)) std::cout << "wrote " << o.path << '\n';
  }
  g_pending_outputs.clear();
}

void emit_json(const std::string& destination, const nlohmann::json& j) {
  if (destination.empty()) return;
  queue_output(destination, io::json_text(j));
}

// ---------------------------------------------------------------------------------------------
// Plots

/// --plot PREFIX or --plot FILE.png|svg: the format, and the prefix each plot's name extends.
struct PlotTarget {
  std::string prefix;
  viz::ImageFormat format = viz::ImageFormat::kPng;
};

PlotTarget plot_target(const std::string& flag) {
  PlotTarget t;
  if (auto format = viz::image_format_from_path(flag)) {
    t.format = *format;
    t.prefix = flag.substr(0, flag.size() - 4);
  } else {
    t.prefix = flag;
  }
  return t;
}

void save_plot(const PlotTarget& target, const std::string& name, const viz::Figure& figure) {
  const std::string path = target.prefix + "_" + name + std::string(viz::extension(target.format));
  const viz::RenderResult image = viz::render(figure, target.format);
  if (!image.ok) throw io::ParseError(path, 0, "cannot draw the plot: " + image.message);
  queue_output(path, image.bytes);
}

/// The two axes of the top view: given by --plot-plane, or (auto) the two along which the
/// reference spreads most (KITTI camera poses have y pointing down, so that gives x-z).
std::pair<int, int> plane_axes(const std::string& plane, const std::vector<Matrix4>& reference) {
  if (plane == "xy") return {0, 1};
  if (plane == "xz") return {0, 2};
  if (plane == "yz") return {1, 2};
  Vector3 lo = Vector3::Constant(std::numeric_limits<double>::infinity());
  Vector3 hi = -lo;
  for (const Matrix4& T : reference) {
    lo = lo.cwiseMin(T.block<3, 1>(0, 3));
    hi = hi.cwiseMax(T.block<3, 1>(0, 3));
  }
  const Vector3 extent = hi - lo;
  int smallest = 2;
  if (extent.x() < extent(smallest)) smallest = 0;
  if (extent.y() < extent(smallest)) smallest = 1;
  if (smallest == 0) return {1, 2};
  if (smallest == 1) return {0, 2};
  return {0, 1};
}

viz::Series positions(const std::vector<Matrix4>& poses, std::pair<int, int> axes) {
  viz::Series s;
  for (const Matrix4& T : poses) {
    s.x.push_back(T(axes.first, 3));
    s.y.push_back(T(axes.second, 3));
  }
  return s;
}

const char* axis_name(int axis) { return axis == 0 ? "x [m]" : axis == 1 ? "y [m]" : "z [m]"; }

/// Top view: reference dashed grey, estimate coloured by `values` (one per estimate pose) when
/// given, otherwise blue; optional coloured points (RPE pair starts).
viz::Figure top_view(const std::string& title, const std::vector<Matrix4>& reference,
                     const std::vector<Matrix4>& estimate, const std::vector<double>& values,
                     const std::string& color_label, const std::string& plane, const viz::Series* points = nullptr) {
  const auto axes = plane_axes(plane, reference);
  viz::Axes a;
  a.title = title;
  a.x_label = axis_name(axes.first);
  a.y_label = axis_name(axes.second);
  a.equal_aspect = true;
  viz::Series ref = positions(reference, axes);
  ref.label = "reference";
  ref.color = viz::kGrey;
  ref.dashed = true;
  ref.width_px = 1.5;
  viz::Series est = positions(estimate, axes);
  est.label = "estimate";
  est.width_px = 2.0;
  est.color = viz::categorical(0);
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  const std::vector<double>& coloured = points != nullptr ? points->values : values;
  for (double v : coloured) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (!coloured.empty()) a.color_bar = viz::ColorBar{color_label, lo, hi};
  if (points == nullptr && !values.empty()) {
    est.values = values;
    est.label = "estimate (colour: error)";
  }
  a.series = {ref, est};
  if (points != nullptr) a.series.push_back(*points);
  viz::Figure f;
  f.width_px = 900;
  f.height_px = 800;
  f.panels = {a};
  return f;
}

/// Error against time or distance, with rmse / mean / median lines as evo draws them.
viz::Figure error_plot(const std::string& title, const std::vector<double>& x, const std::vector<double>& errors,
                       const std::string& x_label, const std::string& y_label, const eval::Statistics& s,
                       const std::string& unit) {
  viz::Axes a;
  a.title = title;
  a.x_label = x_label;
  a.y_label = y_label;
  a.y_from_zero = true;
  viz::Series e;
  e.label = "error";
  e.x = x;
  e.y = errors;
  e.width_px = 1.3;
  e.color = viz::categorical(0);
  a.series = {e};
  const std::string u = unit.empty() ? "" : " " + unit;
  a.horizontal_lines = {{"rmse " + number(s.rmse, 4) + u, s.rmse, viz::categorical(3), true},
                        {"mean " + number(s.mean, 4) + u, s.mean, viz::categorical(1), true},
                        {"median " + number(s.median, 4) + u, s.median, viz::categorical(2), true}};
  viz::Figure f;
  f.width_px = 1000;
  f.height_px = 450;
  f.panels = {a};
  return f;
}

std::string relation_label(eval::PoseRelation r) {
  const std::string_view unit = eval::unit_of(r);
  return std::string(eval::describe(r)) + (unit.empty() ? "" : " [" + std::string(unit) + "]");
}

// ---------------------------------------------------------------------------------------------
// The four metrics

void print_header(const std::string& what, const EvalFlags& f, const char* reference_name = "reference") {
  std::cout << what << '\n';
  print_row(reference_name, f.reference);
  print_row("estimate", f.estimate);
}

int run_ape(const EvalFlags& f) {
  const eval::MatrixTrajectory reference = read_reference(f);
  const eval::MatrixTrajectory estimate = read_estimate(f);
  eval::ApeOptions options;
  options.relation = *eval::pose_relation_from_name(f.relation);
  options.association = association_options(f);
  options.alignment = alignment_options(f);
  const eval::ApeResult r = eval::evaluate_ape(reference, estimate, options);
  if (!r.outcome.ok()) fail(f, r.outcome);

  print_header("APE w.r.t. " + std::string(eval::describe(r.relation)), f);
  print_row("pairs", describe_pairs(r.association));
  print_alignment(r.alignment);
  print_statistics(r.statistics, eval::unit_of(r.relation));

  nlohmann::json j = {{"metric", "ape"},
                      {"reference", f.reference},
                      {"estimate", f.estimate},
                      {"relation", eval::to_string(r.relation)},
                      {"unit", eval::unit_of(r.relation)},
                      {"association", association_json(r.association, options.association)},
                      {"alignment", alignment_json(r.alignment)},
                      {"statistics", statistics_json(r.statistics)},
                      {"time_s", r.time_s},
                      {"errors", r.errors}};
  emit_json(f.json, j);
  if (!f.plot.empty()) {
    const PlotTarget target = plot_target(f.plot);
    const std::string label = "APE, " + relation_label(r.relation);
    save_plot(target, "top",
              top_view("APE (" + std::string(eval::to_string(r.alignment.method)) + " alignment): " +
                           "rmse " + number(r.statistics.rmse, 4) + " " + std::string(eval::unit_of(r.relation)),
                       r.reference, r.estimate, r.errors, label, f.plot_plane));
    save_plot(target, "error",
              error_plot(r.association.by_time ? "APE over time" : "APE per pose", r.time_s, r.errors,
                         r.association.by_time ? "time since the first pair [s]" : "pose index", label, r.statistics,
                         std::string(eval::unit_of(r.relation))));
  }
  return 0;
}

/// Path length along `poses` at each pose, metres.
std::vector<double> path_length(const std::vector<Matrix4>& poses) {
  std::vector<double> d(poses.size(), 0.0);
  for (std::size_t i = 1; i < poses.size(); ++i) {
    d[i] = d[i - 1] + (poses[i].block<3, 1>(0, 3) - poses[i - 1].block<3, 1>(0, 3)).norm();
  }
  return d;
}

int run_rpe(const EvalFlags& f) {
  const eval::MatrixTrajectory reference = read_reference(f);
  const eval::MatrixTrajectory estimate = read_estimate(f);
  eval::RpeOptions options;
  options.relation = *eval::pose_relation_from_name(f.relation);
  options.delta = f.delta;
  options.delta_unit = *eval::delta_unit_from_name(f.unit);
  options.all_pairs = f.all_pairs;
  options.association = association_options(f);
  options.alignment = alignment_options(f);
  if (std::string problems = options.validate(); !problems.empty()) {
    throw std::runtime_error("invalid RPE options: " + problems);
  }
  const eval::RpeResult r = eval::evaluate_rpe(reference, estimate, options);
  if (!r.outcome.ok()) fail(f, r.outcome);

  const bool metres = options.delta_unit == eval::DeltaUnit::kMeters;
  const std::string delta = number(options.delta, 6) + (metres ? " m" : " frames");
  print_header("RPE w.r.t. " + std::string(eval::describe(r.relation)) + ", delta " + delta + ", " +
                   (options.all_pairs ? "all pairs" : "consecutive pairs"),
               f);
  print_row("pairs", describe_pairs(r.association) + "; " + std::to_string(r.pairs.size()) + " RPE pairs");
  print_alignment(r.alignment);
  print_statistics(r.statistics, eval::unit_of(r.relation));

  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& [i, j] : r.pairs) pairs.push_back({i, j});
  nlohmann::json j = {{"metric", "rpe"},
                      {"reference", f.reference},
                      {"estimate", f.estimate},
                      {"relation", eval::to_string(r.relation)},
                      {"unit", eval::unit_of(r.relation)},
                      {"delta", options.delta},
                      {"delta_unit", eval::to_string(options.delta_unit)},
                      {"all_pairs", options.all_pairs},
                      {"association", association_json(r.association, options.association)},
                      {"alignment", alignment_json(r.alignment)},
                      {"statistics", statistics_json(r.statistics)},
                      {"pairs", pairs},
                      {"errors", r.errors}};
  emit_json(f.json, j);
  if (!f.plot.empty()) {
    const PlotTarget target = plot_target(f.plot);
    const std::string label = "RPE, " + relation_label(r.relation);
    // x of each pair: distance along the reference (metres) or time of its first pose.
    const std::vector<double> distance = path_length(r.reference);
    std::vector<double> x;
    viz::Series starts;
    starts.style = viz::SeriesStyle::kPoints;
    starts.width_px = 5;
    starts.label = "pair start (colour: error)";
    const auto axes = plane_axes(f.plot_plane, r.reference);
    for (std::size_t k = 0; k < r.pairs.size(); ++k) {
      const std::size_t i = r.pairs[k].first;
      x.push_back(metres ? distance[i] : r.time_s[i]);
      starts.x.push_back(r.estimate[i](axes.first, 3));
      starts.y.push_back(r.estimate[i](axes.second, 3));
      starts.values.push_back(r.errors[k]);
    }
    save_plot(target, "top", top_view("RPE over " + delta + " (not aligned unless --align): rmse " +
                                          number(r.statistics.rmse, 4) + " " + std::string(eval::unit_of(r.relation)),
                                      r.reference,
                                      r.estimate, {}, label, f.plot_plane, &starts));
    const std::string x_label = metres ? "distance travelled along the reference [m]"
                                       : (r.association.by_time ? "time since the first pair [s]" : "pose index");
    save_plot(target, "error", error_plot("RPE over " + delta, x, r.errors, x_label, label, r.statistics,
                                          std::string(eval::unit_of(r.relation))));
  }
  return 0;
}

int run_kitti(const EvalFlags& f) {
  const eval::MatrixTrajectory reference = read_reference(f);
  const eval::MatrixTrajectory estimate = read_estimate(f);
  eval::KittiOptions options;
  options.association = association_options(f);
  const eval::KittiResult r = eval::evaluate_kitti(reference, estimate, options);
  if (!r.outcome.ok()) fail(f, r.outcome);

  print_header("KITTI odometry metric (devkit evaluate_odometry.cpp): segments of 100..800 m every 10 frames", f,
               "ground truth");
  print_row("pairs", describe_pairs(r.association) + "; " + std::to_string(r.segments.size()) + " segments");
  print_row("path", number(r.path_length_m.back(), 6) + " m (ground truth)");
  print_row("t_err", number(r.translation_error_percent(), 6) + " %");
  print_row("r_err", number(r.rotation_error_deg_per_100m(), 6) + " deg/100 m (" +
                         number(r.rotation_error_rad_per_m, 6) + " rad/m)");
  std::cout << "  length [m]  segments  t_err [%]  r_err [deg/100 m]\n";
  for (const eval::KittiLengthError& e : r.per_length) {
    char line[128];
    std::snprintf(line, sizeof line, "  %10.0f  %8zu  %9.4f  %17.4f%s\n", e.length_m, e.segments,
                  100.0 * e.translation_error_m_per_m, e.rotation_error_rad_per_m * kRadToDeg * 100.0,
                  e.reported_by_devkit ? "" : "  (fewer than 3 segments: the devkit omits this length)");
    std::cout << line;
  }

  nlohmann::json lengths = nlohmann::json::array();
  for (const eval::KittiLengthError& e : r.per_length) {
    lengths.push_back({{"length_m", e.length_m},
                       {"segments", e.segments},
                       {"t_err_m_per_m", e.translation_error_m_per_m},
                       {"r_err_rad_per_m", e.rotation_error_rad_per_m},
                       {"reported_by_devkit", e.reported_by_devkit}});
  }
  nlohmann::json j = {{"metric", "kitti"},
                      {"reference", f.reference},
                      {"estimate", f.estimate},
                      {"association", association_json(r.association, options.association)},
                      {"segments", r.segments.size()},
                      {"t_err_m_per_m", r.translation_error_m_per_m},
                      {"r_err_rad_per_m", r.rotation_error_rad_per_m},
                      {"t_err_percent", r.translation_error_percent()},
                      {"r_err_deg_per_100m", r.rotation_error_deg_per_100m()},
                      {"per_length", lengths}};
  emit_json(f.json, j);
  if (!f.plot.empty()) {
    const PlotTarget target = plot_target(f.plot);
    viz::Axes t;
    viz::Axes rot;
    t.title = "translation error: " + number(r.translation_error_percent(), 4) + " % overall";
    rot.title = "rotation error: " + number(r.rotation_error_deg_per_100m(), 4) + " deg/100 m overall";
    t.x_label = rot.x_label = "segment length [m]";
    t.y_label = "t_err [%]";
    rot.y_label = "r_err [deg/100 m]";
    viz::BarSet tb{"", {}, viz::categorical(0)};
    viz::BarSet rb{"", {}, viz::categorical(1)};
    for (const eval::KittiLengthError& e : r.per_length) {
      t.categories.push_back(number(e.length_m, 6));
      const bool any = e.segments > 0;
      tb.values.push_back(any ? 100.0 * e.translation_error_m_per_m : std::nan(""));
      rb.values.push_back(any ? e.rotation_error_rad_per_m * kRadToDeg * 100.0 : std::nan(""));
    }
    rot.categories = t.categories;
    t.bars = {tb};
    rot.bars = {rb};
    t.bar_value_decimals = 3;
    rot.bar_value_decimals = 3;
    t.horizontal_lines = {{"mean over all segments", r.translation_error_percent(), viz::kBlack, true}};
    rot.horizontal_lines = {{"mean over all segments", r.rotation_error_deg_per_100m(), viz::kBlack, true}};
    viz::Figure bars;
    bars.title = "KITTI odometry metric per segment length (" + std::to_string(r.segments.size()) + " segments)";
    bars.width_px = 1200;
    bars.height_px = 480;
    bars.columns = 2;
    bars.panels = {t, rot};
    save_plot(target, "segments", bars);
    save_plot(target, "top", top_view("KITTI: t_err " + number(r.translation_error_percent(), 4) + " %", r.reference,
                                      r.estimate, {}, "", f.plot_plane));
  }
  return 0;
}

void print_mean_std(const std::string& name, const eval::MeanStd& m, const std::string& unit) {
  print_row(name, number(m.mean, 6) + " +- " + number(m.std, 6) + " " + unit + "  (min " + number(m.min, 6) +
                      ", max " + number(m.max, 6) + ")");
}

nlohmann::json mean_std_json(const eval::MeanStd& m) {
  return {{"mean", m.mean}, {"std", m.std}, {"min", m.min}, {"max", m.max}};
}

/// The estimate of a relations evaluation: a trajectory file, or a (corrected) CARMEN log whose
/// laser poses are the estimate, as the Freiburg evaluator reads it (one pose per laser record,
/// at its ipc_timestamp; the relations' times name these records).
eval::MatrixTrajectory read_relations_estimate(const EvalFlags& f) {
  const std::string& flag = f.estimate_format.empty() ? f.format : f.estimate_format;
  const io::FileFormat format = resolve_format(f.estimate, flag, "--est-format");
  if (format != io::FileFormat::kCarmen) return read_estimate(f);
  io::CarmenReadReport report;
  const io::CarmenLog log = io::read_carmen_log(f.estimate, &report);
  eval::MatrixTrajectory estimate;
  for (const io::LaserScan& scan : log.scans) {
    Matrix4 T = Matrix4::Identity();
    const core::SE2& p = scan.T_odom_laser;
    T(0, 0) = std::cos(p.angle());
    T(0, 1) = -std::sin(p.angle());
    T(1, 0) = std::sin(p.angle());
    T(1, 1) = std::cos(p.angle());
    T(0, 3) = p.x();
    T(1, 3) = p.y();
    if (!estimate.stamps.empty() && scan.time <= estimate.stamps.back()) {
      throw io::ParseError(f.estimate, scan.line,
                           "laser record time " + scan.time.to_seconds_string() + " s does not follow the previous one (" +
                               estimate.stamps.back().to_seconds_string() + " s); the estimate needs increasing times");
    }
    estimate.stamps.push_back(scan.time);
    estimate.poses.push_back(T);
  }
  if (estimate.poses.empty()) throw io::ParseError(f.estimate, 0, "no laser records (FLASER, RLASER, ROBOTLASER1)");
  return estimate;
}

int run_relations(const EvalFlags& f) {
  const std::vector<eval::Relation> relations = eval::read_relations(f.reference);
  const eval::MatrixTrajectory estimate = read_relations_estimate(f);
  eval::RelationsOptions options;
  if (f.max_diff_s >= 0) options.max_time_difference_s = f.max_diff_s;
  const eval::RelationsResult r = eval::evaluate_relations(relations, estimate, options);
  if (!r.outcome.ok()) fail(f, r.outcome);

  print_header("Relations metric (Kuemmerle et al. 2009), " + std::to_string(relations.size()) + " relations", f,
               "relations");
  print_mean_std("trans abs", r.translation_absolute_m, "m");
  print_mean_std("trans sq", r.translation_squared_m2, "m^2");
  print_mean_std("rot abs", r.rotation_absolute_deg, "deg");
  print_mean_std("rot sq", r.rotation_squared_deg2, "deg^2");

  nlohmann::json per = nlohmann::json::array();
  for (std::size_t k = 0; k < relations.size(); ++k) {
    per.push_back({{"line", relations[k].line},
                   {"t_i", relations[k].from.to_seconds_string()},
                   {"t_j", relations[k].to.to_seconds_string()},
                   {"translation_error_m", r.translation_errors_m[k]},
                   {"rotation_error_rad", r.rotation_errors_rad[k]}});
  }
  nlohmann::json j = {{"metric", "relations"},
                      {"relations", f.reference},
                      {"estimate", f.estimate},
                      {"max_time_difference_s", options.max_time_difference_s},
                      {"count", relations.size()},
                      {"translation_absolute_m", mean_std_json(r.translation_absolute_m)},
                      {"translation_squared_m2", mean_std_json(r.translation_squared_m2)},
                      {"rotation_absolute_deg", mean_std_json(r.rotation_absolute_deg)},
                      {"rotation_squared_deg2", mean_std_json(r.rotation_squared_deg2)},
                      {"per_relation", per}};
  emit_json(f.json, j);
  if (!f.plot.empty()) {
    const PlotTarget target = plot_target(f.plot);
    const double t0 = relations.front().from.seconds();
    viz::Axes trans;
    viz::Axes rot;
    trans.title = "translational error per relation: " + number(r.translation_absolute_m.mean, 4) + " +- " +
                  number(r.translation_absolute_m.std, 4) + " m";
    rot.title = "rotational error per relation: " + number(r.rotation_absolute_deg.mean, 4) + " +- " +
                number(r.rotation_absolute_deg.std, 4) + " deg";
    trans.x_label = rot.x_label = "time of the relation's first scan, since the first relation [s]";
    trans.y_label = "error [m]";
    rot.y_label = "error [deg]";
    trans.y_from_zero = rot.y_from_zero = true;
    viz::Series ts;
    ts.style = viz::SeriesStyle::kPoints;
    ts.width_px = 3.5;
    viz::Series rs = ts;
    rs.color = viz::categorical(1);
    for (std::size_t k = 0; k < relations.size(); ++k) {
      const double x = relations[k].from.seconds() - t0;
      ts.x.push_back(x);
      ts.y.push_back(r.translation_errors_m[k]);
      rs.x.push_back(x);
      rs.y.push_back(r.rotation_errors_rad[k] * kRadToDeg);
    }
    trans.series = {ts};
    rot.series = {rs};
    trans.horizontal_lines = {{"mean", r.translation_absolute_m.mean, viz::kBlack, true}};
    rot.horizontal_lines = {{"mean", r.rotation_absolute_deg.mean, viz::kBlack, true}};
    viz::Figure errors;
    errors.width_px = 1000;
    errors.height_px = 700;
    errors.panels = {trans, rot};
    save_plot(target, "error", errors);
  }
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Flags

void add_common(CLI::App& command, EvalFlags& f, bool relations) {
  if (relations) {
    command.add_option("RELATIONS", f.reference, "Relations file: 't_i t_j x y z roll pitch yaw' per line")->required();
  } else {
    command.add_option("GT", f.reference, "Reference (ground-truth) trajectory: TUM, KITTI or EuRoC")->required();
  }
  command.add_option("EST", f.estimate,
                     relations ? "Estimate: TUM, KITTI (with --est-times) or EuRoC trajectory, or a corrected CARMEN log"
                               : "Estimated trajectory: TUM, KITTI or EuRoC")
      ->required();
  command.add_option("--format", f.format, "Format of both trajectories: tum, kitti, euroc (default: from the name)")
      ->check(CLI::IsMember({"tum", "kitti", "euroc"}));
  if (!relations) {
    command.add_option("--gt-format", f.reference_format, "Format of GT only")->check(CLI::IsMember({"tum", "kitti", "euroc"}));
    command.add_option("--gt-times", f.reference_times, "KITTI times file for GT (then poses associate by time)");
  }
  command.add_option("--est-format", f.estimate_format, "Format of EST only")
      ->check(relations ? CLI::IsMember({"tum", "kitti", "euroc", "carmen"}) : CLI::IsMember({"tum", "kitti", "euroc"}));
  command.add_option("--est-times", f.estimate_times, "KITTI times file for EST");
  command.add_option("--max-diff", f.max_diff_s,
                     relations ? "Largest time difference to the nearest estimated pose, s (default 0.1)"
                               : "Largest time difference of an associated pair, s (default 0.01, as evo)")
      ->check(checks::non_negative());
  if (!relations) {
    command.add_option("--offset", f.offset_s, "Added to every EST time stamp before association, s (default 0)")
        ->check(checks::finite());
  }
  command.add_option("--json", f.json, "Also write the results as JSON to this file ('-' for stdout)");
  command.add_option("--plot", f.plot,
                     "Write plots: PREFIX gives PREFIX_<name>.png; PREFIX.svg or PREFIX.png picks the format");
  command.add_option("--plot-plane", f.plot_plane, "Plane of the top view: auto (the reference's widest), xy, xz, yz")
      ->check(CLI::IsMember({"auto", "xy", "xz", "yz"}));
}

void add_align_and_relation(CLI::App& command, EvalFlags& f) {
  command.add_option("--align", f.align, "Alignment of EST onto GT: none, se3, sim3, se2, first (default none)")
      ->check(CLI::IsMember({"none", "se3", "sim3", "se2", "first"}));
  command
      .add_option("--relation", f.relation,
                  "What to measure: trans_part (m), angle_deg, angle_rad, rot_part, full (default trans_part)")
      ->check(CLI::IsMember({"trans_part", "angle_deg", "angle_rad", "rot_part", "full"}));
}

}  // namespace

Runner register_eval(CLI::App& app) {
  auto flags = std::make_shared<EvalFlags>();
  app.require_subcommand(1);
  CLI::App* ape = app.add_subcommand("ape", "Absolute pose error, as evo_ape (association, alignment, statistics)");
  add_common(*ape, *flags, false);
  add_align_and_relation(*ape, *flags);

  CLI::App* rpe = app.add_subcommand("rpe", "Relative pose error over a delta in frames or metres, as evo_rpe");
  add_common(*rpe, *flags, false);
  add_align_and_relation(*rpe, *flags);
  rpe->add_option("--delta", flags->delta, "Pair distance in --unit (default 1)")->check(checks::positive());
  rpe->add_option("--unit", flags->unit, "Unit of --delta: frames or m (default frames)")
      ->check(CLI::IsMember({"frames", "f", "m", "meters", "metres"}));
  rpe->add_flag("--all-pairs", flags->all_pairs, "All overlapping pairs instead of consecutive ones");

  CLI::App* kitti = app.add_subcommand("kitti", "KITTI odometry metric: t_err [%] and r_err [deg/100 m] over 100..800 m");
  add_common(*kitti, *flags, false);

  CLI::App* relations =
      app.add_subcommand("relations", "Freiburg relations metric (Kuemmerle et al. 2009) on a relations file");
  add_common(*relations, *flags, true);

  return [flags, ape, rpe, kitti, relations]() {
    // With --json - the results table goes to stderr and standard output carries the JSON alone.
    claim_standard_output(flags->json);
    if (!flags->plot.empty() && (flags->plot == "-" || io::is_standard_output(flags->plot))) {
      throw io::ParseError(flags->plot, 0, "--plot writes several files (PREFIX_<name>.png): give a prefix, not standard output");
    }
    int status = 2;
    if (ape->parsed()) status = run_ape(*flags);
    if (rpe->parsed()) status = run_rpe(*flags);
    if (kitti->parsed()) status = run_kitti(*flags);
    if (relations->parsed()) status = run_relations(*flags);
    if (status == 0) write_queued_outputs();  // a failed evaluation writes nothing
    return status;
  };
}

}  // namespace cairn::cli
