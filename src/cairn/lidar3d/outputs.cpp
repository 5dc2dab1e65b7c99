#include "cairn/viz/cairo_image.hpp"
#include "cairn/lidar3d/outputs.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "cairn/core/utf8.hpp"
#include "cairn/eval/alignment.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/rpe.hpp"

namespace cairn::lidar3d {
namespace {

eval::MatrixTrajectory relative_to_first(const std::vector<core::SE3>& poses) {
  eval::MatrixTrajectory out;
  const core::SE3 T_first_world = poses.front().inverse();
  for (const core::SE3& T : poses) out.poses.push_back((T_first_world * T).matrix());
  return out;
}

}  // namespace

GlobalMap::GlobalMap(double voxel_size_m) : voxel_size_m_(voxel_size_m), inverse_(1.0 / voxel_size_m) {
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m)) throw std::invalid_argument("map voxel size must be > 0");
}

void GlobalMap::add_scan(const std::vector<Eigen::Vector3d>& points_sensor, const core::SE3& T_world_sensor) {
  const Eigen::Matrix3d R = T_world_sensor.rotation_matrix();
  const Eigen::Vector3d t = T_world_sensor.translation();
  for (const Eigen::Vector3d& p_sensor : points_sensor) {
    const Eigen::Vector3d p = R * p_sensor + t;
    if (voxels_.try_emplace(voxel_of(p, inverse_), points_.size()).second) points_.push_back(p.cast<float>());
  }
}

std::vector<Eigen::Vector3f> GlobalMap::points() const { return points_; }

std::vector<Eigen::Vector3f> GlobalMap::remove(const std::vector<bool>& flags) {
  if (flags.size() != points_.size()) throw std::invalid_argument("GlobalMap::remove: one flag per point expected");
  std::vector<Eigen::Vector3f> kept, removed;
  for (std::size_t i = 0; i < points_.size(); ++i) (flags[i] ? removed : kept).push_back(points_[i]);
  points_ = std::move(kept);
  return removed;
}

TrajectoryErrors evaluate_trajectory(const std::vector<core::SE3>& ground_truth, const std::vector<core::SE3>& estimate) {
  if (ground_truth.size() != estimate.size()) {
    throw std::invalid_argument("the ground truth has " + std::to_string(ground_truth.size()) + " poses for " +
                                std::to_string(estimate.size()) + " scans");
  }
  if (ground_truth.size() < 2) throw std::invalid_argument("at least 2 poses are needed for trajectory errors");
  TrajectoryErrors e;
  e.poses = ground_truth.size();
  const eval::MatrixTrajectory gt = relative_to_first(ground_truth);
  const eval::MatrixTrajectory est = relative_to_first(estimate);
  for (std::size_t i = 1; i < gt.poses.size(); ++i) {
    e.path_length_m += (gt.poses[i].block<3, 1>(0, 3) - gt.poses[i - 1].block<3, 1>(0, 3)).norm();
  }
  e.end_point_error_m = (gt.poses.back().block<3, 1>(0, 3) - est.poses.back().block<3, 1>(0, 3)).norm();
  e.end_point_error_percent = e.path_length_m > 0.0 ? 100.0 * e.end_point_error_m / e.path_length_m : 0.0;

  eval::RpeOptions rpe;
  rpe.relation = eval::PoseRelation::kTranslationPart;
  const eval::RpeResult rpe_t = eval::evaluate_rpe(gt, est, rpe);
  if (!rpe_t.outcome.ok()) throw std::runtime_error("RPE: " + rpe_t.outcome.message);
  rpe.relation = eval::PoseRelation::kRotationAngleDeg;
  const eval::RpeResult rpe_r = eval::evaluate_rpe(gt, est, rpe);
  if (!rpe_r.outcome.ok()) throw std::runtime_error("RPE: " + rpe_r.outcome.message);
  e.rpe_translation_rmse_m = rpe_t.statistics.rmse;
  e.rpe_rotation_rmse_deg = rpe_r.statistics.rmse;

  eval::ApeOptions ape;
  ape.alignment.method = eval::AlignmentMethod::kSE3;
  const eval::ApeResult ate = eval::evaluate_ape(gt, est, ape);
  if (ate.outcome.ok()) {
    e.ate_rmse_m = ate.statistics.rmse;
  } else {
    e.ate_note = ate.outcome.message;
  }

  const eval::KittiResult kitti = eval::evaluate_kitti(gt, est);
  if (kitti.outcome.ok() && !kitti.segments.empty()) {
    e.kitti_translation_percent = kitti.translation_error_percent();
    e.kitti_rotation_deg_per_100m = kitti.rotation_error_deg_per_100m();
  }
  return e;
}

