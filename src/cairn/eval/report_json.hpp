#pragma once
/// \file
/// The JSON form of every metric's result, as `cairn eval --json` writes it and as every
/// pipeline that reports errors against ground truth can reuse it: the parts (statistics,
/// association, alignment, mean and standard deviation) and one whole object per metric
/// (APE, RPE, KITTI, relations). Objects only: turning them into text is io::json_text's job.
///
/// Units are in the key names (`t_err_m_per_m`, `max_time_difference_s`) or, for the per-pair
/// errors of APE and RPE, in the object's "unit" (that of the pose relation: m, rad, deg or
/// none).

#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "cairn/eval/alignment.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/eval/statistics.hpp"

namespace cairn::eval {

/// {rmse, mean, median, std, min, max, sse, count}, in the errors' unit (sse in its square).
nlohmann::json statistics_json(const Statistics& statistics);

/// {pairs, max_pairs, by_time, max_time_difference_s, offset_s}: how many poses paired and
/// under which options.
nlohmann::json association_json(const Association& association, const AssociationOptions& options);

/// {method, pairs_used, R (3 rows), t, scale}: p_reference = scale R p_estimate + t.
nlohmann::json alignment_json(const Alignment& alignment);

/// {mean, std, min, max}.
nlohmann::json mean_std_json(const MeanStd& mean_std);

/// The whole APE report: metric "ape", the two input names, relation and unit, association,
/// alignment, statistics, and per pair its time (time_s) and error (errors).
/// Precondition: result.outcome.ok().
nlohmann::json ape_json(const ApeResult& result, const ApeOptions& options, std::string_view reference_name,
                        std::string_view estimate_name);

/// The whole RPE report: as APE's, plus delta, delta_unit and all_pairs, the index pairs into
/// the paired poses (pairs) and one error per pair (errors); no times.
/// Precondition: result.outcome.ok().
nlohmann::json rpe_json(const RpeResult& result, const RpeOptions& options, std::string_view reference_name,
                        std::string_view estimate_name);

/// The whole KITTI report: metric "kitti", the two input names, association, the number of
/// segments, t_err / r_err overall (m/m, rad/m, %, deg/100 m) and per nominal length.
/// Precondition: result.outcome.ok().
nlohmann::json kitti_json(const KittiResult& result, const KittiOptions& options, std::string_view reference_name,
                          std::string_view estimate_name);

/// The whole relations report: metric "relations", the relations file's and the estimate's
/// names, the time tolerance, the four rows of Hess et al. 2016 Table II and per relation its
/// line, times and errors. `relations` are those the result was computed from.
/// Precondition: result.outcome.ok().
nlohmann::json relations_json(const RelationsResult& result, const std::vector<Relation>& relations,
                              const RelationsOptions& options, std::string_view relations_name,
                              std::string_view estimate_name);

}  // namespace cairn::eval
