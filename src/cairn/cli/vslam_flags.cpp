// The flags of `cairn vslam` (see vslam_flags.hpp; the run is in cmd_vslam.cpp).

#include "cairn/cli/vslam_flags.hpp"

#include <limits>

#include "cairn/cli/flag_checks.hpp"

namespace cairn::cli {

void add_vslam_flags(CLI::App& command, VslamFlags& flags) {
  CLI::App* cmd = &command;
  CLI::Option* folder = cmd->add_option("folder", flags.folder, "KITTI odometry folder (calib.txt, image_0/1 or image_l/r), EuRoC MAV folder (mav0/cam0, cam1), TUM RGB-D folder, or a plain folder: images (monocular) or left/ and right/ (rectified stereo), with --calib")->required();
  cmd->add_option("--out", flags.out, "Output directory (trajectory.tum/.kitti, keyframes.tum, map_points.ply, frames.csv, report.json, trajectory.png, features.png)");
  cmd->add_option("--camera", flags.camera, "Calibration preset for TUM RGB-D: tum-fr1, tum-fr2, tum-fr3");
  cmd->add_option("--calib", flags.calib, "Calibration YAML (fx, fy, cx, cy, k1..k3, p1, p2, baseline_m, depth_units_per_m, virtual_baseline_m)");
  cmd->add_option("--ground-truth", flags.ground_truth, "TUM-format ground truth (default: the dataset's poses.txt / groundtruth.txt)");
  cmd->add_option("--vocabulary", flags.vocabulary, "Bag-of-words vocabulary (cairn vocabulary train, or DBoW2 .txt/.yml): loop closure and relocalisation");
  cmd->add_option("--config", flags.config, "YAML configuration over the dataset's settings (every key optional; --print-config lists them)");
  cmd->add_option("--set", flags.set, "Override one key after --config: section.key=value (repeatable); --features and --no-local-ba win over both");
  // FOLDER is optional with --print-config: this callback runs before CLI11 checks requirements.
  cmd->add_flag_callback("--print-config", [f = &flags, folder] { f->print_config = true; folder->required(false); },
                         "Print the configuration in effect (YAML: the dataset's settings, then --config, --set and the flags) and exit unless FOLDER is given");
  cmd->add_option("--features", flags.features, "ORB features per image (default 2000 stereo, 1000 RGB-D, as ORB-SLAM2)")
      ->check(checks::whole_range(10, 100000));
  cmd->add_option("--max-frames", flags.max_frames, "Process at most N frames")->check(checks::count(std::numeric_limits<long>::max()));
  cmd->add_option("--feature-frame", flags.feature_frame, "Frame drawn in features.png, 0-based (default: the middle one)")
      ->check(checks::count_or_zero(std::numeric_limits<long>::max()));
  cmd->add_flag("--mono", flags.mono, "Monocular: the left (stereo) or colour (TUM) images only; the scale is not observable (a plain folder of images is monocular anyway)");
  cmd->add_flag("--no-local-ba", flags.no_local_ba, "Skip local bundle adjustment (visual odometry only)");
  cmd->add_flag("-q,--quiet", flags.quiet, "No progress or summary");
  cmd->add_flag("--progress", flags.progress, "Progress lines even when stderr is not a terminal");
  cmd->add_flag("--overwrite", flags.overwrite, "Replace an existing output directory's files");
}

}  // namespace cairn::cli
