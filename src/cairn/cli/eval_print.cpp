// Terminal tables of `cairn eval` (see eval_print.hpp).

#include "cairn/cli/eval_print.hpp"

#include <cstdio>
#include <iostream>
#include <numbers>
#include <string>
#include <string_view>

#include "cairn/core/se3.hpp"
#include "cairn/eval/pose_relation.hpp"
#include "cairn/eval/statistics.hpp"

namespace cairn::cli {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

std::string number(double v, int significant = 9) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, v);
  return buffer;
}

void print_row(const std::string& name, const std::string& value) {
  std::cout << "  " << name << std::string(name.size() < 14 ? 14 - name.size() : 1, ' ') << value << '\n';
}

void print_header(const std::string& what, const EvalFlags& f, const char* reference_name = "reference") {
  std::cout << what << '\n';
  print_row(reference_name, f.reference);
  print_row("estimate", f.estimate);
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

std::string describe_pairs(const eval::Association& a) {
  return std::to_string(a.size()) + " of " + std::to_string(a.max_pairs) +
         (a.by_time ? " poses associated by time" : " poses paired by index");
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

void print_mean_std(const std::string& name, const eval::MeanStd& m, const std::string& unit) {
  print_row(name, number(m.mean, 6) + " +- " + number(m.std, 6) + " " + unit + "  (min " + number(m.min, 6) +
                      ", max " + number(m.max, 6) + ")");
}

}  // namespace

void print_ape_table(const eval::ApeResult& r, const EvalFlags& f) {
  print_header("APE w.r.t. " + std::string(eval::describe(r.relation)), f);
  print_row("pairs", describe_pairs(r.association));
  print_alignment(r.alignment);
  print_statistics(r.statistics, eval::unit_of(r.relation));
}

void print_rpe_table(const eval::RpeResult& r, const eval::RpeOptions& options, const EvalFlags& f) {
  const bool metres = options.delta_unit == eval::DeltaUnit::kMeters;
  const std::string delta = number(options.delta, 6) + (metres ? " m" : " frames");
  print_header("RPE w.r.t. " + std::string(eval::describe(r.relation)) + ", delta " + delta + ", " +
                   (options.all_pairs ? "all pairs" : "consecutive pairs"),
               f);
  print_row("pairs", describe_pairs(r.association) + "; " + std::to_string(r.pairs.size()) + " RPE pairs");
  print_alignment(r.alignment);
  print_statistics(r.statistics, eval::unit_of(r.relation));
}

void print_kitti_table(const eval::KittiResult& r, const EvalFlags& f) {
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
}

void print_relations_table(const eval::RelationsResult& r, std::size_t relation_count, const EvalFlags& f) {
  print_header("Relations metric (Kuemmerle et al. 2009), " + std::to_string(relation_count) + " relations", f,
               "relations");
  print_mean_std("trans abs", r.translation_absolute_m, "m");
  print_mean_std("trans sq", r.translation_squared_m2, "m^2");
  print_mean_std("rot abs", r.rotation_absolute_deg, "deg");
  print_mean_std("rot sq", r.rotation_squared_deg2, "deg^2");
}

}  // namespace cairn::cli