namespace {

// The picture's frame: the trajectory plus the map within 30 m of it (the map reaches 100 m out
// and would shrink the trajectory to a few pixels), metres per pixel, and the legend strip below.
struct TopDownFrame {
  Eigen::Vector2d lo, hi;
  double resolution = 0.05;  // metres per pixel
  int width = 200, height = 200;
  static constexpr int kLegend = 28;
  Eigen::Vector2d pixel(const Eigen::Vector3d& p) const {
    return Eigen::Vector2d((p.x() - lo.x()) / resolution, static_cast<double>(height) - (p.y() - lo.y()) / resolution);
  }
};

TopDownFrame top_down_frame(const std::vector<OdometryScanResult>& scans, int max_side_px) {
  TopDownFrame f;
  f.lo = Eigen::Vector2d(1e300, 1e300);
  f.hi = Eigen::Vector2d(-1e300, -1e300);
  for (const OdometryScanResult& s : scans) {
    f.lo = f.lo.cwiseMin(s.T_world_sensor.translation().head<2>());
    f.hi = f.hi.cwiseMax(s.T_world_sensor.translation().head<2>());
  }
  if (scans.empty()) f.lo = f.hi = Eigen::Vector2d::Zero();
  f.lo -= Eigen::Vector2d(30.0, 30.0);
  f.hi += Eigen::Vector2d(30.0, 30.0);
  const int max_side = std::max(200, max_side_px);
  f.resolution = std::max((f.hi - f.lo).maxCoeff() / max_side, 0.05);
  f.width = std::max(200, static_cast<int>(std::ceil((f.hi.x() - f.lo.x()) / f.resolution)));
  f.height = std::max(200, static_cast<int>(std::ceil((f.hi.y() - f.lo.y()) / f.resolution)));
  return f;
}

// Map points: darker where higher above the trajectory's mean height (walls, trees), light for
// the ground.
void draw_map_points(cairo_t* cr, const TopDownFrame& f, const std::vector<Eigen::Vector3f>& map_points,
                     const std::vector<OdometryScanResult>& scans) {
  double z_mean = 0.0;
  for (const OdometryScanResult& s : scans) z_mean += s.T_world_sensor.translation().z();
  if (!scans.empty()) z_mean /= static_cast<double>(scans.size());
  const double dot = std::max(1.0, 0.25 / f.resolution);
  for (const Eigen::Vector3f& point : map_points) {
    const Eigen::Vector3d p = point.cast<double>();
    if (p.x() < f.lo.x() || p.y() < f.lo.y() || p.x() > f.hi.x() || p.y() > f.hi.y()) continue;
    const double above_ground = p.z() - (z_mean - 1.7);
    const double shade = std::clamp(0.85 - 0.25 * above_ground, 0.15, 0.88);
    cairo_set_source_rgb(cr, shade, shade, shade);
    const Eigen::Vector2d q = f.pixel(p);
    cairo_rectangle(cr, q.x(), q.y(), dot, dot);
    cairo_fill(cr);
  }
}

// Ground truth, aligned onto the estimate (SE(3) Umeyama), thin grey dashes; nothing when it
// cannot be aligned.
void draw_ground_truth(cairo_t* cr, const TopDownFrame& f, const std::vector<OdometryScanResult>& scans,
                       const std::vector<core::SE3>& ground_truth) {
  std::vector<Eigen::Matrix4d> est, gt;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    est.push_back(scans[i].T_world_sensor.matrix());
    gt.push_back(ground_truth[i].matrix());
  }
  eval::AlignmentOptions options;
  options.method = eval::AlignmentMethod::kSE3;
  const eval::Alignment alignment = eval::align(est, gt, options);
  if (!alignment.outcome.ok()) return;
  const std::vector<Eigen::Matrix4d> aligned = eval::apply_alignment(alignment, gt);
  cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
  cairo_set_line_width(cr, 1.5);
  const double dashes[] = {6.0, 4.0};
  cairo_set_dash(cr, dashes, 2, 0.0);
  for (std::size_t i = 0; i < aligned.size(); ++i) {
    const Eigen::Vector2d q = f.pixel(aligned[i].block<3, 1>(0, 3));
    if (i == 0) cairo_move_to(cr, q.x(), q.y());
    else cairo_line_to(cr, q.x(), q.y());
  }
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0.0);
}

