#pragma once
/// \file
/// The plots of each metric as viz::Figures (plain data; viz/render.hpp draws them): a top view
/// of reference and estimate coloured by the error, the error against time or distance with
/// its rmse / mean / median lines as evo draws them, the KITTI errors per segment length, the
/// relations' errors per relation. Each metric's function returns its figures with a short
/// name ("top", "error", "segments") that the caller turns into a file name; `cairn eval --plot`
/// writes PREFIX_<name>.png. Every pipeline that reports errors against ground truth can reuse
/// them.
///
/// `plane` picks the two axes of a top view: "xy", "xz", "yz", or anything else (the CLI says
/// "auto") for the two along which the reference spreads most.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cairn/core/types.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/pose_relation.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/eval/statistics.hpp"
#include "cairn/viz/figure.hpp"

namespace cairn::eval {

/// A figure and the name its file takes ("top", "error", "segments").
struct NamedFigure {
  std::string name;
  viz::Figure figure;
};

/// The two axes (0 x, 1 y, 2 z) of the top view: those `plane` names ("xy", "xz", "yz"), or
/// else the two along which the positions of `reference` spread most (KITTI camera poses have
/// y pointing down, so that gives x-z).
std::pair<int, int> plane_axes(std::string_view plane, const std::vector<Matrix4>& reference);

/// Top view: reference dashed grey, estimate coloured by `values` (one per estimate pose) when
/// given, otherwise blue; optional coloured `points` (RPE pair starts), whose values then set
/// the colour bar instead. `color_label` names the colour bar, with unit.
viz::Figure top_view(const std::string& title, const std::vector<Matrix4>& reference,
                     const std::vector<Matrix4>& estimate, const std::vector<double>& values,
                     const std::string& color_label, std::string_view plane, const viz::Series* points = nullptr);

/// `errors` against `x`, with rmse / mean / median lines of `statistics` as evo draws them;
/// `unit` ("m", "deg", or "" for none) follows the numbers in the legend.
viz::Figure error_plot(const std::string& title, const std::vector<double>& x, const std::vector<double>& errors,
                       const std::string& x_label, const std::string& y_label, const Statistics& statistics,
                       const std::string& unit);

/// Path length along `poses` at each pose (0 at the first), metres.
std::vector<double> path_length(const std::vector<Matrix4>& poses);

/// evo's wording of the relation with its unit in brackets: "translation part [m]".
std::string relation_label(PoseRelation relation);

/// "top" (estimate coloured by its APE) and "error" (APE over time, or per pose without
/// stamps). Precondition: result.outcome.ok().
std::vector<NamedFigure> ape_figures(const ApeResult& result, std::string_view plane);

/// "top" (each pair's start coloured by its RPE) and "error" (RPE against the distance along
/// the reference for a delta in metres, otherwise against time or pose index). `options` are
/// those the result was computed with. Precondition: result.outcome.ok().
std::vector<NamedFigure> rpe_figures(const RpeResult& result, const RpeOptions& options, std::string_view plane);

/// "segments" (t_err and r_err per nominal length, as bars) and "top".
/// Precondition: result.outcome.ok().
std::vector<NamedFigure> kitti_figures(const KittiResult& result, std::string_view plane);

/// "error": translational and rotational error of each relation against the time of its first
/// scan. `relations` are those the result was computed from. Precondition: result.outcome.ok().
std::vector<NamedFigure> relations_figures(const RelationsResult& result, const std::vector<Relation>& relations);

}  // namespace cairn::eval
