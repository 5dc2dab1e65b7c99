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

/// The keys: pointers into `options`, each with its section, name and meaning. The vocabulary is
/// not a key (`cairn vslam --vocabulary`).
io::Parameters parameters(VisualSlamOptions& options);
/// set / load / yaml (--print-config) / json (report.json's "options") over parameters().
const io::Configuration<VisualSlamOptions>& configuration();

}  // namespace cairn::vslam
