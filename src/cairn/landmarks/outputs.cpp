#include "cairn/viz/cairo_image.hpp"
#include "cairn/landmarks/outputs.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>

#include <cairo.h>
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/core/utf8.hpp"
#include "cairn/filter/chi_square.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::landmarks {
namespace {

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }


}  // namespace

void write_trajectory_tum(const std::string& path, const std::vector<TimedPose>& trajectory) {
  io::Trajectory out;
  for (const TimedPose& p : trajectory) {
    out.stamps.push_back(p.time);
    out.poses.emplace_back(core::SO3::from_rpy(0.0, 0.0, p.pose.z()), Vector3(p.pose.x(), p.pose.y(), 0.0));
  }
  io::write_tum(path, out);
}

void write_landmark_estimates_csv(const std::string& path, const std::vector<LandmarkEstimate>& landmarks) {
  io::write_output(path, [&](std::ostream& out) {
    out << "index,id,x_m,y_m,cov_xx_m2,cov_xy_m2,cov_yy_m2,observations\n";
    for (std::size_t l = 0; l < landmarks.size(); ++l) {
      const LandmarkEstimate& e = landmarks[l];
      std::string line = std::to_string(l) + "," + std::to_string(e.id);
      for (const double v : {e.p_world.x(), e.p_world.y(), e.covariance(0, 0), e.covariance(0, 1), e.covariance(1, 1)}) {
        line += ",";
        io::append_number(line, v);
      }
      line += "," + std::to_string(e.observations) + "\n";
      out << line;
    }
  });
}

std::string report_json(const LandmarkSlamReport& r) {
  nlohmann::json j;
  j["method"] = r.method;
  j["association"] = r.association;
  j["source"] = r.source;
  j["steps"] = r.steps;
  j["steps_in_run"] = r.steps_in_run;
  j["interrupted"] = r.interrupted;
  j["landmarks"] = r.landmarks;
  j["ate"] = {{"rmse_m", number_or_null(r.ate_rmse_m)},
              {"max_m", number_or_null(r.ate_max_m)},
              {"poses", r.ate_poses},
              {"final_position_error_m", number_or_null(r.final_position_error_m)},
              {"final_heading_error_rad", number_or_null(r.final_heading_error_rad)},
              {"alignment", "none (estimate and ground truth share the world frame)"}};
  j["landmark_rmse_m"] = number_or_null(r.landmark_rmse_m);
  const filter::ChiSquareBand pose_band = filter::mean_chi_square_band(3.0, 1, 0.95);
  nlohmann::json nees = nlohmann::json::array();
  for (const NeesPoint& p : r.nees) {
    const filter::ChiSquareBand landmark_band =
        p.landmarks_evaluated > 0 ? filter::mean_chi_square_band(2.0, static_cast<int>(p.landmarks_evaluated), 0.95)
                                  : filter::ChiSquareBand{};
    nees.push_back({{"step", p.step},
                    {"time_s", p.time_s},
                    {"pose_nees", number_or_null(p.pose_nees)},
                    {"landmark_nees_mean", number_or_null(p.landmark_nees_mean)},
                    {"landmarks_evaluated", p.landmarks_evaluated},
                    {"landmark_band_if_independent_95", {landmark_band.lower, landmark_band.upper}}});
  }
  j["nees"] = {{"checkpoints", nees},
               {"pose_band_single_run_95", {pose_band.lower, pose_band.upper}},
               {"mean_pose_nees_all_steps", number_or_null(r.mean_pose_nees_all_steps)},
               {"note",
                "pose NEES is chi^2(3) if consistent; one run gives a wide band, see docs/landmark-slam.md for "
                "Monte-Carlo averages. The landmark band assumes independent landmarks, which they are not."}};
  const AssociationCounts& a = r.association_counts;
  j["associations"] = {{"observations", a.observations},
                       {"spurious_observations", a.spurious_observations},
                       {"rejected_invalid", a.rejected_invalid},
                       {"paired_correct", a.paired_correct},
                       {"paired_wrong", a.paired_wrong},
                       {"spurious_paired", a.spurious_paired},
                       {"spurious_rejected", a.spurious_rejected},
                       {"true_unpaired", a.true_unpaired},
                       {"landmarks_created", a.landmarks_created},
                       {"landmarks_from_spurious", a.landmarks_from_spurious},
                       {"landmarks_duplicated", a.landmarks_duplicated},
                       {"candidates_expired", a.candidates_expired},
                       {"jcbb_nodes", a.jcbb_nodes},
                       {"jcbb_truncated_searches", a.jcbb_truncated_searches}};
  j["ekf"] = {{"predictions", r.ekf_counters.predictions},
              {"updates", r.ekf_counters.updates},
              {"landmarks_added", r.ekf_counters.landmarks_added},
              {"rejected_invalid", r.ekf_counters.rejected_invalid}};
  if (r.method == "graph") {
    const backend::LandmarkGraphSummary& g = r.graph_summary;
    j["graph"] = {{"status", g.status == backend::LandmarkGraphStatus::kConverged       ? "converged"
                             : g.status == backend::LandmarkGraphStatus::kMaxIterations ? "max_iterations"
                                                                                        : "failed"},
                  {"message", g.message},
                  {"solves", r.graph_solves},
                  {"iterations_last_solve", g.iterations},
                  {"initial_cost_last_solve", g.initial_cost},
                  {"final_cost", g.final_cost},
                  {"variables", g.variables},
                  {"factor_nonzeros", g.factor_nonzeros}};
  }
  j["timing_s"] = {{"total", r.total_time_s},
                   {"ekf", r.ekf_time_s},
                   {"ekf_mean_step", r.ekf_mean_step_s},
                   {"ekf_max_step", r.ekf_max_step_s},
                   {"graph_all_solves", r.graph_time_s},
                   {"graph_last_solve_and_marginals", r.graph_final_solve_s}};
  return io::json_text(j);
}

