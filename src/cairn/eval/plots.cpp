#include "cairn/eval/plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <numbers>

#include "cairn/viz/color.hpp"

namespace cairn::eval {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// printf's %g with `significant` digits: the numbers in titles and legends.
std::string number(double v, int significant) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, v);
  return buffer;
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

}  // namespace

std::pair<int, int> plane_axes(std::string_view plane, const std::vector<Matrix4>& reference) {
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

viz::Figure top_view(const std::string& title, const std::vector<Matrix4>& reference,
                     const std::vector<Matrix4>& estimate, const std::vector<double>& values,
                     const std::string& color_label, std::string_view plane, const viz::Series* points) {
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

viz::Figure error_plot(const std::string& title, const std::vector<double>& x, const std::vector<double>& errors,
                       const std::string& x_label, const std::string& y_label, const Statistics& statistics,
                       const std::string& unit) {
  const Statistics& s = statistics;
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

std::vector<double> path_length(const std::vector<Matrix4>& poses) {
  std::vector<double> d(poses.size(), 0.0);
  for (std::size_t i = 1; i < poses.size(); ++i) {
    d[i] = d[i - 1] + (poses[i].block<3, 1>(0, 3) - poses[i - 1].block<3, 1>(0, 3)).norm();
  }
  return d;
}

std::string relation_label(PoseRelation relation) {
  const std::string_view unit = unit_of(relation);
  return std::string(describe(relation)) + (unit.empty() ? "" : " [" + std::string(unit) + "]");
}

std::vector<NamedFigure> ape_figures(const ApeResult& result, std::string_view plane) {
  const ApeResult& r = result;
  const std::string label = "APE, " + relation_label(r.relation);
  std::vector<NamedFigure> figures;
  figures.push_back({"top", top_view("APE (" + std::string(to_string(r.alignment.method)) + " alignment): " + "rmse " +
                                         number(r.statistics.rmse, 4) + " " + std::string(unit_of(r.relation)),
                                     r.reference, r.estimate, r.errors, label, plane)});
  figures.push_back({"error", error_plot(r.association.by_time ? "APE over time" : "APE per pose", r.time_s, r.errors,
                                         r.association.by_time ? "time since the first pair [s]" : "pose index", label,
                                         r.statistics, std::string(unit_of(r.relation)))});
  return figures;
}

std::vector<NamedFigure> rpe_figures(const RpeResult& result, const RpeOptions& options, std::string_view plane) {
  const RpeResult& r = result;
  const bool metres = options.delta_unit == DeltaUnit::kMeters;
  const std::string delta = number(options.delta, 6) + (metres ? " m" : " frames");
  const std::string label = "RPE, " + relation_label(r.relation);
  // x of each pair: distance along the reference (metres) or time of its first pose.
  const std::vector<double> distance = path_length(r.reference);
  std::vector<double> x;
  viz::Series starts;
  starts.style = viz::SeriesStyle::kPoints;
  starts.width_px = 5;
  starts.label = "pair start (colour: error)";
  const auto axes = plane_axes(plane, r.reference);
  for (std::size_t k = 0; k < r.pairs.size(); ++k) {
    const std::size_t i = r.pairs[k].first;
    x.push_back(metres ? distance[i] : r.time_s[i]);
    starts.x.push_back(r.estimate[i](axes.first, 3));
    starts.y.push_back(r.estimate[i](axes.second, 3));
    starts.values.push_back(r.errors[k]);
  }
  std::vector<NamedFigure> figures;
  // "--align" is the flag of `cairn eval rpe`: the title has always named it.
  figures.push_back({"top", top_view("RPE over " + delta + " (not aligned unless --align): rmse " +
                                         number(r.statistics.rmse, 4) + " " + std::string(unit_of(r.relation)),
                                     r.reference, r.estimate, {}, label, plane, &starts)});
  const std::string x_label = metres ? "distance travelled along the reference [m]"
                                     : (r.association.by_time ? "time since the first pair [s]" : "pose index");
  figures.push_back({"error", error_plot("RPE over " + delta, x, r.errors, x_label, label, r.statistics,
                                         std::string(unit_of(r.relation)))});
  return figures;
}

std::vector<NamedFigure> kitti_figures(const KittiResult& result, std::string_view plane) {
  const KittiResult& r = result;
  viz::Axes t;
  viz::Axes rot;
  t.title = "translation error: " + number(r.translation_error_percent(), 4) + " % overall";
  rot.title = "rotation error: " + number(r.rotation_error_deg_per_100m(), 4) + " deg/100 m overall";
  t.x_label = rot.x_label = "segment length [m]";
  t.y_label = "t_err [%]";
  rot.y_label = "r_err [deg/100 m]";
  viz::BarSet tb{"", {}, viz::categorical(0)};
  viz::BarSet rb{"", {}, viz::categorical(1)};
  for (const KittiLengthError& e : r.per_length) {
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
  std::vector<NamedFigure> figures;
  figures.push_back({"segments", bars});
  figures.push_back({"top", top_view("KITTI: t_err " + number(r.translation_error_percent(), 4) + " %", r.reference,
                                     r.estimate, {}, "", plane)});
  return figures;
}

std::vector<NamedFigure> relations_figures(const RelationsResult& result, const std::vector<Relation>& relations) {
  const RelationsResult& r = result;
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
  std::vector<NamedFigure> figures;
  figures.push_back({"error", errors});
  return figures;
}

}  // namespace cairn::eval
