// `cairn vslam FOLDER --out DIR`: stereo (KITTI odometry layout) or RGB-D (TUM layout) visual
// SLAM, fed one frame at a time through the interface a robot would use (vslam/visual_slam.hpp).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <map>
#include <numeric>
#include <optional>
#include <unistd.h>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/spread.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/calibration_yaml.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/viz/render.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::cli {
namespace {

struct VslamFlags {
  std::string folder;
  std::string out;
  std::string camera;
  std::string calib;
  std::string ground_truth;
  std::string vocabulary;
  int features = 0;
  long max_frames = 0;
  long feature_frame = -1;
  bool no_local_ba = false;
  bool mono = false;
  bool quiet = false;
  bool progress = false;
  bool overwrite = false;
};

nlohmann::json stats_json(const eval::Statistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"max", s.max}, {"count", s.count}};
}

int vslam_command(const VslamFlags& flags) {
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  const std::string layout = io::detect_image_layout(flags.folder);
  io::ImageSequence seq = layout == "kitti"    ? io::read_kitti_stereo(flags.folder)
                          : layout == "euroc"  ? io::read_euroc_stereo(flags.folder)
                          : layout == "folder" ? io::read_image_folder(flags.folder)
                                               : io::read_tum_rgbd(flags.folder);
  // EuRoC's cameras are not rectified: rectify every pair (Bouguet) and track the rectified
  // left camera; its ground truth is the body's moved to that camera.
  std::optional<vision::StereoRectifier> rectifier;
  if (seq.rig) {
    if (!flags.calib.empty() || !flags.camera.empty()) throw std::invalid_argument("an EuRoC folder brings its own calibration: no --camera or --calib");
    int w = seq.rig->left.width, h = seq.rig->left.height;
    if (w <= 0 || h <= 0) {
      const cv::Mat first = vision::read_gray_image(seq.frames.front().image);
      w = first.cols;
      h = first.rows;
    }
    rectifier.emplace(*seq.rig, w, h);
    seq.calibration = rectifier->rectified();
  }
  if (!flags.calib.empty() && !flags.camera.empty()) throw std::invalid_argument("give --camera or --calib, not both");
  if (!flags.calib.empty()) {
    io::CameraCalibration c = io::read_calibration_yaml(flags.calib);
    if (seq.kind == io::SequenceKind::kStereo && !(c.baseline_m > 0.0)) c.baseline_m = seq.calibration.baseline_m;
    seq.calibration = c;
  } else if (!flags.camera.empty()) {
    seq.calibration = io::tum_calibration_preset(flags.camera);
  } else if (!seq.calibration_from_dataset) {
    if (seq.layout == "folder") {
      throw std::invalid_argument("a plain image folder has no calibration: give --calib FILE (fx, fy, cx, cy, distortion; stereo also baseline_m)");
    }
    throw std::invalid_argument("a " + seq.layout + " folder has no calibration: give --camera tum-fr1|tum-fr2|tum-fr3 or --calib FILE");
  }
  if (seq.kind == io::SequenceKind::kStereo && !flags.mono && !(seq.calibration.baseline_m > 0.0)) {
    throw std::invalid_argument("stereo images need the baseline between the rectified cameras: baseline_m in " +
                                (flags.calib.empty() ? std::string("the calibration") : flags.calib) + " (or --mono for the left images only)");
  }
  const io::SequenceKind kind = flags.mono ? io::SequenceKind::kMonocular : seq.kind;
  std::size_t n = seq.frames.size();
  if (flags.max_frames > 0) n = std::min<std::size_t>(n, static_cast<std::size_t>(flags.max_frames));
  io::Trajectory ground_truth;
  std::string ground_truth_path;
  if (!flags.ground_truth.empty()) {
    ground_truth = io::read_tum(flags.ground_truth);
    ground_truth_path = flags.ground_truth;
  } else if (seq.ground_truth) {
    ground_truth = *seq.ground_truth;
    ground_truth_path = seq.ground_truth_path;
    if (rectifier) {
      const core::SE3 T_body_camera = seq.rig->T_body_left * rectifier->T_left_rectified();
      for (core::SE3& T : ground_truth.poses) T = T * T_body_camera;
    }
  }

  // A calibration that no real camera has (fx in other units, a baseline of 0.05 mm) would be
  // tracked "ok" while measuring nothing: refused before any work, against the first image's size.
  if (n > 0) {
    int first_width = seq.calibration.width, first_height = seq.calibration.height;
    if (first_width == 0 || first_height == 0) {
      const cv::Mat first = vision::read_gray_image(seq.frames[0].image);
      first_width = first.cols;
      first_height = first.rows;
    }
    const bool stereo = seq.kind == io::SequenceKind::kStereo && !flags.mono;
    if (const std::string implausible = seq.calibration.implausibilities(first_width, first_height, stereo); !implausible.empty()) {
      const std::string source = !flags.calib.empty()    ? flags.calib
                                 : !flags.camera.empty() ? "--camera " + flags.camera
                                                         : seq.layout == "kitti" ? seq.folder + "/calib.txt"
                                                         : seq.folder + " (its calibration)";
      throw io::ParseError(source, 0, "implausible calibration: " + implausible);
    }
  }

  vslam::VisualSlamOptions options;
  // ORB-SLAM2's settings: 2000 for KITTI (stereo and monocular), 1000 for TUM.
  options.orb.features = flags.features > 0 ? flags.features : (seq.layout == "kitti" ? 2000 : 1000);
  if (seq.kind == io::SequenceKind::kRgbd) options.close_depth_baselines = 40.0;  // ORB-SLAM2 TUM*.yaml ThDepth
  options.local_ba = !flags.no_local_ba;
  if (!flags.vocabulary.empty()) {
    options.vocabulary = std::make_shared<const vision::Vocabulary>(vision::Vocabulary::load(flags.vocabulary));
    if (!flags.quiet) std::fprintf(stderr, "cairn vslam: vocabulary %s: %s\n", flags.vocabulary.c_str(), options.vocabulary->description().c_str());
  } else if (!flags.quiet) {
    std::fprintf(stderr, "cairn vslam: no --vocabulary: no loop closure; relocalisation tries the 8 most recent keyframes only\n");
  }
  if (!flags.quiet) {
    std::fprintf(stderr, "cairn vslam: %s %s%s, %zu frames, fx %.6g, %s %.6g m%s\n", seq.layout.c_str(),
                 std::string(io::to_string(kind)).c_str(), flags.mono ? " (the left / colour images only; scale unobservable)" : "", n,
                 seq.calibration.fx,
                 seq.kind == io::SequenceKind::kStereo ? "baseline" : "virtual baseline",
                 seq.kind == io::SequenceKind::kStereo ? seq.calibration.baseline_m : seq.calibration.virtual_baseline_m,
                 seq.calibration.has_distortion() ? ", distorted (keypoints undistorted)" : "");
    for (const std::string& note : seq.notes) std::fprintf(stderr, "cairn vslam: %s\n", note.c_str());
  }

  io::OutputDirectory out(flags.out, flags.overwrite);
  vslam::VisualSlam slam(seq.calibration, kind, options);
  std::vector<vslam::FrameResult> results;
  std::vector<double> read_s;
  const bool tty = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  const auto start = std::chrono::steady_clock::now();
  const std::size_t feature_frame = flags.feature_frame >= 0 ? static_cast<std::size_t>(flags.feature_frame) : n / 2;
  if (flags.feature_frame >= 0 && feature_frame >= n) {
    throw UsageError("--feature-frame " + std::to_string(flags.feature_frame) + ": this run has " + std::to_string(n) +
                     " frames (0 to " + std::to_string(n - 1) + ")");
  }
  cv::Mat feature_image;
  std::vector<cv::KeyPoint> feature_keypoints;
  std::vector<signed char> feature_states;
  vslam::TrackingHealth last_health = vslam::TrackingHealth::kOk;
  std::string last_note;
  int messages = 0;
  int width = seq.calibration.width, height = seq.calibration.height;
  for (std::size_t k = 0; k < n && !interrupted(); ++k) {
    const io::ImageFrame& frame = seq.frames[k];
    const auto read_start = std::chrono::steady_clock::now();
    cv::Mat image = vision::read_gray_image(frame.image, width, height);
    width = image.cols;
    height = image.rows;
    vslam::FrameResult r;
    if (kind == io::SequenceKind::kMonocular) {
      if (rectifier) {
        cv::Mat unused, rectified;
        rectifier->rectify(image, image, rectified, unused);
        image = rectified;
      }
      read_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - read_start).count());
      r = slam.add_monocular(frame.time, image);
    } else if (seq.kind == io::SequenceKind::kStereo) {
      cv::Mat right = vision::read_gray_image(frame.right_image, width, height);
      if (rectifier) {
        cv::Mat left_rectified, right_rectified;
        rectifier->rectify(image, right, left_rectified, right_rectified);
        image = left_rectified;
        right = right_rectified;
      }
      read_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - read_start).count());
      r = slam.add_stereo(frame.time, image, right);
    } else {
      const cv::Mat depth = vision::read_depth_image(frame.depth_image, width, height);
      read_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - read_start).count());
      r = slam.add_rgbd(frame.time, image, depth);
    }
    if (k == feature_frame) {
      feature_image = image;
      feature_keypoints = r.keypoints;
      feature_states = r.keypoint_states;
    }
    r.keypoints.clear();
    r.keypoint_states.clear();
    // Health changes, and events (a new note while not ok: initialisation steps, new maps); at most
    // 100 such lines, the rest are in frames.csv.
    const bool changed = r.health != last_health || (r.health != vslam::TrackingHealth::kOk && r.note != last_note);
    if (!flags.quiet && changed && messages < 100) {
      std::fprintf(stderr, "%s[frame %zu] %s%s%s\n", tty ? "\r" : "", k, std::string(vslam::to_string(r.health)).c_str(),
                   r.note.empty() ? "" : ": ", r.note.c_str());
      if (++messages == 100) std::fprintf(stderr, "cairn vslam: further health messages are only in frames.csv\n");
    }
    last_health = r.health;
    last_note = r.note;
    if ((tty || flags.progress) && (k % 10 == 0 || k + 1 == n)) {
      std::fprintf(stderr, "%sframe %zu / %zu  %.0f ms  %d inliers  %zu keyframes%s", tty ? "\r" : "", k + 1, n, 1e3 * r.times.total_s,
                   r.inliers, slam.summary().keyframes, tty ? "   " : "\n");
      std::fflush(stderr);
    }
    results.push_back(std::move(r));
  }
  if (tty) std::fprintf(stderr, "\n");
  const bool stopped = interrupted();
  if (stopped) std::fprintf(stderr, "cairn vslam: interrupted by %s after %zu frames: writing the result so far\n", interrupt_signal_name(), results.size());
  if (results.empty()) throw std::runtime_error("no frame was processed");
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Trajectories (every frame, at the final keyframe poses) and keyframes.
  const std::vector<core::SE3> poses = slam.trajectory();
  // TUM: the tracked frames only (a lost frame has no pose, as ORB-SLAM2's SaveTrajectoryTUM);
  // KITTI: one line per frame as its devkit needs, a lost frame carrying the motion model's guess.
  // Frames of map segments that never merged with the main map (the one of the first keyframe)
  // are in frames of their own: trajectory_map_<segment>.tum.
  const std::vector<int> segments = slam.frame_segments();
  const int main_segment = slam.main_segment();
  io::Trajectory trajectory, every_frame;
  std::map<int, io::Trajectory> other_maps;
  for (std::size_t k = 0; k < results.size(); ++k) {
    every_frame.stamps.push_back(results[k].time);
    every_frame.poses.push_back(poses[k]);
    if (!results[k].tracked || segments[k] < 0) continue;
    io::Trajectory& t = segments[k] == main_segment ? trajectory : other_maps[segments[k]];
    t.stamps.push_back(results[k].time);
    t.poses.push_back(poses[k]);
  }
  if (trajectory.poses.empty()) throw std::runtime_error("no frame was tracked: nothing to write (see the messages above)");
  io::write_output(out.staging_path("trajectory.tum"), [&](std::ostream& o) { io::write_tum(o, trajectory); });
  for (const auto& [id, t] : other_maps) {
    io::write_output(out.staging_path("trajectory_map_" + std::to_string(id) + ".tum"), [&](std::ostream& o) { io::write_tum(o, t); });
  }
  io::write_output(out.staging_path("trajectory.kitti"), [&](std::ostream& o) { io::write_kitti(o, every_frame); });
  io::Trajectory keyframes;
  for (const std::size_t k : slam.keyframe_frames()) {
    if (segments[k] != main_segment) continue;  // keyframes of the main map, as trajectory.tum
    keyframes.stamps.push_back(results[k].time);
    keyframes.poses.push_back(poses[k]);  // keyframes are tracked frames
  }
  io::write_output(out.staging_path("keyframes.tum"), [&](std::ostream& o) { io::write_tum(o, keyframes); });
  std::vector<Eigen::Vector3f> map_points;
  for (const Eigen::Vector3d& p : slam.map_points()) map_points.push_back(p.cast<float>());
  io::write_output(out.staging_path("map_points.ply"), [&](std::ostream& o) {
    io::write_ply(o, map_points, "cairn vslam map points, world = the first camera (x right, y down, z forward)");
  });
  io::write_output(out.staging_path("frames.csv"), [&](std::ostream& o) {
    o << "frame,time_s,health,tracked,segment,keyframe,relocalised,loop_closed,new_map,features,stereo_points,first_stage_matches,used_reference,used_image_alignment,inliers,inlier_ratio,"
         "sigma_position_m,features_ms,stereo_ms,tracking_ms,mapping_ms,total_ms,note\n";
    for (const auto& r : results) {
      o << r.frame << ',' << r.time.to_seconds_string() << ',' << vslam::to_string(r.health) << ',' << (r.tracked ? 1 : 0) << ','
        << segments[r.frame] << ',' << (r.keyframe ? 1 : 0) << ',' << (r.relocalised ? 1 : 0) << ',' << (r.loop_closed ? 1 : 0) << ','
        << (r.new_map ? 1 : 0) << ',' << r.features << ',' << r.stereo_points << ',' << r.motion_matches << ','
        << (r.used_reference ? 1 : 0) << ',' << (r.used_image_alignment ? 1 : 0) << ',' << r.inliers << ',' << r.inlier_ratio << ',' << r.sigma_position_m << ','
        << 1e3 * r.times.features_s << ',' << 1e3 * r.times.stereo_s << ',' << 1e3 * r.times.tracking_s << ','
        << 1e3 * r.times.mapping_s << ',' << 1e3 * r.times.total_s << ",\"" << r.note << "\"\n";
    }
  });

  // Evaluation against the ground truth, when there is one.
  nlohmann::json evaluation = nullptr;
  viz::Figure figure;
  figure.title = "cairn vslam: " + seq.folder;
  figure.width_px = 1000;
  figure.height_px = 800;
  viz::Axes axes;
  axes.title = "top view (x right, z forward of the first camera)";
  axes.x_label = "x [m]";
  axes.y_label = "z [m]";
  axes.equal_aspect = true;
  if (!ground_truth.poses.empty()) {
    eval::ApeOptions ape_options;
    ape_options.alignment.method = kind == io::SequenceKind::kMonocular ? eval::AlignmentMethod::kSim3 : eval::AlignmentMethod::kSE3;
    ape_options.association.max_time_difference_s = 0.02;
    const eval::ApeResult ape = eval::evaluate_ape(ground_truth, trajectory, ape_options);
    eval::RpeOptions rpe_options;
    rpe_options.association = ape_options.association;
    const eval::RpeResult rpe_t = eval::evaluate_rpe(ground_truth, trajectory, rpe_options);
    rpe_options.relation = eval::PoseRelation::kRotationAngleDeg;
    const eval::RpeResult rpe_r = eval::evaluate_rpe(ground_truth, trajectory, rpe_options);
    evaluation = {{"ground_truth", ground_truth_path}};
    if (ape.outcome.ok()) {
      evaluation[kind == io::SequenceKind::kMonocular ? "ate_sim3_aligned_m" : "ate_se3_aligned_m"] = stats_json(ape.statistics);
      if (kind == io::SequenceKind::kMonocular) evaluation["sim3_scale"] = ape.alignment.scale;
      // The ground truth drawn in the estimate's frame: T_est = alignment^-1 * T_gt.
      viz::Series gt;
      gt.label = kind == io::SequenceKind::kMonocular ? "ground truth (estimate Sim(3)-aligned)" : "ground truth (estimate SE(3)-aligned)";
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
      axes.title = std::string("top view, estimate ") + (kind == io::SequenceKind::kMonocular ? "Sim(3)" : "SE(3)") +
                   "-aligned to the ground truth (x, z of the ground truth's frame)";
      axes.series.push_back(gt);
      axes.series.push_back(est);
      // Drift at the end with no alignment, both trajectories re-based on their first pair.
      const Eigen::Matrix4d d_ref = ape.reference.front().inverse() * ape.reference.back();
      const Eigen::Matrix4d aligned_first = ape.estimate.front();
      const Eigen::Matrix4d d_est = aligned_first.inverse() * ape.estimate.back();
      evaluation["end_point_drift_m"] = (d_ref.block<3, 1>(0, 3) - d_est.block<3, 1>(0, 3)).norm();
      double path = 0.0;
      for (std::size_t i = 1; i < ape.reference.size(); ++i) path += (ape.reference[i].block<3, 1>(0, 3) - ape.reference[i - 1].block<3, 1>(0, 3)).norm();
      evaluation["path_length_m"] = path;
      evaluation["frames_compared"] = ape.reference.size();
    } else {
      evaluation["ate_error"] = ape.outcome.message;
    }
    if (rpe_t.outcome.ok()) evaluation["rpe_1_frame_translation_m"] = stats_json(rpe_t.statistics);
    if (rpe_r.outcome.ok()) evaluation["rpe_1_frame_rotation_deg"] = stats_json(rpe_r.statistics);
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
  io::write_output(out.staging_path("trajectory.png"), [&](std::ostream& o) { o << png.bytes; });
  if (!feature_image.empty()) {
    const std::string bytes = vision::draw_features_png(feature_image, feature_keypoints, feature_states,
                                                          "frame " + std::to_string(feature_frame));
    io::write_output(out.staging_path("features.png"), [&](std::ostream& o) { o << bytes; });
  }

  // Report.
  const vslam::VisualSlamSummary& s = slam.summary();
  std::vector<double> tracking, features_s, total, mapping;
  for (const auto& r : results) {
    tracking.push_back(r.times.stereo_s + r.times.tracking_s);
    features_s.push_back(r.times.features_s);
    mapping.push_back(r.times.mapping_s);
    total.push_back(r.times.total_s);
  }
  nlohmann::json report;
  report["input"] = {{"folder", seq.folder},
                     {"layout", seq.layout},
                     {"kind", std::string(io::to_string(kind))},
                     {"frames_listed", seq.frames.size()},
                     {"frames_processed", results.size()},
                     {"times_from_file", seq.times_from_file},
                     {"notes", seq.notes},
                     {"calibration",
                      {{"fx", seq.calibration.fx}, {"fy", seq.calibration.fy}, {"cx", seq.calibration.cx}, {"cy", seq.calibration.cy},
                       {"distortion", {seq.calibration.k1, seq.calibration.k2, seq.calibration.p1, seq.calibration.p2, seq.calibration.k3}},
                       {"baseline_m", seq.calibration.baseline_m}, {"virtual_baseline_m", seq.calibration.virtual_baseline_m},
                       {"depth_units_per_m", seq.calibration.depth_units_per_m},
                       {"source", !flags.calib.empty() ? flags.calib : (!flags.camera.empty() ? "preset " + flags.camera : "dataset")}}}};
  report["options"] = {{"features", options.orb.features},
                       {"scale_factor", options.orb.scale_factor},
                       {"levels", options.orb.levels},
                       {"fast_thresholds", {options.orb.initial_fast_threshold, options.orb.min_fast_threshold}},
                       {"close_depth_baselines", options.close_depth_baselines},
                       {"lost_below_inliers", options.lost_below_inliers},
                       {"degraded_below_inliers", options.degraded_below_inliers},
                       {"local_ba", options.local_ba},
                       {"keyframe_culling", options.keyframe_culling},
                       {"keyframe_culling_redundancy", options.keyframe_culling_redundancy},
                       {"image_alignment", options.image_alignment},
                       {"image_alignment_min_correlation", options.image_alignment_min_correlation},
                       {"fuse_points", options.fuse_points},
                       {"monocular_keyframe_turn_fov", options.monocular_keyframe_turn_fov}};
  report["summary"] = {{"frames", s.frames},
                       {"ok", s.frames_ok},
                       {"degraded", s.frames_degraded},
                       {"lost", s.frames_lost},
                       {"keyframes", s.keyframes},
                       {"map_points_created", s.map_points},
                       {"map_points_culled", s.map_points_culled},
                       {"map_points", map_points.size()},
                       {"local_bundle_adjustments", s.local_bas},
                       {"reference_fallbacks", s.reference_fallbacks},
                       {"interrupted", stopped}};
  report["timing"] = {{"total_s", total_s},
                      {"per_frame_ms", spread_json_ms(total)},
                      {"features_ms", spread_json_ms(features_s)},
                      {"tracking_ms", spread_json_ms(tracking)},
                      {"mapping_ms", spread_json_ms(mapping)},
                      {"image_read_ms", spread_json_ms(read_s)},
                      {"local_ba_s", s.local_ba_s},
                      {"threads", "ORB of the two images in parallel; everything else on one thread"}};
  {
    nlohmann::json maps = nlohmann::json::array();
    std::map<int, std::size_t> frames_in;
    for (std::size_t k = 0; k < results.size(); ++k) {
      if (results[k].tracked && segments[k] >= 0) ++frames_in[segments[k]];
    }
    for (const auto& [id, count] : frames_in) {
      maps.push_back({{"segment", id},
                      {"main", id == main_segment},
                      {"tracked_frames", count},
                      {"trajectory", id == main_segment ? "trajectory.tum" : "trajectory_map_" + std::to_string(id) + ".tum"}});
    }
    report["maps"] = maps;
  }
  report["evaluation"] = evaluation;
  report["place_recognition"] = {{"vocabulary", flags.vocabulary.empty() ? nlohmann::json(nullptr) : nlohmann::json(flags.vocabulary)},
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
  for (const vslam::LoopRecord& l : s.loops) {
    report["place_recognition"]["candidates"].push_back({{"keyframe", l.keyframe},
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
  report["not_implemented"] = {"local mapping in its own thread"};
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  out.commit();

  if (!flags.quiet) {
    std::printf("%zu frames: %zu ok, %zu degraded, %zu lost; %zu relocalisations, %zu loops closed, %zu revisits verified, %zu new maps (%zu merged); %zu keyframes, %zu map points; per frame median %.1f ms "
                "(tracking %.1f ms, ORB %.1f ms, mapping %.1f ms)\n",
                s.frames, s.frames_ok, s.frames_degraded, s.frames_lost, s.relocalisations, s.loops_accepted, s.revisits_verified, s.maps_started, s.maps_merged,
                s.keyframes, map_points.size(), spread(total).median * 1e3,
                spread(tracking).median * 1e3, spread(features_s).median * 1e3, spread(mapping).median * 1e3);
    if (!evaluation.is_null() && evaluation.contains("ate_sim3_aligned_m")) {
      std::printf("against %s, the %zu tracked frames of %zu: ATE (Sim(3)-aligned, scale %.4f: monocular scale is not observable) "
                  "RMSE %.4f m\n",
                  ground_truth_path.c_str(), evaluation["frames_compared"].get<std::size_t>(), results.size(),
                  evaluation["sim3_scale"].get<double>(), evaluation["ate_sim3_aligned_m"]["rmse"].get<double>());
    }
    if (!evaluation.is_null() && evaluation.contains("ate_se3_aligned_m")) {
      std::printf("against %s, the main map's %zu tracked frames of %zu: ATE (SE(3)-aligned) RMSE %.4f m; end-point drift %.3f m "
                  "over %.1f m; RPE (1 frame) RMSE %.4f m, %.4f deg\n",
                  ground_truth_path.c_str(), evaluation["frames_compared"].get<std::size_t>(), results.size(),
                  evaluation["ate_se3_aligned_m"]["rmse"].get<double>(),
                  evaluation["end_point_drift_m"].get<double>(), evaluation["path_length_m"].get<double>(),
                  evaluation.value("rpe_1_frame_translation_m", nlohmann::json{{"rmse", NAN}})["rmse"].get<double>(),
                  evaluation.value("rpe_1_frame_rotation_deg", nlohmann::json{{"rmse", NAN}})["rmse"].get<double>());
    }
    std::printf("wrote %s\n", flags.out.c_str());
  }
  return stopped ? 130 : 0;
}

}  // namespace

Runner register_vslam(CLI::App& app) {
  auto flags = std::make_shared<VslamFlags>();
  CLI::App* cmd = &app;
  cmd->add_option("folder", flags->folder, "KITTI odometry folder (calib.txt, image_0/1 or image_l/r), EuRoC MAV folder (mav0/cam0, cam1), TUM RGB-D folder, or a plain folder: images (monocular) or left/ and right/ (rectified stereo), with --calib")->required();
  cmd->add_option("--out", flags->out, "Output directory (trajectory.tum/.kitti, keyframes.tum, map_points.ply, frames.csv, report.json, trajectory.png, features.png)");
  cmd->add_option("--camera", flags->camera, "Calibration preset for TUM RGB-D: tum-fr1, tum-fr2, tum-fr3");
  cmd->add_option("--calib", flags->calib, "Calibration YAML (fx, fy, cx, cy, k1..k3, p1, p2, baseline_m, depth_units_per_m, virtual_baseline_m)");
  cmd->add_option("--ground-truth", flags->ground_truth, "TUM-format ground truth (default: the dataset's poses.txt / groundtruth.txt)");
  cmd->add_option("--vocabulary", flags->vocabulary, "Bag-of-words vocabulary (cairn vocabulary train, or DBoW2 .txt/.yml): loop closure and relocalisation");
  cmd->add_option("--features", flags->features, "ORB features per image (default 2000 stereo, 1000 RGB-D, as ORB-SLAM2)")
      ->check(checks::whole_range(10, 100000));
  cmd->add_option("--max-frames", flags->max_frames, "Process at most N frames")->check(checks::count(std::numeric_limits<long>::max()));
  cmd->add_option("--feature-frame", flags->feature_frame, "Frame drawn in features.png, 0-based (default: the middle one)")
      ->check(checks::count_or_zero(std::numeric_limits<long>::max()));
  cmd->add_flag("--mono", flags->mono, "Monocular: the left (stereo) or colour (TUM) images only; the scale is not observable (a plain folder of images is monocular anyway)");
  cmd->add_flag("--no-local-ba", flags->no_local_ba, "Skip local bundle adjustment (visual odometry only)");
  cmd->add_flag("-q,--quiet", flags->quiet, "No progress or summary");
  cmd->add_flag("--progress", flags->progress, "Progress lines even when stderr is not a terminal");
  cmd->add_flag("--overwrite", flags->overwrite, "Replace an existing output directory's files");
  return [flags] { return vslam_command(*flags); };
}

}  // namespace cairn::cli