void write_report_json(const std::string& path, const LandmarkSlamReport& report) {
  io::write_output(path, [&](std::ostream& out) { out << report_json(report); });
}

namespace {

/// The picture's frame: the world box over everything drawn (1 m added around it), its scale and
/// the canvas, with the legend's strip below the map.
struct LandmarkCanvas {
  Vector2 low, high;
  double scale = 1.0;
  double margin = 20.0;
  double legend = 60.0;
  int width = 0, height = 0;

  Vector2 to_pixel(const Vector2& p) const { return Vector2(margin + (p.x() - low.x()) * scale, margin + (high.y() - p.y()) * scale); }
};

LandmarkCanvas landmark_canvas(const LandmarkRun& run, const LandmarkSlamResult& result) {
  LandmarkCanvas c;
  c.low = Vector2(1e300, 1e300);
  c.high = Vector2(-1e300, -1e300);
  const auto grow = [&](const Vector2& p) {
    if (!p.allFinite()) return;
    c.low = c.low.cwiseMin(p);
    c.high = c.high.cwiseMax(p);
  };
  for (const TimedPose& p : result.trajectory) grow(p.pose.head<2>());
  for (const TimedPose& p : run.ground_truth) grow(p.pose.head<2>());
  for (const auto& [id, p] : run.true_landmarks) grow(p);
  for (const LandmarkEstimate& l : result.landmarks) grow(l.p_world);
  if (!(c.low.x() <= c.high.x())) {
    c.low = Vector2(-1, -1);
    c.high = Vector2(1, 1);
  }
  c.low -= Vector2(1.0, 1.0);
  c.high += Vector2(1.0, 1.0);
  const Vector2 size = c.high - c.low;
  c.scale = std::min(25.0, 2000.0 / std::max({size.x(), size.y(), 1.0}));
  c.width = static_cast<int>(std::ceil(size.x() * c.scale + 2 * c.margin));
  c.height = static_cast<int>(std::ceil(size.y() * c.scale + 2 * c.margin + c.legend));
  return c;
}

void draw_polyline(cairo_t* cr, const LandmarkCanvas& c, const std::vector<TimedPose>& poses, double r, double g, double b,
                   double line_width) {
  if (poses.empty()) return;
  cairo_set_source_rgb(cr, r, g, b);
  cairo_set_line_width(cr, line_width);
  bool first = true;
  for (const TimedPose& p : poses) {
    const Vector2 q = c.to_pixel(p.pose.head<2>());
    if (first) {
      cairo_move_to(cr, q.x(), q.y());
      first = false;
    } else {
      cairo_line_to(cr, q.x(), q.y());
    }
  }
  cairo_stroke(cr);
}

/// True landmarks: black crosses.
void draw_true_landmarks(cairo_t* cr, const LandmarkCanvas& c, const LandmarkRun& run) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  for (const auto& [id, p] : run.true_landmarks) {
    const Vector2 q = c.to_pixel(p);
    cairo_move_to(cr, q.x() - 4, q.y() - 4);
    cairo_line_to(cr, q.x() + 4, q.y() + 4);
    cairo_move_to(cr, q.x() - 4, q.y() + 4);
    cairo_line_to(cr, q.x() + 4, q.y() - 4);
  }
  cairo_stroke(cr);
}

