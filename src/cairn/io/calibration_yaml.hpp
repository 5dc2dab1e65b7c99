#pragma once
/// \file
/// Camera calibrations a user hands `cairn vslam`: a small YAML file (docs/vslam.md, "Your own
/// images: a plain folder") and the published presets of TUM RGB-D's three Kinects.

#include <string>

#include "cairn/io/image_sequence.hpp"

namespace cairn::io {

/// Reads a calibration YAML: fx, fy, cx, cy required; k1 k2 p1 p2 k3, width, height, baseline_m,
/// depth_units_per_m, virtual_baseline_m optional. Unknown keys are errors (a typo must not
/// silently leave a zero). Throws ParseError naming the file and line.
CameraCalibration read_calibration_yaml(const std::string& path);

/// The same, from text already in memory, named `name` in errors (for tests and fuzzing).
CameraCalibration parse_calibration_yaml(const std::string& name, const std::string& text);

/// The published calibrations of TUM's three Kinects ("tum-fr1", "tum-fr2", "tum-fr3"; the
/// numbers of vision.in.tum.de "Intrinsic Camera Calibration of the Kinect" and ORB-SLAM2's
/// TUM1/2/3.yaml), colour camera, depth 5000 units per metre, ORB-SLAM2's bf = 40 for the
/// virtual baseline. Throws std::invalid_argument for another name.
CameraCalibration tum_calibration_preset(const std::string& name);

}  // namespace cairn::io
