#pragma once
/// \file
/// Pictures and tables of a localisation run (`cairn localize2d`): the saved map rendered into one
/// grid in the map frame, map.png with the localised trajectory coloured by health, scans.csv.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/io/trajectory.hpp"
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

/// trajectory.tum's poses: the localised scans of `results`, ordered by time (the first of equal
/// stamps kept), lifted to SE(3) in the map frame.
io::Trajectory localized_trajectory(const std::vector<LocalizationResult>& results);

/// Errors of the localised scans against a ground truth in the map's frame (no alignment: the
/// point is to check where the localiser put the robot in the map). A scan is compared with the
/// ground-truth pose of the nearest stamp within 0.05 s; a relocalisation is wrong when it is off
/// by more than 0.3 m or 3 degrees.
struct LocalizationTruthErrors {
  std::vector<double> translation_m, rotation_deg;
  std::vector<double> translation_ok_m;  ///< of the scans whose health was ok
  std::size_t wrong_relocalisations = 0, relocalisations_compared = 0;
  std::size_t unmatched = 0;  ///< localised scans without a ground-truth pose within 0.05 s
};
LocalizationTruthErrors compare_with_ground_truth(const io::Trajectory& truth,
                                                  const std::vector<LocalizationResult>& results);
/// report.json's "ground_truth": the counts, and eval's statistics (as evo computes them) of each
/// error list (null when empty).
nlohmann::json ground_truth_json(const std::string& path, const LocalizationTruthErrors& errors);

}  // namespace cairn::slam2d
