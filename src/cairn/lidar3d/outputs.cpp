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

std::vector<unsigned char> render_top_down(const std::vector<Eigen::Vector3f>& map_points,
                                           const std::vector<OdometryScanResult>& scans,
                                           const std::vector<core::SE3>& ground_truth, int max_side_px) {
  // Extent: the trajectory plus the map within 30 m of it (the map reaches 100 m out and would
  // shrink the trajectory to a few pixels).
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const OdometryScanResult& s : scans) {
    lo = lo.cwiseMin(s.T_world_sensor.translation().head<2>());
    hi = hi.cwiseMax(s.T_world_sensor.translation().head<2>());
  }
  if (scans.empty()) lo = hi = Eigen::Vector2d::Zero();
  lo -= Eigen::Vector2d(30.0, 30.0);
  hi += Eigen::Vector2d(30.0, 30.0);
  const int max_side = std::max(200, max_side_px);
  const double resolution = std::max((hi - lo).maxCoeff() / max_side, 0.05);  // metres per pixel
  const int width = std::max(200, static_cast<int>(std::ceil((hi.x() - lo.x()) / resolution)));
  const int height = std::max(200, static_cast<int>(std::ceil((hi.y() - lo.y()) / resolution)));
  const int legend = 28;
  auto pixel = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d((p.x() - lo.x()) / resolution, static_cast<double>(height) - (p.y() - lo.y()) / resolution);
  };

  viz::CairoSurface surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height + legend));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) throw std::runtime_error("cannot create a picture");
  viz::CairoContext context(cairo_create(surface.get()));
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  // Map points: darker where higher above the trajectory's mean height (walls, trees), light
  // for the ground.
  double z_mean = 0.0;
  for (const OdometryScanResult& s : scans) z_mean += s.T_world_sensor.translation().z();
  if (!scans.empty()) z_mean /= static_cast<double>(scans.size());
  const double dot = std::max(1.0, 0.25 / resolution);
  for (const Eigen::Vector3f& point : map_points) {
    const Eigen::Vector3d p = point.cast<double>();
    if (p.x() < lo.x() || p.y() < lo.y() || p.x() > hi.x() || p.y() > hi.y()) continue;
    const double above_ground = p.z() - (z_mean - 1.7);
    const double shade = std::clamp(0.85 - 0.25 * above_ground, 0.15, 0.88);
    cairo_set_source_rgb(cr, shade, shade, shade);
    const Eigen::Vector2d q = pixel(p);
    cairo_rectangle(cr, q.x(), q.y(), dot, dot);
    cairo_fill(cr);
  }

  // Ground truth, aligned onto the estimate (SE(3) Umeyama), thin grey dashes.
  if (ground_truth.size() == scans.size() && scans.size() >= 3) {
    std::vector<Eigen::Matrix4d> est, gt;
    for (std::size_t i = 0; i < scans.size(); ++i) {
      est.push_back(scans[i].T_world_sensor.matrix());
      gt.push_back(ground_truth[i].matrix());
    }
    eval::AlignmentOptions options;
    options.method = eval::AlignmentMethod::kSE3;
    const eval::Alignment alignment = eval::align(est, gt, options);
    if (alignment.outcome.ok()) {
      const std::vector<Eigen::Matrix4d> aligned = eval::apply_alignment(alignment, gt);
      cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
      cairo_set_line_width(cr, 1.5);
      const double dashes[] = {6.0, 4.0};
      cairo_set_dash(cr, dashes, 2, 0.0);
      for (std::size_t i = 0; i < aligned.size(); ++i) {
        const Eigen::Vector2d q = pixel(aligned[i].block<3, 1>(0, 3));
        if (i == 0) cairo_move_to(cr, q.x(), q.y());
        else cairo_line_to(cr, q.x(), q.y());
      }
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0.0);
    }
  }

  // Trajectory by health; no line across a segment change.
  cairo_set_line_width(cr, 2.5);
  for (std::size_t i = 1; i < scans.size(); ++i) {
    if (scans[i].segment != scans[i - 1].segment) continue;
    const Health h = scans[i].health;
    if (h == Health::kOk) cairo_set_source_rgb(cr, 0.12, 0.35, 0.85);
    else if (h == Health::kDegraded) cairo_set_source_rgb(cr, 0.95, 0.55, 0.05);
    else cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
    const Eigen::Vector2d a = pixel(scans[i - 1].T_world_sensor.translation());
    const Eigen::Vector2d b = pixel(scans[i].T_world_sensor.translation());
    cairo_move_to(cr, a.x(), a.y());
    cairo_line_to(cr, b.x(), b.y());
    cairo_stroke(cr);
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (scans[i].health != Health::kLost) continue;
    cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
    const Eigen::Vector2d q = pixel(scans[i].T_world_sensor.translation());
    cairo_arc(cr, q.x(), q.y(), 4.0, 0.0, 2.0 * M_PI);
    cairo_fill(cr);
  }

  // Legend and scale bar.
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_rectangle(cr, 0, height, width, legend);
  cairo_fill(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 12.0);
  double x = 8.0;
  const double y = height + 18.0;
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
  if (ground_truth.size() == scans.size() && scans.size() >= 3) entry(0.35, 0.35, 0.35, "ground truth (aligned)");
  const double nice[] = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000};
  double bar_m = nice[0];
  for (double candidate : nice) {
    if (candidate / resolution <= 0.2 * width) bar_m = candidate;
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, x, y - 9.0, bar_m / resolution, 4.0);
  cairo_fill(cr);
  cairo_move_to(cr, x + bar_m / resolution + 6.0, y - 3.0);
  cairo_show_text(cr, (std::to_string(static_cast<int>(bar_m)) + " m").c_str());
  const std::string png = viz::encode_png(surface.get());
  return std::vector<unsigned char>(png.begin(), png.end());
}

}  // namespace cairn::lidar3d
