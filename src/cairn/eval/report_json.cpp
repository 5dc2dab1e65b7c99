#include "cairn/eval/report_json.hpp"

#include <cstddef>

namespace cairn::eval {

nlohmann::json statistics_json(const Statistics& statistics) {
  const Statistics& s = statistics;
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"sse", s.sse},       {"count", s.count}};
}

nlohmann::json association_json(const Association& association, const AssociationOptions& options) {
  return {{"pairs", association.size()},
          {"max_pairs", association.max_pairs},
          {"by_time", association.by_time},
          {"max_time_difference_s", options.max_time_difference_s},
          {"offset_s", options.offset_s}};
}

nlohmann::json alignment_json(const Alignment& alignment) {
  const Alignment& a = alignment;
  nlohmann::json R = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) R.push_back({a.R(r, 0), a.R(r, 1), a.R(r, 2)});
  return {{"method", to_string(a.method)},
          {"pairs_used", a.pairs_used},
          {"R", R},
          {"t", {a.t.x(), a.t.y(), a.t.z()}},
          {"scale", a.scale}};
}

nlohmann::json mean_std_json(const MeanStd& mean_std) {
  const MeanStd& m = mean_std;
  return {{"mean", m.mean}, {"std", m.std}, {"min", m.min}, {"max", m.max}};
}

nlohmann::json ape_json(const ApeResult& result, const ApeOptions& options, std::string_view reference_name,
                        std::string_view estimate_name) {
  const ApeResult& r = result;
  return {{"metric", "ape"},
          {"reference", reference_name},
          {"estimate", estimate_name},
          {"relation", to_string(r.relation)},
          {"unit", unit_of(r.relation)},
          {"association", association_json(r.association, options.association)},
          {"alignment", alignment_json(r.alignment)},
          {"statistics", statistics_json(r.statistics)},
          {"time_s", r.time_s},
          {"errors", r.errors}};
}

nlohmann::json rpe_json(const RpeResult& result, const RpeOptions& options, std::string_view reference_name,
                        std::string_view estimate_name) {
  const RpeResult& r = result;
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& [i, j] : r.pairs) pairs.push_back({i, j});
  return {{"metric", "rpe"},
          {"reference", reference_name},
          {"estimate", estimate_name},
          {"relation", to_string(r.relation)},
          {"unit", unit_of(r.relation)},
          {"delta", options.delta},
          {"delta_unit", to_string(options.delta_unit)},
          {"all_pairs", options.all_pairs},
          {"association", association_json(r.association, options.association)},
          {"alignment", alignment_json(r.alignment)},
          {"statistics", statistics_json(r.statistics)},
          {"pairs", pairs},
          {"errors", r.errors}};
}

nlohmann::json kitti_json(const KittiResult& result, const KittiOptions& options, std::string_view reference_name,
                          std::string_view estimate_name) {
  const KittiResult& r = result;
  nlohmann::json lengths = nlohmann::json::array();
  for (const KittiLengthError& e : r.per_length) {
    lengths.push_back({{"length_m", e.length_m},
                       {"segments", e.segments},
                       {"t_err_m_per_m", e.translation_error_m_per_m},
                       {"r_err_rad_per_m", e.rotation_error_rad_per_m},
                       {"reported_by_devkit", e.reported_by_devkit}});
  }
  return {{"metric", "kitti"},
          {"reference", reference_name},
          {"estimate", estimate_name},
          {"association", association_json(r.association, options.association)},
          {"segments", r.segments.size()},
          {"t_err_m_per_m", r.translation_error_m_per_m},
          {"r_err_rad_per_m", r.rotation_error_rad_per_m},
          {"t_err_percent", r.translation_error_percent()},
          {"r_err_deg_per_100m", r.rotation_error_deg_per_100m()},
          {"per_length", lengths}};
}

nlohmann::json relations_json(const RelationsResult& result, const std::vector<Relation>& relations,
                              const RelationsOptions& options, std::string_view relations_name,
                              std::string_view estimate_name) {
  const RelationsResult& r = result;
  nlohmann::json per = nlohmann::json::array();
  for (std::size_t k = 0; k < relations.size(); ++k) {
    per.push_back({{"line", relations[k].line},
                   {"t_i", relations[k].from.to_seconds_string()},
                   {"t_j", relations[k].to.to_seconds_string()},
                   {"translation_error_m", r.translation_errors_m[k]},
                   {"rotation_error_rad", r.rotation_errors_rad[k]}});
  }
  return {{"metric", "relations"},
          {"relations", relations_name},
          {"estimate", estimate_name},
          {"max_time_difference_s", options.max_time_difference_s},
          {"count", relations.size()},
          {"translation_absolute_m", mean_std_json(r.translation_absolute_m)},
          {"translation_squared_m2", mean_std_json(r.translation_squared_m2)},
          {"rotation_absolute_deg", mean_std_json(r.rotation_absolute_deg)},
          {"rotation_squared_deg2", mean_std_json(r.rotation_squared_deg2)},
          {"per_relation", per}};
}

}  // namespace cairn::eval