/// Estimates: green dots with 95% ellipses (radius sqrt(chi2inv(0.95, 2) lambda_i) along the
/// eigenvectors of the 2x2 covariance), magnified 10x when tiny so they stay visible.
void draw_estimates(cairo_t* cr, const LandmarkCanvas& c, const LandmarkSlamResult& result) {
  const double k95 = std::sqrt(filter::chi_square_quantile(0.95, 2.0));
  for (const LandmarkEstimate& l : result.landmarks) {
    const Vector2 q = c.to_pixel(l.p_world);
    if (!q.allFinite()) continue;
    cairo_set_source_rgb(cr, l.id < 0 ? 0.8 : 0.0, 0.6, 0.0);
    cairo_arc(cr, q.x(), q.y(), 2.5, 0, 2 * std::numbers::pi);
    cairo_fill(cr);
    if (!l.covariance.allFinite()) continue;
    const Eigen::SelfAdjointEigenSolver<Matrix2> eigen(l.covariance);
    const Vector2 values = eigen.eigenvalues().cwiseMax(0.0);
    const Vector2 axis = eigen.eigenvectors().col(1);
    cairo_save(cr);
    cairo_translate(cr, q.x(), q.y());
    cairo_rotate(cr, -std::atan2(axis.y(), axis.x()));
    const double a = k95 * std::sqrt(values(1)) * c.scale * 10.0;
    const double b = k95 * std::sqrt(values(0)) * c.scale * 10.0;
    cairo_scale(cr, std::max(a, 0.5), std::max(b, 0.5));
    cairo_arc(cr, 0, 0, 1, 0, 2 * std::numbers::pi);
    cairo_restore(cr);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
  }
}

void draw_legend(cairo_t* cr, const LandmarkCanvas& c, const LandmarkSlamResult& result) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 12);
  const double y0 = c.height - c.legend + 18;
  cairo_move_to(cr, c.margin, y0);
  const std::string line1 = "cairn landmarks --method " + result.report.method + " --association " +
                            result.report.association + ": red estimate, blue ground truth, orange dead reckoning";
  cairo_show_text(cr, core::valid_utf8(line1).c_str());
  cairo_move_to(cr, c.margin, y0 + 18);
  cairo_show_text(cr, "black x true landmarks, green estimates with 95% ellipses magnified 10x; 1 m scale bar:");
  cairo_set_line_width(cr, 2.0);
  cairo_move_to(cr, c.margin, y0 + 30);
  cairo_line_to(cr, c.margin + c.scale, y0 + 30);
  cairo_stroke(cr);
}

}  // namespace

void write_landmarks_png(const std::string& path, const LandmarkRun& run, const LandmarkSlamResult& result) {
  const LandmarkCanvas canvas = landmark_canvas(run, result);
  viz::CairoSurface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, canvas.width, canvas.height));
  viz::CairoContext context(cairo_create(surface.get()));
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  draw_polyline(cr, canvas, run.odometry, 0.95, 0.6, 0.2, 1.0);      // dead reckoning: orange
  draw_polyline(cr, canvas, run.ground_truth, 0.2, 0.35, 0.9, 1.5);  // ground truth: blue
  draw_polyline(cr, canvas, result.trajectory, 0.85, 0.1, 0.1, 1.0); // estimate: red
  draw_true_landmarks(cr, canvas, run);
  draw_estimates(cr, canvas, result);
  draw_legend(cr, canvas, result);
  const std::string png = viz::encode_png(surface.get());
  io::write_output(path, [&](std::ostream& out) { out << png; });
}

}  // namespace cairn::landmarks
