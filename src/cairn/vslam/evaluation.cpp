#include "cairn/vslam/evaluation.hpp"

#include <Eigen/Core>
#include <Eigen/LU>

#include "cairn/eval/report_json.hpp"

namespace cairn::vslam {

io::Trajectory ground_truth_of_rectified_camera(io::Trajectory T_world_body, const io::StereoRig& rig,
                                                const vision::StereoRectifier& rectifier) {
  const core::SE3 T_body_camera = rig.T_body_left * rectifier.T_left_rectified();
  for (core::SE3& T : T_world_body.poses) T = T * T_body_camera;
  return T_world_body;
}

GroundTruthEvaluation evaluate_against_ground_truth(const GroundTruth& ground_truth, const io::Trajectory& estimate,
                                                    io::SequenceKind kind) {
  GroundTruthEvaluation e;
  e.ground_truth_path = ground_truth.path;
  e.sim3 = kind == io::SequenceKind::kMonocular;
  eval::ApeOptions ape_options;
  ape_options.alignment.method = e.sim3 ? eval::AlignmentMethod::kSim3 : eval::AlignmentMethod::kSE3;
  ape_options.association.max_time_difference_s = 0.02;
  e.ape = eval::evaluate_ape(ground_truth.trajectory, estimate, ape_options);
  eval::RpeOptions rpe_options;
  rpe_options.association = ape_options.association;
  e.rpe_translation = eval::evaluate_rpe(ground_truth.trajectory, estimate, rpe_options);
  rpe_options.relation = eval::PoseRelation::kRotationAngleDeg;
  e.rpe_rotation = eval::evaluate_rpe(ground_truth.trajectory, estimate, rpe_options);
  if (e.ape.outcome.ok()) {
    const eval::ApeResult& ape = e.ape;
    // Drift at the end with no alignment, both trajectories re-based on their first pair.
    const Eigen::Matrix4d d_ref = ape.reference.front().inverse() * ape.reference.back();
    const Eigen::Matrix4d aligned_first = ape.estimate.front();
    const Eigen::Matrix4d d_est = aligned_first.inverse() * ape.estimate.back();
    e.end_point_drift_m = (d_ref.block<3, 1>(0, 3) - d_est.block<3, 1>(0, 3)).norm();
    double path = 0.0;
    for (std::size_t i = 1; i < ape.reference.size(); ++i) path += (ape.reference[i].block<3, 1>(0, 3) - ape.reference[i - 1].block<3, 1>(0, 3)).norm();
    e.path_length_m = path;
  }
  return e;
}

nlohmann::json evaluation_json(const GroundTruthEvaluation& e) {
  nlohmann::json evaluation = {{"ground_truth", e.ground_truth_path}};
  if (e.ape.outcome.ok()) {
    evaluation[e.sim3 ? "ate_sim3_aligned_m" : "ate_se3_aligned_m"] = eval::statistics_json(e.ape.statistics);
    if (e.sim3) evaluation["sim3_scale"] = e.ape.alignment.scale;
    evaluation["end_point_drift_m"] = e.end_point_drift_m;
    evaluation["path_length_m"] = e.path_length_m;
    evaluation["frames_compared"] = e.ape.reference.size();
  } else {
    evaluation["ate_error"] = e.ape.outcome.message;
  }
  if (e.rpe_translation.outcome.ok()) evaluation["rpe_1_frame_translation_m"] = eval::statistics_json(e.rpe_translation.statistics);
  if (e.rpe_rotation.outcome.ok()) evaluation["rpe_1_frame_rotation_deg"] = eval::statistics_json(e.rpe_rotation.statistics);
  return evaluation;
}

}  // namespace cairn::vslam
