#pragma once
/// \file
/// The slam2d configuration as YAML: every key of Slam2dOptions under a section, each with its
/// documented default (docs/configuration.md is `cairn slam2d --print-config`). Files may set
/// any subset; unknown keys and wrong types are errors naming the file and line.
///
///   front_end:
///     keyframe_distance_m: 0.2
///   loop_closure:
///     min_score: 0.6

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/io/parameters.hpp"
#include "cairn/slam2d/localization.hpp"
#include "cairn/slam2d/slam.hpp"

namespace cairn::slam2d {

/// "default" (SICK LMS-class scanners: 180-361 beams over 180 degrees, the Freiburg logs) or
/// "short-range" (360-degree scanners up to 12 m with 2-3 cm noise, RPLIDAR/YDLIDAR class);
/// throws std::invalid_argument naming the known presets otherwise.
Slam2dOptions preset_options(const std::string& name);
std::vector<std::string> preset_names();

/// Reads `path` over `options` (keys absent from the file keep their value). Throws
/// io::ParseError naming file and line on a syntax error, unknown key or wrong type.
void load_config(const std::string& path, Slam2dOptions& options);
/// "section.key=value". Throws std::invalid_argument on an unknown key or a bad value.
void apply_setting(const std::string& assignment, Slam2dOptions& options);
/// Every key with its value and a comment saying what it means.
std::string config_to_yaml(const Slam2dOptions& options);
/// {section: {key: value}} of every key (report.json's "options").
nlohmann::json config_json(const Slam2dOptions& options);
/// The keys: pointers into `options`, each with its section, name and meaning.
io::Parameters parameters(Slam2dOptions& options);
/// set / load / yaml / json over parameters() (the four functions above are these).
const io::Configuration<Slam2dOptions>& configuration();

/// The localiser's own keys (section "localization"; its matching keys are Slam2dOptions').
io::Parameters localization_parameters(Localizer2dOptions& options);
/// report.json's "options" of a localisation run: the localization keys, and "matching" (config_json).
nlohmann::json localization_config_json(const Localizer2dOptions& options);

}  // namespace cairn::slam2d
