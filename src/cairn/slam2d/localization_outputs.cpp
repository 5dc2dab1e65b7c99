#include "cairn/slam2d/map_picture.hpp"
#include "cairn/eval/report_json.hpp"
#include "cairn/slam2d/localization_outputs.hpp"
#include "cairn/slam2d/config.hpp"
#include "cairn/slam2d/outputs.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <ostream>

#include "cairn/eval/statistics.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::slam2d {
namespace {

}  // namespace

ProbabilityGrid render_saved_map(const SavedMap2D& map, double resolution_m) {
  ProbabilityGridOptions options = map.grid;
  options.resolution_m = resolution_m;
  const ProbabilityGrid bounds_only(options);
  // World-frame bounding box of every submap's observed cells.
  Eigen::Vector2d lower = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d upper = -lower;
  for (const SavedSubmap& submap : map.submaps) {
    int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
    if (!submap.grid.known_bounds(i0, j0, i1, j1)) continue;
    const double r = submap.grid.resolution();
    const Eigen::Vector2d a = submap.grid.origin() + Eigen::Vector2d(i0, j0) * r;
    const Eigen::Vector2d b = submap.grid.origin() + Eigen::Vector2d(i1 + 1, j1 + 1) * r;
    for (const Eigen::Vector2d& corner : {a, b, Eigen::Vector2d(a.x(), b.y()), Eigen::Vector2d(b.x(), a.y())}) {
      const Eigen::Vector2d p = submap.T_world_submap * corner;
      lower = lower.cwiseMin(p);
      upper = upper.cwiseMax(p);
    }
  }
  if (!(lower.array() <= upper.array()).all()) return ProbabilityGrid(options);
  const long offset_i = static_cast<long>(std::floor(lower.x() / resolution_m));
  const long offset_j = static_cast<long>(std::floor(lower.y() / resolution_m));
  const int width = static_cast<int>(std::floor(upper.x() / resolution_m) - static_cast<double>(offset_i)) + 1;
  const int height = static_cast<int>(std::floor(upper.y() / resolution_m) - static_cast<double>(offset_j)) + 1;
  const std::size_t cells = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<double> sum(cells, 0.0);
  std::vector<std::uint8_t> known(cells, 0);
  for (const SavedSubmap& submap : map.submaps) {
    int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
    if (!submap.grid.known_bounds(i0, j0, i1, j1)) continue;
    const ProbabilityGrid& grid = submap.grid;
    const double r = grid.resolution();
    const core::SE2 T_submap_world = submap.T_world_submap.inverse();
    // The submap's box in world cells, then every world cell centre looked up in the submap.
    Eigen::Vector2d box_lower = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d box_upper = -box_lower;
    const Eigen::Vector2d a = grid.origin() + Eigen::Vector2d(i0, j0) * r;
    const Eigen::Vector2d b = grid.origin() + Eigen::Vector2d(i1 + 1, j1 + 1) * r;
    for (const Eigen::Vector2d& corner : {a, b, Eigen::Vector2d(a.x(), b.y()), Eigen::Vector2d(b.x(), a.y())}) {
      const Eigen::Vector2d p = submap.T_world_submap * corner;
      box_lower = box_lower.cwiseMin(p);
      box_upper = box_upper.cwiseMax(p);
    }
    const int wi0 = std::max(0, static_cast<int>(std::floor(box_lower.x() / resolution_m) - static_cast<double>(offset_i)));
    const int wj0 = std::max(0, static_cast<int>(std::floor(box_lower.y() / resolution_m) - static_cast<double>(offset_j)));
    const int wi1 = std::min(width - 1, static_cast<int>(std::floor(box_upper.x() / resolution_m) - static_cast<double>(offset_i)));
    const int wj1 = std::min(height - 1, static_cast<int>(std::floor(box_upper.y() / resolution_m) - static_cast<double>(offset_j)));
    for (int wj = wj0; wj <= wj1; ++wj) {
      for (int wi = wi0; wi <= wi1; ++wi) {
        const Eigen::Vector2d centre_world((static_cast<double>(offset_i + wi) + 0.5) * resolution_m,
                                           (static_cast<double>(offset_j + wj) + 0.5) * resolution_m);
        const Eigen::Vector2d p = T_submap_world * centre_world;
        const int i = static_cast<int>(std::floor(p.x() / r) - static_cast<double>(grid.offset_i()));
        const int j = static_cast<int>(std::floor(p.y() / r) - static_cast<double>(grid.offset_j()));
        if (!grid.cell_known(i, j)) continue;
        const std::size_t k = static_cast<std::size_t>(wj) * static_cast<std::size_t>(width) + static_cast<std::size_t>(wi);
        sum[k] += static_cast<double>(grid.cell_log_odds(i, j));
        known[k] = 1;
      }
    }
  }
  std::vector<float> log_odds(cells, 0.0f);
  for (std::size_t k = 0; k < cells; ++k) {
    if (known[k]) log_odds[k] = static_cast<float>(std::clamp(sum[k], bounds_only.min_log_odds(), bounds_only.max_log_odds()));
  }
  return ProbabilityGrid::from_cells(options, offset_i, offset_j, width, height, std::move(log_odds), std::move(known));
}

