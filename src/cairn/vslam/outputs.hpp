#pragma once
/// \file
/// What `cairn vslam` writes, each file through io::write_output into an io::OutputDirectory's
/// staging (the command commits it):
///
///   trajectory.tum            the main map's tracked frames, T_world_camera (a lost frame has no
///                             pose, as ORB-SLAM2's SaveTrajectoryTUM); the main map is the segment
///                             of the first keyframe
///   trajectory_map_<s>.tum    the tracked frames of each map segment s that never merged with the
///                             main map, in a frame of its own
///   trajectory.kitti          every frame, one line each as the KITTI devkit needs (a lost frame
///                             carries the motion model's guess)
///   keyframes.tum             the main map's keyframes (localising in a saved map: the map's)
///   map_points.ply            the good map points, world = the first camera (x right, y down, z forward)
///   frames.csv                per frame: health, segment, events, counts, times (ms), note
///   trajectory.png            top view; with a ground truth, the estimate aligned to it
///   features.png              one frame's keypoints and what became of them
///   report.json               input, options, summary, timing, map segments, evaluation against
///                             the ground truth (evaluation.hpp), place recognition; localising
///                             in a saved map, "localization" (the map, frames localised,
///                             relocalisations accepted and refused)
///
/// Poses are at the final keyframe poses (VisualSlam::trajectory).

#include <cstddef>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cairn/io/image_sequence.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/vslam/evaluation.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::vslam {

/// What the run was given, for report.json ("input", "place_recognition").
struct RunInput {
  const io::ImageSequence& sequence;  ///< with the calibration the run used
  io::SequenceKind kind;              ///< as tracked (kMonocular for the left images of a stereo pair)
  std::string calibration_source;     ///< the calibration file, "preset <name>" or "dataset"
  std::string vocabulary_path;        ///< empty: none
  /// A bag's topics read, role and topic ({"left", "/stereo/left/image_raw"}, ...: BagImages::
  /// topics); empty for a folder. report.json's input then says "bag" and lists them.
  std::vector<std::pair<std::string, std::string>> topics = {};
  /// Localising in a saved map (VisualSlam::localization_only): the map file; report.json's
  /// "localization" names it, and keyframes.tum holds the map's keyframes (mapping-run stamps).
  std::string map_path = {};
  /// Frames of the sequence skipped before the first one processed (--first-frame); frames.csv
  /// counts from the first processed, report.json's input says how many were skipped.
  std::size_t first_frame = 0;
};

/// The frame drawn in features.png.
struct FeaturePicture {
  std::size_t frame = 0;
  cv::Mat image;  ///< the grey image tracked; empty: no features.png
  std::vector<cv::KeyPoint> keypoints;
  std::vector<signed char> states;  ///< FrameResult::keypoint_states
};

/// The frames a run processed, in order.
struct RunRecord {
  std::vector<FrameResult> frames;  ///< their keypoints may be dropped
  std::vector<double> read_s;       ///< per frame: decoding (and rectifying) its images
  double total_s = 0.0;             ///< wall clock over the frames
  bool interrupted = false;         ///< stopped before the last frame (report.json says so)
  FeaturePicture features;
};

/// Per-frame times in seconds, as report.json's "timing" and the command's summary give them.
struct FrameTimeSeries {
  std::vector<double> total_s, features_s, mapping_s;
  std::vector<double> tracking_s;  ///< stereo matching (or depth lookup) and tracking
};
FrameTimeSeries frame_times(const std::vector<FrameResult>& frames);

/// Gravity in the map's frame and the IMU's biases, once the inertial estimate exists (an empty
/// object before): gravity_world_mps2, gyro_bias_rad_s, accel_bias_mps2. report.json's "inertial"
/// section and Python's VisualSlam.inertial both hold these fields.
nlohmann::json inertial_estimate_json(const VisualSlam& slam);

/// What the command's summary needs of the outputs.
struct WrittenOutputs {
  std::size_t map_points = 0;
  std::optional<GroundTruthEvaluation> evaluation;  ///< when the ground truth has poses
};

/// Writes every file above into out.staging(), in that order; record.frames must be the frames
/// fed to `slam`, from the first on. Throws std::runtime_error when no frame was tracked (nothing
/// written) or trajectory.png cannot be drawn, io::ParseError when a file cannot be written.
WrittenOutputs write_outputs(const io::OutputDirectory& out, const VisualSlam& slam, const RunInput& input,
                             const RunRecord& record, const GroundTruth& ground_truth);

}  // namespace cairn::vslam
