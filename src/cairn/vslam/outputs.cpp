#include "cairn/vslam/outputs.hpp"

#include <Eigen/Core>
#include <map>
#include <nlohmann/json.hpp>
#include <ostream>
#include <stdexcept>

#include "cairn/eval/spread.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/viz/render.hpp"
#include "cairn/vslam/config.hpp"

namespace cairn::vslam {
namespace {

/// The run's poses split by map segment.
struct Trajectories {
  std::vector<core::SE3> poses;  ///< every frame's (VisualSlam::trajectory)
  std::vector<int> segments;     ///< every frame's segment (VisualSlam::frame_segments)
  int main_segment = 0;
  io::Trajectory main;         ///< the main map's tracked frames
  io::Trajectory every_frame;  ///< tracked or not
  std::map<int, io::Trajectory> other_maps;
};

Trajectories split_trajectories(const VisualSlam& slam, const std::vector<FrameResult>& results) {
  Trajectories t;
  t.poses = slam.trajectory();
  t.segments = slam.frame_segments();
  t.main_segment = slam.main_segment();
  for (std::size_t k = 0; k < results.size(); ++k) {
    t.every_frame.stamps.push_back(results[k].time);
    t.every_frame.poses.push_back(t.poses[k]);
    if (!results[k].tracked || t.segments[k] < 0) continue;
    io::Trajectory& segment = t.segments[k] == t.main_segment ? t.main : t.other_maps[t.segments[k]];
    segment.stamps.push_back(results[k].time);
    segment.poses.push_back(t.poses[k]);
  }
  return t;
}

void write_trajectories(const io::OutputDirectory& out, const VisualSlam& slam, const std::vector<FrameResult>& results,
                        const Trajectories& t) {
  io::write_output(out.staging_path("trajectory.tum"), [&](std::ostream& o) { io::write_tum(o, t.main); });
  for (const auto& [id, trajectory] : t.other_maps) {
    io::write_output(out.staging_path("trajectory_map_" + std::to_string(id) + ".tum"), [&](std::ostream& o) { io::write_tum(o, trajectory); });
  }
  io::write_output(out.staging_path("trajectory.kitti"), [&](std::ostream& o) { io::write_kitti(o, t.every_frame); });
  io::Trajectory keyframes;
  if (slam.localization_only()) {  // the saved map's keyframes, stamped with the mapping run's times
    keyframes.stamps = slam.keyframe_times();
    keyframes.poses = slam.keyframe_poses();
  }
  for (const std::size_t k : slam.localization_only() ? std::vector<std::size_t>{} : slam.keyframe_frames()) {
    if (t.segments[k] != t.main_segment) continue;  // keyframes of the main map, as trajectory.tum
    keyframes.stamps.push_back(results[k].time);
    keyframes.poses.push_back(t.poses[k]);  // keyframes are tracked frames
  }
  io::write_output(out.staging_path("keyframes.tum"), [&](std::ostream& o) { io::write_tum(o, keyframes); });
}

void write_frames_csv(const std::string& path, const std::vector<FrameResult>& results, const std::vector<int>& segments) {
  io::write_output(path, [&](std::ostream& o) {
    o << "frame,time_s,health,tracked,segment,keyframe,relocalised,loop_closed,new_map,features,stereo_points,first_stage_matches,used_reference,used_image_alignment,inliers,inlier_ratio,"
         "sigma_position_m,features_ms,stereo_ms,tracking_ms,mapping_ms,total_ms,note\n";
    for (const auto& r : results) {
      o << r.frame << ',' << r.time.to_seconds_string() << ',' << to_string(r.health) << ',' << (r.tracked ? 1 : 0) << ','
        << segments[r.frame] << ',' << (r.keyframe ? 1 : 0) << ',' << (r.relocalised ? 1 : 0) << ',' << (r.loop_closed ? 1 : 0) << ','
        << (r.new_map ? 1 : 0) << ',' << r.features << ',' << r.stereo_points << ',' << r.motion_matches << ','
        << (r.used_reference ? 1 : 0) << ',' << (r.used_image_alignment ? 1 : 0) << ',' << r.inliers << ',' << r.inlier_ratio << ',' << r.sigma_position_m << ','
        << 1e3 * r.times.features_s << ',' << 1e3 * r.times.stereo_s << ',' << 1e3 * r.times.tracking_s << ','
        << 1e3 * r.times.mapping_s << ',' << 1e3 * r.times.total_s << ",\"" << r.note << "\"\n";
    }
  });
}

/// Top view (x, z); with a successful APE, the ground truth and the estimate aligned to it.
std::string trajectory_png(const std::string& folder, const io::Trajectory& trajectory, const GroundTruthEvaluation* evaluation) {
  viz::Figure figure;
  figure.title = "cairn vslam: " + folder;
  figure.width_px = 1000;
  figure.height_px = 800;
  viz::Axes axes;
  axes.title = "top view (x right, z forward of the first camera)";
  axes.x_label = "x [m]";
  axes.y_label = "z [m]";
  axes.equal_aspect = true;
  if (evaluation && evaluation->ape.outcome.ok()) {
    const eval::ApeResult& ape = evaluation->ape;
    // The ground truth drawn in the estimate's frame: T_est = alignment^-1 * T_gt.
    viz::Series gt;
    gt.label = evaluation->sim3 ? "ground truth (estimate Sim(3)-aligned)" : "ground truth (estimate SE(3)-aligned)";
    gt.color = viz::kBlack;
    gt.dashed = true;
    viz::Series est;
    est.label = "cairn vslam";
    for (std::size_t i = 0; i < ape.reference.size(); ++i) {
      gt.x.push_back(ape.reference[i](0, 3));
      gt.y.push_back(ape.reference[i](2, 3));
      est.x.push_back(ape.estimate[i](0, 3));
      est.y.push_back(ape.estimate[i](2, 3));
    }
    axes.title = std::string("top view, estimate ") + (evaluation->sim3 ? "Sim(3)" : "SE(3)") +
                 "-aligned to the ground truth (x, z of the ground truth's frame)";
    axes.series.push_back(gt);
    axes.series.push_back(est);
  }
  if (axes.series.empty()) {
    viz::Series est;
    est.label = "cairn vslam";
    for (const auto& T : trajectory.poses) {
      est.x.push_back(T.translation().x());
      est.y.push_back(T.translation().z());
    }
    axes.series.push_back(est);
  }
  figure.panels.push_back(axes);
  const viz::RenderResult png = viz::render(figure, viz::ImageFormat::kPng);
  if (!png.ok) throw std::runtime_error("cannot draw trajectory.png: " + png.message);
  return png.bytes;
}

nlohmann::json input_json(const RunInput& input, std::size_t frames_processed) {
  const io::ImageSequence& seq = input.sequence;
  nlohmann::json json = {{"folder", seq.folder},
                         {"layout", seq.layout},
                         {"kind", std::string(io::to_string(input.kind))},
                         {"frames_listed", seq.frames.size()},
                         {"frames_processed", frames_processed},
                         {"first_frame", input.first_frame},
                         {"times_from_file", seq.times_from_file},
                         {"notes", seq.notes},
                         {"calibration",
                          {{"fx", seq.calibration.fx}, {"fy", seq.calibration.fy}, {"cx", seq.calibration.cx}, {"cy", seq.calibration.cy},
                           {"distortion", {seq.calibration.k1, seq.calibration.k2, seq.calibration.p1, seq.calibration.p2, seq.calibration.k3}},
                           {"baseline_m", seq.calibration.baseline_m}, {"virtual_baseline_m", seq.calibration.virtual_baseline_m},
                           {"depth_units_per_m", seq.calibration.depth_units_per_m},
                           {"source", input.calibration_source}}}};
  if (!input.topics.empty()) {
    json["bag"] = seq.folder;
    json["topics"] = nlohmann::json::object();
    for (const auto& [role, topic] : input.topics) json["topics"][role] = topic;
  }
  return json;
}

nlohmann::json summary_json(const VisualSlamSummary& s, std::size_t map_points, bool interrupted) {
  return {{"frames", s.frames},
          {"ok", s.frames_ok},
          {"degraded", s.frames_degraded},
          {"lost", s.frames_lost},
          {"keyframes", s.keyframes},
          {"map_points_created", s.map_points},
          {"map_points_culled", s.map_points_culled},
          {"map_points", map_points},
          {"local_bundle_adjustments", s.local_bas},
          {"reference_fallbacks", s.reference_fallbacks},
          {"interrupted", interrupted}};
}

/// With an IMU (VisualInertialOptions): the inertial estimates and what the IMU did to the frames.
nlohmann::json inertial_json(const VisualSlam& slam) {
  const VisualSlamSummary& s = slam.summary();
  const VisualInertialOptions& o = slam.options().inertial;
  nlohmann::json j = {{"T_imu_camera", {{"translation", {o.T_body_camera.translation().x(), o.T_body_camera.translation().y(),
                                                          o.T_body_camera.translation().z()}},
                                         {"quaternion_xyzw", {o.T_body_camera.so3().unit_quaternion().x(), o.T_body_camera.so3().unit_quaternion().y(),
                                                              o.T_body_camera.so3().unit_quaternion().z(), o.T_body_camera.so3().unit_quaternion().w()}}}},
                      {"initialised", slam.inertial_initialised()},
                      {"initialised_at_s", s.inertial_initialised_at_s >= 0.0 ? nlohmann::json(s.inertial_initialised_at_s) : nlohmann::json(nullptr)},
                      {"estimates", s.inertial_estimates},
                      {"estimates_refused", s.inertial_estimates_refused},
                      {"last_refusal", s.inertial_refusal},
                      {"estimates_s", s.inertial_s},
                      {"frames_carried", s.frames_carried_by_imu},
                      {"frames_contradicting_imu", s.frames_contradicting_imu},
                      {"local_bas_with_imu", s.inertial_local_bas},
                      {"imu_factors_in_local_bas", s.inertial_local_ba_factors},
                      {"loops_corrected_in_4_dof", s.loops_corrected_in_4dof}};
  j.update(inertial_estimate_json(slam));
  if (s.monocular_initial_scale > 0.0) {
    j["monocular"] = {{"initial_scale", s.monocular_initial_scale},
                      {"last_judged_scale", s.monocular_scale_estimate},
                      {"frames_scale_drifted", s.frames_scale_drifted},
                      {"estimates_unexcited", s.scale_estimates_unexcited}};
  }
  return j;
}

nlohmann::json timing_json(const RunRecord& record, const VisualSlamSummary& s) {
  const FrameTimeSeries times = frame_times(record.frames);
  return {{"total_s", record.total_s},
          {"per_frame_ms", eval::spread_json_ms(times.total_s)},
          {"features_ms", eval::spread_json_ms(times.features_s)},
          {"tracking_ms", eval::spread_json_ms(times.tracking_s)},
          {"mapping_ms", eval::spread_json_ms(times.mapping_s)},
          {"image_read_ms", eval::spread_json_ms(record.read_s)},
          {"local_ba_s", s.local_ba_s},
          {"threads", s.local_mapping_thread ? "ORB of the two images in parallel; a keyframe's local bundle adjustment in its own thread while the next frame is read and extracted (joined, with culling and loop closing, in that frame's mapping time); the rest on one thread"
                                             : "ORB of the two images in parallel; everything else on one thread"}};
}

/// Per map segment with tracked frames: its id, whether it is the main map, its tracked frames
/// and its trajectory file.
nlohmann::json maps_json(const std::vector<FrameResult>& results, const Trajectories& t) {
  nlohmann::json maps = nlohmann::json::array();
  std::map<int, std::size_t> frames_in;
  for (std::size_t k = 0; k < results.size(); ++k) {
    if (results[k].tracked && t.segments[k] >= 0) ++frames_in[t.segments[k]];
  }
  for (const auto& [id, count] : frames_in) {
    maps.push_back({{"segment", id},
                    {"main", id == t.main_segment},
                    {"tracked_frames", count},
                    {"trajectory", id == t.main_segment ? "trajectory.tum" : "trajectory_map_" + std::to_string(id) + ".tum"}});
  }
  return maps;
}

nlohmann::json place_recognition_json(const RunInput& input, const VisualSlamOptions& options, const VisualSlamSummary& s) {
  nlohmann::json place_recognition = {{"vocabulary", input.vocabulary_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(input.vocabulary_path)},
                                      {"vocabulary_description", options.vocabulary ? options.vocabulary->description() : ""},
                                      {"loop_queries", s.loop_queries},
                                      {"loops_accepted", s.loops_accepted},
                                      {"relocalisations", s.relocalisations},
                                      {"relocalisations_refused_ambiguous", s.relocalisations_ambiguous},
                                      {"keyframes_culled", s.keyframes_culled},
                                      {"loops_refused_ambiguous", s.loops_ambiguous},
                                      {"map_points_fused", s.map_points_fused},
                                      {"fusion_observations_added", s.fusion_observations},
                                      {"image_alignment_poses", s.image_alignment_poses},
                                      {"maps_started", s.maps_started},
                                      {"maps_merged", s.maps_merged},
                                      {"merge_attempts_with_recent_keyframes", s.merge_attempts},
                                      {"revisits_verified", s.revisits_verified},
                                      {"global_bundle_adjustments", s.global_bas},
                                      {"loop_s", s.loop_s},
                                      {"global_ba_s", s.global_ba_s},
                                      {"candidates", nlohmann::json::array()}};
  for (const LoopRecord& l : s.loops) {
    place_recognition["candidates"].push_back({{"keyframe", l.keyframe},
                                               {"frame", l.frame},
                                               {"candidate_keyframe", l.candidate},
                                               {"candidate_frame", l.candidate_frame},
                                               {"score", l.score},
                                               {"min_covisible_score", l.min_covisible_score},
                                               {"consistency", l.consistency},
                                               {"pnp_inliers", l.pnp_inliers},
                                               {"matches", l.matches},
                                               {"merge", l.merge},
                                               {"decision", l.decision},
                                               {"reason", l.reason},
                                               {"correction_m", l.correction_m},
                                               {"correction_deg", l.correction_deg},
                                               {"scale", l.scale}});
  }
  return place_recognition;
}

/// Localising in a saved map: the map, how many frames were localised and how, and every
/// relocalisation refused (frame and reason; the rest of the notes are in frames.csv).
nlohmann::json localization_json(const RunInput& input, const VisualSlam& slam, const std::vector<FrameResult>& results) {
  const VisualSlamSummary& s = slam.summary();
  std::size_t tracked = 0, relocalised = 0;
  nlohmann::json refused = nlohmann::json::array();
  for (const FrameResult& r : results) {
    tracked += r.tracked ? 1 : 0;
    relocalised += r.relocalised ? 1 : 0;
    if (r.relocalisation_refused) refused.push_back({{"frame", r.frame}, {"reason", r.note}});
  }
  return {{"map", input.map_path},
          {"map_keyframes", slam.keyframe_poses().size()},
          {"map_points", slam.map_points().size()},
          {"frames", results.size()},
          {"frames_localised", tracked},
          {"relocalisations", relocalised},
          {"relocalisations_refused_ambiguous", s.relocalisations_ambiguous},
          {"relocalisations_refused", refused}};
}

}  // namespace

nlohmann::json inertial_estimate_json(const VisualSlam& slam) {
  nlohmann::json j = nlohmann::json::object();
  if (!slam.inertial_initialised()) return j;
  const Eigen::Vector3d g = slam.gravity_world();
  const inertial::ImuBias b = slam.imu_bias();
  j["gravity_world_mps2"] = {g.x(), g.y(), g.z()};
  j["gyro_bias_rad_s"] = {b.gyro_rad_s.x(), b.gyro_rad_s.y(), b.gyro_rad_s.z()};
  j["accel_bias_mps2"] = {b.accel_mps2.x(), b.accel_mps2.y(), b.accel_mps2.z()};
  return j;
}

FrameTimeSeries frame_times(const std::vector<FrameResult>& frames) {
  FrameTimeSeries times;
  for (const auto& r : frames) {
    times.tracking_s.push_back(r.times.stereo_s + r.times.tracking_s);
    times.features_s.push_back(r.times.features_s);
    times.mapping_s.push_back(r.times.mapping_s);
    times.total_s.push_back(r.times.total_s);
  }
  return times;
}

WrittenOutputs write_outputs(const io::OutputDirectory& out, const VisualSlam& slam, const RunInput& input,
                             const RunRecord& record, const GroundTruth& ground_truth) {
  const std::vector<FrameResult>& results = record.frames;
  const Trajectories t = split_trajectories(slam, results);
  if (t.main.poses.empty()) throw std::runtime_error("no frame was tracked: nothing to write (see the messages above)");
  write_trajectories(out, slam, results, t);
  WrittenOutputs written;
  std::vector<Eigen::Vector3f> map_points;
  for (const Eigen::Vector3d& p : slam.map_points()) map_points.push_back(p.cast<float>());
  written.map_points = map_points.size();
  io::write_output(out.staging_path("map_points.ply"), [&](std::ostream& o) {
    io::write_ply(o, map_points, "cairn vslam map points, world = the first camera (x right, y down, z forward)");
  });
  write_frames_csv(out.staging_path("frames.csv"), results, t.segments);

  if (!ground_truth.trajectory.poses.empty()) written.evaluation = evaluate_against_ground_truth(ground_truth, t.main, input.kind);
  const std::string png = trajectory_png(input.sequence.folder, t.main, written.evaluation ? &*written.evaluation : nullptr);
  io::write_output(out.staging_path("trajectory.png"), [&](std::ostream& o) { o << png; });
  if (!record.features.image.empty()) {
    const FeaturePicture& f = record.features;
    const std::string bytes = vision::draw_features_png(f.image, f.keypoints, f.states, "frame " + std::to_string(f.frame));
    io::write_output(out.staging_path("features.png"), [&](std::ostream& o) { o << bytes; });
  }

  const VisualSlamSummary& s = slam.summary();
  nlohmann::json report;
  report["input"] = input_json(input, results.size());
  report["options"] = configuration().json(slam.options());
  report["summary"] = summary_json(s, written.map_points, record.interrupted);
  report["timing"] = timing_json(record, s);
  report["maps"] = maps_json(results, t);
  report["evaluation"] = written.evaluation ? evaluation_json(*written.evaluation) : nlohmann::json(nullptr);
  report["place_recognition"] = place_recognition_json(input, slam.options(), s);
  if (slam.localization_only()) report["localization"] = localization_json(input, slam, results);
  report["inertial"] = slam.options().inertial.enabled ? inertial_json(slam) : nlohmann::json(nullptr);
  report["not_implemented"] = {"merges of map segments in 4 DoF for visual-inertial maps", "the biases as variables of the pose optimisation"};
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  return written;
}

}  // namespace cairn::vslam
