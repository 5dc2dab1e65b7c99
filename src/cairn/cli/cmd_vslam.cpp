// `cairn vslam FOLDER --out DIR`: stereo (KITTI odometry layout) or RGB-D (TUM layout) visual
// SLAM, fed one frame at a time through the interface a robot would use (vslam/visual_slam.hpp).
// The images are prepared by vslam/image_input.hpp, or, for `cairn vslam BAG`, read from the bag's
// image topics by vslam/bag_images.hpp and bag_frame_reader.hpp; the files, the evaluation against
// ground truth and report.json are vslam/outputs.hpp's; the options' keys (--config, --set,
// --print-config) are vslam/config.hpp's.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <utility>

#include "cairn/bag/bag.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/vslam_flags.hpp"
#include "cairn/cli/vslam_input.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/eval/spread.hpp"
#include "cairn/io/calibration_yaml.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/vslam/bag_frame_reader.hpp"
#include "cairn/vslam/bag_images.hpp"
#include "cairn/vslam/config.hpp"
#include "cairn/vslam/evaluation.hpp"
#include "cairn/vslam/foxglove_output.hpp"
#include "cairn/vslam/image_input.hpp"
#include "cairn/vslam/inertial_input.hpp"
#include "cairn/vslam/map_file.hpp"
#include "cairn/vslam/outputs.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::cli {
namespace {


/// `options` (the dataset's settings), then --config, --set and the dedicated flags, which win;
/// refused with exit status 2 when a key or the result is invalid. Printed with --print-config.
vslam::VisualSlamOptions configured_options(const VslamFlags& flags, vslam::VisualSlamOptions options) {
  if (!flags.config.empty()) vslam::configuration().load(flags.config, options);
  try {
    for (const std::string& assignment : flags.set) vslam::configuration().set(assignment, options);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  if (flags.features > 0) options.orb.features = flags.features;
  if (flags.no_local_ba) options.local_ba = false;
  if (std::string p; !options.is_valid(&p)) throw UsageError("invalid configuration: " + p);
  if (flags.print_config) std::cout << vslam::configuration().yaml(options);
  return options;
}

vslam::VisualSlamOptions make_options(const VslamFlags& flags, const io::ImageSequence& seq) {
  vslam::VisualSlamOptions options = configured_options(flags, vslam::dataset_options(seq.layout, seq.kind));
  if (!flags.vocabulary.empty()) {
    options.vocabulary = std::make_shared<const vision::Vocabulary>(vision::Vocabulary::load(flags.vocabulary));
    if (!flags.quiet) std::fprintf(stderr, "cairn vslam: vocabulary %s: %s\n", flags.vocabulary.c_str(), options.vocabulary->description().c_str());
  } else if (!flags.quiet) {
    std::fprintf(stderr, "cairn vslam: no --vocabulary: no loop closure; relocalisation tries the 8 most recent keyframes only\n");
  }
  return options;
}

void print_input(const io::ImageSequence& seq, io::SequenceKind kind, std::size_t n, const VslamFlags& flags) {
  std::fprintf(stderr, "cairn vslam: %s %s%s, %zu frames, fx %.6g, %s %.6g m%s\n", seq.layout.c_str(),
               std::string(io::to_string(kind)).c_str(), flags.mono ? " (the left / colour images only; scale unobservable)" : "", n,
               seq.calibration.fx,
               seq.kind == io::SequenceKind::kStereo ? "baseline" : "virtual baseline",
               seq.kind == io::SequenceKind::kStereo ? seq.calibration.baseline_m : seq.calibration.virtual_baseline_m,
               seq.calibration.has_distortion() ? ", distorted (keypoints undistorted)" : "");
  for (const std::string& note : seq.notes) std::fprintf(stderr, "cairn vslam: %s\n", note.c_str());
}

/// --imu and its companions: refused when they make no sense, then read (nothing without --imu
/// or --imu-topic).
std::optional<vslam::VisualInertialInput> read_imu(const VslamFlags& flags, const VslamInput& input,
                                                   const std::optional<vision::StereoRectifier>& rectifier) {
  const bool offset_given = flags.command != nullptr && flags.command->count("--imu-time-offset") > 0;
  checks::refuse_imu_companions_without_imu(flags.uses_imu(), !flags.imu_calibration.empty(), "--camera-extrinsic",
                                            !flags.camera_extrinsic.empty(), offset_given);
  if (!flags.uses_imu()) return std::nullopt;
  if (!flags.imu.empty() && !flags.imu_topic.empty()) {
    throw UsageError("--imu and --imu-topic: give one (--imu-topic reads sensor_msgs/Imu from the images' bag, --imu a file, folder or bag)");
  }
  if (!flags.imu_topic.empty() && !input.bag) throw UsageError("--imu-topic reads sensor_msgs/Imu from the images' bag, but FOLDER is not a bag: give --imu PATH");
  if (!flags.localize_in.empty()) throw UsageError("--imu with --localize-in: localising in a saved map does not use an IMU in this version");
  vslam::VisualInertialInputRequest request;
  request.imu.imu = flags.imu;
  if (!flags.imu_topic.empty()) request.imu.bag = flags.folder;
  request.imu.topic = flags.imu_topic;
  request.imu.calibration = flags.imu_calibration;
  request.imu.time_offset_s = flags.imu_time_offset_s;
  request.camera_extrinsic = flags.camera_extrinsic;
  vslam::VisualInertialInput imu = vslam::read_visual_inertial_input(request, input.sequence(), rectifier ? &*rectifier : nullptr);
  if (imu.imu.samples.empty()) throw std::runtime_error("--imu " + imu.imu.source + ": no IMU reading");
  if (!flags.quiet) {
    std::fprintf(stderr, "cairn vslam: IMU %s: %zu readings over %.1f s; noise from %s; camera extrinsic: %s\n", imu.imu.source.c_str(),
                 imu.imu.samples.size(), imu.imu.samples.back().stamp.seconds() - imu.imu.samples.front().stamp.seconds(),
                 imu.imu.calibration_file.empty() ? "EuRoC's ADIS16448 (defaults)" : imu.imu.calibration_file.c_str(),
                 imu.camera_extrinsic.c_str());
    for (const std::string& note : imu.imu.notes) std::fprintf(stderr, "cairn vslam: %s\n", note.c_str());
  }
  return imu;
}

/// Feeds frames 0 .. n-1 to `slam` until the last or a signal (with an IMU, its readings up to
/// each frame first), printing health changes and progress.
vslam::RunRecord run_frames(vslam::VisualSlam& slam, vslam::FrameSource& reader, const io::ImageSequence& seq, std::size_t n,
                            std::size_t feature_frame, const VslamFlags& flags, const vslam::VisualInertialInput* imu) {
  vslam::RunRecord run;
  run.features.frame = feature_frame;
  const bool tty = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  const auto start = core::Clock::now();
  vslam::TrackingHealth last_health = vslam::TrackingHealth::kOk;
  std::string last_note;
  int messages = 0;
  std::size_t next_imu = 0;
  for (std::size_t k = 0; k < n && !interrupted(); ++k) {
    const vslam::FrameImages images = reader.read(k);
    run.read_s.push_back(images.read_s);
    if (imu != nullptr) next_imu = vslam::feed_imu_until(slam, imu->imu.samples, next_imu, seq.frames[k].time);
    vslam::FrameResult r = vslam::add_frame(slam, seq.frames[k].time, images);
    if (k == feature_frame) {
      run.features.image = images.gray;
      run.features.keypoints = r.keypoints;
      run.features.states = r.keypoint_states;
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
    run.frames.push_back(std::move(r));
  }
  if (tty) std::fprintf(stderr, "\n");
  run.interrupted = interrupted();
  if (run.interrupted) std::fprintf(stderr, "cairn vslam: interrupted by %s after %zu frames: writing the result so far\n", interrupt_signal_name(), run.frames.size());
  if (run.frames.empty()) throw std::runtime_error("no frame was processed");
  run.total_s = core::seconds_since(start);
  return run;
}

void print_summary(const vslam::VisualSlamSummary& s, const vslam::RunRecord& run, const vslam::WrittenOutputs& written,
                   const VslamFlags& flags) {
  const vslam::FrameTimeSeries t = vslam::frame_times(run.frames);
  std::printf("%zu frames: %zu ok, %zu degraded, %zu lost; %zu relocalisations, %zu loops closed, %zu revisits verified, %zu new maps (%zu merged); %zu keyframes, %zu map points; per frame median %.1f ms "
              "(tracking %.1f ms, ORB %.1f ms, mapping %.1f ms)\n",
              s.frames, s.frames_ok, s.frames_degraded, s.frames_lost, s.relocalisations, s.loops_accepted, s.revisits_verified, s.maps_started, s.maps_merged,
              s.keyframes, written.map_points, eval::spread(t.total_s).median * 1e3,
              eval::spread(t.tracking_s).median * 1e3, eval::spread(t.features_s).median * 1e3, eval::spread(t.mapping_s).median * 1e3);
  if (const std::optional<vslam::GroundTruthEvaluation>& e = written.evaluation; e && e->ape.outcome.ok() && e->sim3) {
    std::printf("against %s, the %zu tracked frames of %zu: ATE (Sim(3)-aligned, scale %.4f: monocular scale is not observable) "
                "RMSE %.4f m\n",
                e->ground_truth_path.c_str(), e->ape.reference.size(), run.frames.size(), e->ape.alignment.scale, e->ape.statistics.rmse);
  } else if (e && e->ape.outcome.ok()) {
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    std::printf("against %s, the main map's %zu tracked frames of %zu: ATE (SE(3)-aligned) RMSE %.4f m; end-point drift %.3f m "
                "over %.1f m; RPE (1 frame) RMSE %.4f m, %.4f deg\n",
                e->ground_truth_path.c_str(), e->ape.reference.size(), run.frames.size(), e->ape.statistics.rmse,
                e->end_point_drift_m, e->path_length_m,
                e->rpe_translation.outcome.ok() ? e->rpe_translation.statistics.rmse : kNone,
                e->rpe_rotation.outcome.ok() ? e->rpe_rotation.statistics.rmse : kNone);
  }
  if (s.inertial_estimates + s.inertial_estimates_refused > 0 || s.frames_carried_by_imu > 0) {
    std::printf("IMU: %zu inertial estimates (%zu refused%s%s), initialised at %.2f s; %zu frames carried by it, %zu contradicting it, "
                "%zu flagged for monocular scale drift\n",
                s.inertial_estimates, s.inertial_estimates_refused, s.inertial_refusal.empty() ? "" : ", the last: ",
                s.inertial_refusal.c_str(), s.inertial_initialised_at_s, s.frames_carried_by_imu, s.frames_contradicting_imu,
                s.frames_scale_drifted);
  }
  std::printf("wrote %s\n", flags.out.c_str());
}

/// --first-frame: the sequence from frame K on (ground truth pairs by stamp, so it still holds).
void skip_first_frames(VslamInput& input, const VslamFlags& flags) {
  if (flags.first_frame <= 0) return;
  io::ImageSequence& seq = input.sequence();
  if (input.bag) throw UsageError("--first-frame is for dataset folders; a bag's frames are read in order from the first");
  if (static_cast<std::size_t>(flags.first_frame) >= seq.frames.size()) {
    throw UsageError("--first-frame " + std::to_string(flags.first_frame) + ": the sequence has " + std::to_string(seq.frames.size()) + " frames");
  }
  seq.frames.erase(seq.frames.begin(), seq.frames.begin() + flags.first_frame);
}

/// --save-map and --localize-in: usage checks before any work.
void check_map_flags(const VslamFlags& flags) {
  if (!flags.save_map.empty() && !flags.localize_in.empty()) {
    throw UsageError("--save-map and --localize-in exclude each other: localising never changes the map");
  }
  if (flags.save_map.empty()) return;
  if (io::is_standard_output(flags.save_map)) throw std::invalid_argument("--save-map needs a file: the map is binary");
  io::resolve_output(flags.save_map);
  io::check_file_outside_directory("--save-map", flags.save_map, "--out", flags.out,
                                   {"trajectory.tum", "trajectory.kitti", "keyframes.tum", "map_points.ply", "frames.csv", "report.json"});
}

/// The saved map of --localize-in, refused (naming the file and why) when these images cannot be
/// localised in it; a warning when its vocabulary was another.
vslam::SavedVisualMap read_map_to_localise_in(const VslamFlags& flags, const io::ImageSequence& seq, io::SequenceKind kind,
                                              const vslam::VisualSlamOptions& options) {
  vslam::SavedVisualMap map = vslam::read_saved_map(flags.localize_in);
  if (const std::string why = vslam::map_incompatibility(map, seq.calibration, kind, options.vocabulary.get()); !why.empty()) {
    throw std::runtime_error("--localize-in " + flags.localize_in + ": cannot localise these images in this map: " + why);
  }
  if (const std::string warning = vslam::vocabulary_mismatch(map, options.vocabulary.get()); !warning.empty()) {
    std::fprintf(stderr, "cairn vslam: warning: %s\n", warning.c_str());
  }
  if (!flags.quiet) {
    std::fprintf(stderr, "cairn vslam: localising in %s: %zu keyframes, %zu map points (mapped from %s)\n", flags.localize_in.c_str(),
                 map.keyframes.size(), map.points.size(), map.source.c_str());
  }
  return map;
}

int vslam_command(const VslamFlags& flags) {
  if (flags.print_config && flags.folder.empty()) {  // no dataset: VisualSlamOptions' defaults
    configured_options(flags, vslam::VisualSlamOptions{});
    return 0;
  }
  if (flags.out.empty() && !flags.print_config) throw std::invalid_argument("--out DIR is required");
  check_map_flags(flags);
  VslamInput input = read_vslam_input(flags);
  skip_first_frames(input, flags);
  io::ImageSequence& seq = input.sequence();
  const std::optional<vision::StereoRectifier> rectifier = resolve_calibration(input, flags);
  const io::SequenceKind kind = flags.mono ? io::SequenceKind::kMonocular : seq.kind;
  std::size_t n = seq.frames.size();
  if (flags.max_frames > 0) n = std::min<std::size_t>(n, static_cast<std::size_t>(flags.max_frames));
  const vslam::GroundTruth ground_truth = resolve_ground_truth(seq, flags, rectifier);
  check_calibration(input, flags);
  const std::optional<vslam::VisualInertialInput> imu = read_imu(flags, input, rectifier);
  const vslam::VisualSlamOptions options = imu ? vslam::with_imu(make_options(flags, seq), *imu) : make_options(flags, seq);
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  if (!flags.quiet) print_input(seq, kind, n, flags);

  if (!flags.mcap.empty()) {
    if (io::is_standard_output(flags.mcap)) throw std::invalid_argument("--mcap needs a file: MCAP is binary");
    io::resolve_output(flags.mcap);
    io::check_file_outside_directory("--mcap", flags.mcap, "--out", flags.out, {"trajectory.tum", "report.json"});
  }
  io::OutputDirectory out(flags.out, flags.overwrite);
  std::unique_ptr<vslam::VisualSlam> slam_owner =
      flags.localize_in.empty() ? std::make_unique<vslam::VisualSlam>(seq.calibration, kind, options)
                                : std::make_unique<vslam::VisualSlam>(read_map_to_localise_in(flags, seq, kind, options), options);
  vslam::VisualSlam& slam = *slam_owner;
  const std::size_t feature_frame = flags.feature_frame >= 0 ? static_cast<std::size_t>(flags.feature_frame) : n / 2;
  if (flags.feature_frame >= 0 && feature_frame >= n) {
    throw UsageError("--feature-frame " + std::to_string(flags.feature_frame) + ": this run has " + std::to_string(n) +
                     " frames (0 to " + std::to_string(n - 1) + ")");
  }
  std::unique_ptr<vslam::FrameSource> reader;
  if (input.bag) {
    reader = std::make_unique<vslam::BagFrameReader>(*input.bag, kind);
  } else {
    reader = std::make_unique<vslam::FrameReader>(seq, kind, rectifier ? &*rectifier : nullptr);
  }
  const vslam::RunRecord run = run_frames(slam, *reader, seq, n, feature_frame, flags, imu ? &*imu : nullptr);
  const vslam::RunInput run_input{seq, kind, calibration_source(input, flags), flags.vocabulary,
                                  input.bag ? input.bag->topics : std::vector<std::pair<std::string, std::string>>{}, flags.localize_in,
                                  static_cast<std::size_t>(flags.first_frame)};
  const vslam::WrittenOutputs written = vslam::write_outputs(out, slam, run_input, run, ground_truth);
  out.commit();
  if (!flags.save_map.empty()) {
    vslam::write_saved_map(flags.save_map, slam.saved_map(vslam::configuration().json(options).dump(), seq.folder));
    if (!flags.quiet) std::printf("wrote the map for reuse (cairn vslam --localize-in) to %s\n", flags.save_map.c_str());
  }
  if (!flags.mcap.empty()) vslam::write_foxglove_mcap(flags.mcap, slam, run);
  if (!flags.quiet) print_summary(slam.summary(), run, written, flags);
  if (!flags.quiet && slam.localization_only()) {
    std::size_t localised = 0;
    for (const vslam::FrameResult& r : run.frames) localised += r.tracked ? 1 : 0;
    std::printf("localised %zu of %zu frames in %s (%zu keyframes, %zu map points; nothing added to the map)\n", localised, run.frames.size(),
                flags.localize_in.c_str(), slam.keyframe_poses().size(), written.map_points);
  }
  return run.interrupted ? interrupted_exit_status() : 0;
}

}  // namespace

Runner register_vslam(CLI::App& app) {
  auto flags = std::make_shared<VslamFlags>();
  add_vslam_flags(app, *flags);
  return [flags] { return vslam_command(*flags); };
}

}  // namespace cairn::cli