// Trajectory by health; no line across a segment change; a red dot at every lost scan.
void draw_trajectory(cairo_t* cr, const TopDownFrame& f, const std::vector<OdometryScanResult>& scans) {
  cairo_set_line_width(cr, 2.5);
  for (std::size_t i = 1; i < scans.size(); ++i) {
    if (scans[i].segment != scans[i - 1].segment) continue;
    const Health h = scans[i].health;
    if (h == Health::kOk) cairo_set_source_rgb(cr, 0.12, 0.35, 0.85);
    else if (h == Health::kDegraded) cairo_set_source_rgb(cr, 0.95, 0.55, 0.05);
    else cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
    const Eigen::Vector2d a = f.pixel(scans[i - 1].T_world_sensor.translation());
    const Eigen::Vector2d b = f.pixel(scans[i].T_world_sensor.translation());
    cairo_move_to(cr, a.x(), a.y());
    cairo_line_to(cr, b.x(), b.y());
    cairo_stroke(cr);
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (scans[i].health != Health::kLost) continue;
    cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
    const Eigen::Vector2d q = f.pixel(scans[i].T_world_sensor.translation());
    cairo_arc(cr, q.x(), q.y(), 4.0, 0.0, 2.0 * M_PI);
    cairo_fill(cr);
  }
}

// Legend and scale bar in the strip below the map.
void draw_legend(cairo_t* cr, const TopDownFrame& f, bool with_ground_truth) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_rectangle(cr, 0, f.height, f.width, TopDownFrame::kLegend);
  cairo_fill(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 12.0);
  double x = 8.0;
  const double y = f.height + 18.0;
  auto entry = [&](double red, double green, double blue, const char* text) {
    cairo_set_source_rgb(cr, red, green, blue);
    cairo_rectangle(cr, x, y - 9.0, 18.0, 4.0);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x + 22.0, y - 3.0);
    cairo_show_text(cr, core::valid_utf8(text).c_str());
    cairo_text_extents_t extents;
    cairo_text_extents(cr, text, &extents);
    x += 22.0 + extents.x_advance + 14.0;
  };
  entry(0.12, 0.35, 0.85, "ok");
  entry(0.95, 0.55, 0.05, "degraded");
  entry(0.9, 0.1, 0.1, "lost (new map segment)");
  if (with_ground_truth) entry(0.35, 0.35, 0.35, "ground truth (aligned)");
  const double nice[] = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000};
  double bar_m = nice[0];
  for (double candidate : nice) {
    if (candidate / f.resolution <= 0.2 * f.width) bar_m = candidate;
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, x, y - 9.0, bar_m / f.resolution, 4.0);
  cairo_fill(cr);
  cairo_move_to(cr, x + bar_m / f.resolution + 6.0, y - 3.0);
  cairo_show_text(cr, (std::to_string(static_cast<int>(bar_m)) + " m").c_str());
}

}  // namespace

std::vector<unsigned char> render_top_down(const std::vector<Eigen::Vector3f>& map_points,
                                           const std::vector<OdometryScanResult>& scans,
                                           const std::vector<core::SE3>& ground_truth, int max_side_px) {
  const TopDownFrame frame = top_down_frame(scans, max_side_px);
  viz::CairoSurface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, frame.width, frame.height + TopDownFrame::kLegend));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) throw std::runtime_error("cannot create a picture");
  viz::CairoContext context(cairo_create(surface.get()));
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  draw_map_points(cr, frame, map_points, scans);
  const bool with_ground_truth = ground_truth.size() == scans.size() && scans.size() >= 3;
  if (with_ground_truth) draw_ground_truth(cr, frame, scans, ground_truth);
  draw_trajectory(cr, frame, scans);
  draw_legend(cr, frame, with_ground_truth);
  const std::string png = viz::encode_png(surface.get());
  return std::vector<unsigned char>(png.begin(), png.end());
}

}  // namespace cairn::lidar3d