void write_localization_png(const ProbabilityGrid& grid, const std::vector<LocalizationResult>& results,
                            const std::string& path) {
  MapPicture picture(grid, path);
  cairo_t* cr = picture.cr();
  auto to_image = [&](const Eigen::Vector2d& p) { return picture.to_image(p); };
  auto colour = [&](Health h) {
    if (h == Health::kOk) cairo_set_source_rgb(cr, 0.12, 0.35, 0.85);
    else cairo_set_source_rgb(cr, 0.95, 0.55, 0.05);
  };
  // The trajectory, broken where there is no pose; a relocalisation starts a new piece.
  cairo_set_line_width(cr, 1.5);
  for (std::size_t k = 1; k < results.size(); ++k) {
    const LocalizationResult& a = results[k - 1];
    const LocalizationResult& b = results[k];
    if (!a.localised || !b.localised || b.relocalised) continue;
    colour(b.health);
    const auto pa = to_image(a.T_map_laser.translation()), pb = to_image(b.T_map_laser.translation());
    cairo_move_to(cr, pa.x(), pa.y());
    cairo_line_to(cr, pb.x(), pb.y());
    cairo_stroke(cr);
  }
  // Relocalisations: a red circle where the pose was found; where it was lost: a red cross.
  cairo_set_line_width(cr, 2.0);
  cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
  for (std::size_t k = 0; k < results.size(); ++k) {
    if (results[k].relocalised) {
      const auto p = to_image(results[k].T_map_laser.translation());
      cairo_new_sub_path(cr);
      cairo_arc(cr, p.x(), p.y(), 6.0, 0.0, 2.0 * std::numbers::pi);
      cairo_stroke(cr);
    } else if (k > 0 && results[k - 1].localised && !results[k].localised) {
      const auto p = to_image(results[k - 1].T_map_laser.translation());
      cairo_move_to(cr, p.x() - 5.0, p.y() - 5.0);
      cairo_line_to(cr, p.x() + 5.0, p.y() + 5.0);
      cairo_move_to(cr, p.x() - 5.0, p.y() + 5.0);
      cairo_line_to(cr, p.x() + 5.0, p.y() - 5.0);
      cairo_stroke(cr);
    }
  }
  // Legend and scale bar.
  picture.legend_swatch(0.12, 0.35, 0.85, "ok");
  picture.legend_swatch(0.95, 0.55, 0.05, "degraded");
  const double x = picture.legend_x(), y = picture.legend_y();
  cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
  cairo_set_line_width(cr, 2.0);
  cairo_new_sub_path(cr);
  cairo_arc(cr, x + 9.0, y - 7.0, 5.0, 0.0, 2.0 * std::numbers::pi);
  cairo_stroke(cr);
  picture.legend_text("(re)localised");
  const double x2 = picture.legend_x();
  cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
  cairo_move_to(cr, x2 + 4.0, y - 12.0);
  cairo_line_to(cr, x2 + 14.0, y - 2.0);
  cairo_move_to(cr, x2 + 4.0, y - 2.0);
  cairo_line_to(cr, x2 + 14.0, y - 12.0);
  cairo_stroke(cr);
  picture.legend_text("lost");
  picture.scale_bar();
  picture.write(path);
}

