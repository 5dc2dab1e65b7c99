// The flags of `cairn vslam` (see vslam_flags.hpp; the run is in cmd_vslam.cpp).

#include "cairn/cli/vslam_flags.hpp"

#include <limits>

#include "cairn/cli/flag_checks.hpp"

namespace cairn::cli {

void add_vslam_flags(CLI::App& command, VslamFlags& flags) {
  CLI::App* cmd = &command;
  CLI::Option* folder = cmd->add_option("folder", flags.folder, "KITTI odometry folder (calib.txt, image_0/1 or image_l/r), EuRoC MAV folder (mav0/cam0, cam1), TUM RGB-D folder, a plain folder: images (monocular) or left/ and right/ (rectified stereo), with --calib; or a bag (ROS 1 .bag, .mcap, rosbag2 .db3 or folder) with image topics and CameraInfo")->required();
  cmd->add_option("--mcap", flags.mcap, "Also write the trajectory, health and map points as MCAP for Foxglove");
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
  cmd->add_option("--first-frame", flags.first_frame, "Start at frame K, 0-based (the frames before it are skipped; not for bags)")
      ->check(checks::count_or_zero(std::numeric_limits<long>::max()));
  cmd->add_option("--save-map", flags.save_map,
                  "Also write the main map (keyframes, map points, descriptors, covisibility, the vocabulary's identity) for "
                  "--localize-in (docs/formats.md, \"cairn visual map\")");
  cmd->add_option("--localize-in", flags.localize_in,
                  "Localise in a map saved with --save-map instead of mapping: track against it without adding to it, "
                  "relocalise by bag of words (--vocabulary) when lost (ORB-SLAM2's localisation mode)");
  cmd->add_option("--feature-frame", flags.feature_frame, "Frame drawn in features.png, 0-based (default: the middle one)")
      ->check(checks::count_or_zero(std::numeric_limits<long>::max()));
  cmd->add_flag("--mono", flags.mono, "Monocular: the left (stereo) or colour (TUM) images only; the scale is not observable (a plain folder of images is monocular anyway)");
  cmd->add_flag("--no-local-ba", flags.no_local_ba, "Skip local bundle adjustment (visual odometry only)");
  cmd->add_flag("-q,--quiet", flags.quiet, "No progress or summary");
  cmd->add_flag("--progress", flags.progress, "Progress lines even when stderr is not a terminal");
  cmd->add_flag("--overwrite", flags.overwrite, "Replace an existing output directory's files");
  // A bag input: vslam/bag_topics.hpp and bag_images.hpp.
  cmd->add_option("--left-topic", flags.left_topic, "Bag input: the left images of a rectified stereo pair (sensor_msgs/Image or CompressedImage), with --right-topic (default: chosen from the bag's image topics)");
  cmd->add_option("--right-topic", flags.right_topic, "Bag input: the right images of the stereo pair, stamped as the left ones");
  cmd->add_option("--image-topic", flags.image_topic, "Bag input: the colour or grey images: RGB-D with --depth-topic, else monocular");
  cmd->add_option("--depth-topic", flags.depth_topic, "Bag input: the depth images registered to --image-topic (16UC1 or 32FC1), paired within 0.02 s");
  cmd->add_option("--camera-info-topic", flags.camera_info_topic, "Bag input: the left or colour camera's sensor_msgs/CameraInfo (default: camera_info beside the image topic)");
  cmd->add_option("--right-camera-info-topic", flags.right_camera_info_topic, "Bag input: the right camera's CameraInfo (default: camera_info beside the right topic)");
  cmd->add_option("--depth-scale", flags.depth_scale, "Bag input: depth units per metre (default REP 118's: 1000 for 16UC1 millimetres, 1 for 32FC1 metres; TUM RGB-D's values: 5000)")
      ->check(checks::positive());
  flags.command = cmd;
  cmd->add_option("--imu", flags.imu,
                  "Visual-inertial tracking with this IMU: an EuRoC imu0 (or mav0) folder or imu0/data.csv, a plain IMU CSV "
                  "(docs/formats.md), or a bag with one sensor_msgs/Imu topic (docs/vslam.md, \"With an IMU\")");
  cmd->add_option("--imu-topic", flags.imu_topic, "Visual-inertial tracking with this sensor_msgs/Imu topic of the images' bag (instead of --imu)");
  cmd->add_option("--imu-calibration", flags.imu_calibration,
                  "The IMU's noise (EuRoC/Kalibr sensor.yaml; default: sensor.yaml beside the IMU's data, else EuRoC's ADIS16448)");
  cmd->add_option("--camera-extrinsic", flags.camera_extrinsic,
                  "A sensor.yaml whose T_BS is the camera (the left one, before rectification) in the body frame (default: "
                  "EuRoC's cam0/sensor.yaml, else identity)");
  cmd->add_option("--imu-time-offset", flags.imu_time_offset_s, "Seconds added to every IMU stamp to put it on the images' clock")
      ->capture_default_str();
}

}  // namespace cairn::cli
