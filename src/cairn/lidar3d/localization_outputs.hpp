#pragma once
/// \file
/// The outputs of a localisation run in a saved 3D map (`cairn localize3d`): trajectory.tum (the
/// localised scans, map frame), scans.csv (one line per scan), map.png (the saved map from above
/// with the localised trajectory coloured by health) and report.json (summary, every place the
/// descriptor proposed and what its verification decided, every relocalisation with the scans
/// that supported it). The layout of scans.csv is in docs/lidar3d.md, "Localising in a saved map".

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/io/trajectory.hpp"
#include "cairn/lidar3d/localization.hpp"

namespace cairn::lidar3d {

/// The localised scans of `results` (map frame, at their stamps), in input order.
io::Trajectory localized_trajectory(const std::vector<Localization3dResult>& results);

/// scans.csv, through io::write_output.
void write_localization_csv(const std::vector<Localization3dResult>& results, const std::string& path);

/// map.png: render_top_down (outputs.hpp) of the map's points and the localised scans, a gap
/// wherever the localiser had no pose. At most `max_side_px` pixels on the longer side.
void write_localization_png(const SavedMap3D& map, const std::vector<Localization3dResult>& results,
                            const std::string& path, int max_side_px);

/// Milliseconds per tracked scan (localised and not relocalised: the whole add_scan call,
/// Localization3dResult::total_s): how many, median, 90th percentile (nearest rank) and slowest;
/// all zero without one.
struct TrackingTimes {
  std::size_t scans = 0;
  double median_ms = 0.0, p90_ms = 0.0, max_ms = 0.0;
};
TrackingTimes tracking_times(const std::vector<Localization3dResult>& results);
nlohmann::json to_json(const TrackingTimes& times);

/// report.json's body: the map, the options, the summary, the relocalisations and every attempt.
nlohmann::json localization_report_json(const Localizer3d& localizer);

}  // namespace cairn::lidar3d