void write_localization_csv(const std::vector<LocalizationResult>& results, const std::string& path) {
  io::write_output(path, [&](std::ostream& out) {
    out << "time_s,state,health,localised,x_m,y_m,theta_rad,confidence,degeneracy,rms_m,sigma_x_m,sigma_y_m,"
           "sigma_theta_rad,relocalised,dead_reckoning,matching_points,free_space_fraction\n";
    std::string line;
    for (const LocalizationResult& s : results) {
      line = s.time.to_seconds_string();
      line += ',';
      line += to_string(s.state);
      line += ',';
      line += to_string(s.health);
      line += s.localised ? ",1" : ",0";
      // No pose while searching: empty fields, never a guess.
      for (const double v : {s.T_map_laser.x(), s.T_map_laser.y(), s.T_map_laser.angle()}) {
        line += ',';
        if (s.localised) io::append_number(line, v);
      }
      for (const double v : {s.confidence, s.degeneracy, s.rms_m, std::sqrt(std::max(0.0, s.covariance(0, 0))),
                             std::sqrt(std::max(0.0, s.covariance(1, 1))), std::sqrt(std::max(0.0, s.covariance(2, 2)))}) {
        line += ',';
        io::append_number(line, v);
      }
      line += s.relocalised ? ",1" : ",0";
      line += s.dead_reckoning ? ",1," : ",0,";
      line += std::to_string(s.matching_points);
      line += ',';
      io::append_number(line, s.free_space_fraction);
      line += '\n';
      out << line;
    }
  });
}

namespace {
nlohmann::json pose_json(const core::SE2& T) { return nlohmann::json::array({T.x(), T.y(), T.angle()}); }
}  // namespace

nlohmann::json localization_report_json(const Localizer2d& localizer, const Localizer2dOptions& options) {
  const Localizer2dSummary& s = localizer.summary();
  nlohmann::json report;
  report["summary"] = {{"scans", s.scans},
                       {"scans_localised", s.scans_localised},
                       {"first_localised_scan", s.first_localised_scan ? nlohmann::json(*s.first_localised_scan) : nlohmann::json()},
                       {"scans_ok", s.scans_ok},
                       {"scans_degraded", s.scans_degraded},
                       {"scans_lost", s.scans_lost},
                       {"relocalisations", s.relocalisations.size()},
                       {"global_searches", s.global_searches},
                       {"rankings", s.rankings},
                       {"confirmation_searches", s.confirmation_searches},
                       {"verified_matches", s.verified_matches},
                       {"rejected_matches", s.rejected_matches},
                       {"hypotheses", s.hypotheses},
                       {"hypotheses_dropped", s.hypotheses_dropped},
                       {"hypotheses_ignored", s.hypotheses_ignored},
                       {"scans_ambiguous", s.scans_ambiguous},
                       {"uniqueness_tests", s.uniqueness_tests},
                       {"look_alikes", s.look_alikes},
                       {"refused_empty_space_elsewhere", s.refused_empty_space_elsewhere},
                       {"partly_mapped_look_alikes", s.partly_mapped_look_alikes},
                       {"tracking_checks", s.tracking_checks},
                       {"tracking_checks_agreeing", s.tracking_checks_agreeing},
                       {"rivals_refuted", s.rivals_refuted},
                       {"tracking_failures", s.tracking_failures},
                       {"tracking_contradicted", s.tracking_contradicted},
                       {"final_state", std::string(to_string(localizer.state()))}};
  report["summary"]["rejected_by_reason"] = s.rejected_by_reason;
  report["map"] = {{"source", localizer.map().source},
                   {"submaps", localizer.map().submaps.size()},
                   {"searchable_submaps", s.map_submaps},
                   {"keyframes", localizer.map().keyframes.size()},
                   {"tracking_points", s.map_points},
                   {"precomputation_bytes", s.precomputation_bytes},
                   {"grid_resolution_m", localizer.map().grid.resolution_m}};
  report["time_s"] = {{"setup", s.times.setup_s},
                      {"preprocess", s.times.preprocess_s},
                      {"tracking", s.times.tracking_s},
                      {"global_search", s.times.global_search_s},
                      {"ranking", s.times.ranking_s},
                      {"confirmation_search", s.times.confirmation_search_s},
                      {"localisation_total", s.total_s},
                      {"slowest_scan", s.max_scan_s},
                      {"slowest_global_search", s.max_global_search_s}};
  report["options"] = localization_config_json(options);
  nlohmann::json relocalisations = nlohmann::json::array();
  for (const Relocalisation& r : s.relocalisations) {
    nlohmann::json evidence = nlohmann::json::array();
    for (const LocalizationMatch& e : r.evidence) {
      evidence.push_back({{"scan", e.scan},
                          {"time", e.time.to_seconds_string()},
                          {"submap", e.submap},
                          {"search", e.global ? "global" : "confirmation"},
                          {"score", e.score},
                          {"second_score", e.second_score},
                          {"inlier_fraction", e.inlier_fraction},
                          {"rms_m", e.rms_m},
                          {"degeneracy", e.degeneracy},
                          {"free_space_fraction", e.free_space_fraction},
                          {"T_map_laser", pose_json(e.T_map_laser)}});
    }
    relocalisations.push_back({{"scan", r.scan},
                               {"time", r.time.to_seconds_string()},
                               {"T_map_laser", pose_json(r.T_map_laser)},
                               {"searching_since_scan", r.searching_since_scan},
                               {"scans_searched", r.scan - r.searching_since_scan + 1},
                               {"had_prior", r.had_prior},
                               {"rival_hypotheses_died", r.rival_hypotheses},
                               {"evidence", evidence}});
  }
  report["relocalisations"] = relocalisations;
  report["health_events"] = health_events_json(s.health_events);
  return report;
}

