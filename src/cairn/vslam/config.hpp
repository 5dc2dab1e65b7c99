#pragma once
/// \file
/// The vslam configuration as YAML: every tunable key of VisualSlamOptions (with the ORB extractor's
/// and the stereo matcher's options it holds) under a section, each with its value and what it
/// means (`cairn vslam --print-config`). Files may set any subset; unknown keys and wrong types are
/// errors naming the file and line. The same description gives report.json's "options".
///
///   orb:
///     features: 1500
///   loop_closure:
///     min_matches: 50

#include <nlohmann/json.hpp>
#include <string>

#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parameters.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::vslam {

/// ORB-SLAM2's settings for a dataset (the starting point before a configuration file): 2000
/// features for the KITTI layout (stereo and monocular), 1000 for the others (ORB-SLAM2: TUM);
/// RGB-D points are close within 40 baselines (TUM*.yaml ThDepth), stereo within 35.
VisualSlamOptions dataset_options(const std::string& layout, io::SequenceKind kind);

/// Reads `path` over `options` (keys absent from the file keep their value). Throws
/// io::ParseError naming file and line on a syntax error, unknown key or wrong type.
void load_config(const std::string& path, VisualSlamOptions& options);
/// "section.key=value". Throws std::invalid_argument on an unknown key or a bad value.
void apply_setting(const std::string& assignment, VisualSlamOptions& options);
/// Every key with its value and a comment saying what it means.
std::string config_to_yaml(const VisualSlamOptions& options);
/// {section: {key: value}} of every key (report.json's "options").
nlohmann::json config_json(const VisualSlamOptions& options);
/// The keys: pointers into `options`, each with its section, name and meaning. The vocabulary is
/// not a key (`cairn vslam --vocabulary`).
io::Parameters parameters(VisualSlamOptions& options);

}  // namespace cairn::vslam
