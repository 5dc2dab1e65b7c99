#pragma once
/// \file
/// A visual SLAM run against ground truth, as `cairn vslam` reports it (report.json's
/// "evaluation", the terminal's ATE line, the aligned ground truth in trajectory.png): the ground
/// truth moved into the tracked camera's frame where the dataset gives the body's (EuRoC), then
/// cairn::eval's APE and RPE (evo's definitions) on the main map's trajectory.

#include <nlohmann/json.hpp>
#include <string>

#include "cairn/eval/ape.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/vision/features.hpp"

namespace cairn::vslam {

/// A ground truth and the file it came from (report.json and the terminal name it).
struct GroundTruth {
  io::Trajectory trajectory;  ///< empty: no evaluation
  std::string path;
};

/// EuRoC's ground truth is the body's (the IMU), but the camera tracked is the rectified left one:
/// each pose becomes T_world_camera = T_world_body * T_body_left * T_left_rectified.
io::Trajectory ground_truth_of_rectified_camera(io::Trajectory T_world_body, const io::StereoRig& rig,
                                                const vision::StereoRectifier& rectifier);

/// The main map's trajectory against the ground truth, poses paired by stamp within 0.02 s.
struct GroundTruthEvaluation {
  std::string ground_truth_path;
  /// Monocular: the estimate is Sim(3)-aligned (its scale is not observable; evo_ape -as),
  /// otherwise SE(3)-aligned (evo_ape -a).
  bool sim3 = false;
  eval::ApeResult ape;  ///< translation part (m), after the alignment
  /// RPE over 1 frame, no alignment (evo_rpe's defaults): translation part (m), rotation angle (deg).
  eval::RpeResult rpe_translation, rpe_rotation;
  /// When ape.outcome.ok(): |t| of the difference between the last pose relative to the first of
  /// the paired ground truth and of the aligned estimate.
  double end_point_drift_m = 0.0;
  double path_length_m = 0.0;  ///< of the paired ground truth, when ape.outcome.ok()
};

/// Precondition: ground_truth.trajectory is not empty. A metric that fails says so in its
/// outcome (nothing is thrown for it).
GroundTruthEvaluation evaluate_against_ground_truth(const GroundTruth& ground_truth, const io::Trajectory& estimate,
                                                    io::SequenceKind kind);

/// report.json's "evaluation": ground_truth (the path); with a successful APE,
/// ate_se3_aligned_m or ate_sim3_aligned_m {rmse, mean, median, max, count} (and sim3_scale),
/// end_point_drift_m, path_length_m and frames_compared, else ate_error (why not);
/// rpe_1_frame_translation_m and rpe_1_frame_rotation_deg when they succeeded.
nlohmann::json evaluation_json(const GroundTruthEvaluation& evaluation);

}  // namespace cairn::vslam