namespace {

core::SE3 to_se3(const core::SE2& T) {
  return core::SE3(core::SO3::from_rpy(0.0, 0.0, T.angle()), Eigen::Vector3d(T.x(), T.y(), 0.0));
}

/// eval's statistics of `errors` (evo's definitions, as `cairn eval` reports them), null when there are none.
nlohmann::json statistics_json(const std::vector<double>& errors) {
  if (errors.empty()) return nlohmann::json();
  return eval::statistics_json(eval::compute_statistics(errors));
}

}  // namespace

io::Trajectory localized_trajectory(const std::vector<LocalizationResult>& results) {
  std::vector<const LocalizationResult*> localised;
  for (const auto& r : results)
    if (r.localised) localised.push_back(&r);
  std::stable_sort(localised.begin(), localised.end(), [](const auto* a, const auto* b) { return a->time < b->time; });
  io::Trajectory trajectory;
  for (const auto* r : localised) {
    if (!trajectory.stamps.empty() && !(trajectory.stamps.back() < r->time)) continue;
    trajectory.stamps.push_back(r->time);
    trajectory.poses.push_back(to_se3(r->T_map_laser));
  }
  return trajectory;
}

LocalizationTruthErrors compare_with_ground_truth(const io::Trajectory& truth,
                                                  const std::vector<LocalizationResult>& results) {
  LocalizationTruthErrors e;
  for (const LocalizationResult& r : results) {
    if (!r.localised) continue;
    const std::size_t after = static_cast<std::size_t>(
        std::lower_bound(truth.stamps.begin(), truth.stamps.end(), r.time) - truth.stamps.begin());
    std::size_t best = truth.stamps.size();
    double best_dt = 0.05;
    for (const std::size_t candidate : {after - 1, after}) {  // after - 1 wraps when after == 0
      if (candidate >= truth.stamps.size()) continue;
      const double dt = std::abs(truth.stamps[candidate].seconds() - r.time.seconds());
      if (dt <= best_dt) {
        best_dt = dt;
        best = candidate;
      }
    }
    if (best == truth.stamps.size()) {
      ++e.unmatched;
      continue;
    }
    const core::SE3 error = to_se3(r.T_map_laser).inverse() * truth.poses[best];
    const double t = error.translation().head<2>().norm();
    const double angle_deg =
        std::abs(std::atan2(error.rotation_matrix()(1, 0), error.rotation_matrix()(0, 0))) * 180.0 / std::numbers::pi;
    e.translation_m.push_back(t);
    e.rotation_deg.push_back(angle_deg);
    if (r.health == Health::kOk) e.translation_ok_m.push_back(t);
    if (r.relocalised) {
      ++e.relocalisations_compared;
      if (t > 0.3 || angle_deg > 3.0) ++e.wrong_relocalisations;
    }
  }
  return e;
}

nlohmann::json ground_truth_json(const std::string& path, const LocalizationTruthErrors& e) {
  return {{"file", path},
          {"frame", "the map's (no alignment)"},
          {"scans_compared", e.translation_m.size()},
          {"localised_scans_without_ground_truth", e.unmatched},
          {"translation_error_m", statistics_json(e.translation_m)},
          {"translation_error_ok_scans_m", statistics_json(e.translation_ok_m)},
          {"rotation_error_deg", statistics_json(e.rotation_deg)},
          {"relocalisations_compared", e.relocalisations_compared},
          {"relocalisations_off_by_more_than_0.3_m_or_3_deg", e.wrong_relocalisations}};
}

}  // namespace cairn::slam2d
