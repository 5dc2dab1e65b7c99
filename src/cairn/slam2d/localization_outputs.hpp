#pragma once
/// \file
/// Pictures and tables of a localisation run (`cairn localize2d`): the saved map rendered into one
/// grid in the map frame, map.png with the localised trajectory coloured by health, scans.csv.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/slam2d/localization.hpp"
#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/slam2d/saved_map.hpp"

namespace cairn::slam2d {

/// The submaps of `map` in one grid in the map frame, cell `resolution_m`: each cell's log-odds
/// is the sum of those of the submap cells its centre falls into (nearest cell; each keyframe
/// lies in two submaps, so its evidence counts twice), clamped to the map's bounds. For
/// pictures, not for matching.
ProbabilityGrid render_saved_map(const SavedMap2D& map, double resolution_m);

/// map.png: the grid, the localised poses of `results` as a line coloured by health (blue ok,
/// orange degraded) that breaks where the localiser had no pose (lost), a circle at every
/// relocalisation, a legend and a scale bar. Written through io::write_output.
void write_localization_png(const ProbabilityGrid& grid, const std::vector<LocalizationResult>& results,
                            const std::string& path);

/// scans.csv: one line per scan in input order (see docs/slam2d.md, "Map reuse and localisation").
void write_localization_csv(const std::vector<LocalizationResult>& results, const std::string& path);

/// The run's report: summary, times, the localiser's options, every relocalisation with its
/// evidence (the agreeing verified matches), health events. The command adds input and output.
nlohmann::json localization_report_json(const Localizer2d& localizer, const Localizer2dOptions& options);

}  // namespace cairn::slam2d
