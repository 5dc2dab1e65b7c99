// `cairn vslam`'s input: which images (a dataset folder or a bag's image topics) and which
// camera (the dataset's, the bag's CameraInfo, --calib or --camera), checked before any work.

#include "cairn/cli/vslam_input.hpp"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "cairn/bag/bag.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/io/calibration_yaml.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/vslam/bag_images.hpp"
#include "cairn/vslam/config.hpp"
#include "cairn/vslam/evaluation.hpp"
#include "cairn/vslam/image_input.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::cli {
namespace {

io::ImageSequence read_sequence(const std::string& folder) {
  const std::string layout = io::detect_image_layout(folder);
  return layout == "kitti"    ? io::read_kitti_stereo(folder)
         : layout == "euroc"  ? io::read_euroc_stereo(folder)
         : layout == "folder" ? io::read_image_folder(folder)
                              : io::read_tum_rgbd(folder);
}

/// The first flag given that only a bag input takes ("" when none).
std::string bag_flag_given(const VslamFlags& flags) {
  const std::pair<const char*, bool> bag_flags[] = {
      {"--left-topic", !flags.left_topic.empty()},           {"--right-topic", !flags.right_topic.empty()},
      {"--image-topic", !flags.image_topic.empty()},         {"--depth-topic", !flags.depth_topic.empty()},
      {"--camera-info-topic", !flags.camera_info_topic.empty()},
      {"--right-camera-info-topic", !flags.right_camera_info_topic.empty()},
      {"--depth-scale", flags.depth_scale > 0.0}};
  for (const auto& [name, given] : bag_flags) {
    if (given) return name;
  }
  return "";
}

/// The topics named and the depth scale: --depth-scale, else the --calib file's depth_units_per_m.
vslam::BagImageOptions bag_options(const VslamFlags& flags) {
  vslam::BagImageOptions options;
  options.topics = {flags.left_topic,        flags.right_topic,       flags.image_topic,
                    flags.depth_topic,       flags.camera_info_topic, flags.right_camera_info_topic};
  if (std::string why; !options.topics.is_valid(&why)) throw UsageError(why);
  options.calibration_given = !flags.calib.empty() || !flags.camera.empty();
  options.depth_units_per_m = flags.depth_scale;
  if (!(options.depth_units_per_m > 0.0) && !flags.calib.empty()) {
    options.depth_units_per_m = io::read_calibration_yaml(flags.calib).depth_units_per_m;
  }
  return options;
}

/// A folder's camera: an EuRoC pair's own (rectified), --calib, --camera or the dataset's; refused
/// when missing or given twice. Returns the EuRoC pair's rectifier.
std::optional<vision::StereoRectifier> resolve_folder_calibration(io::ImageSequence& seq, const VslamFlags& flags) {
  if (seq.rig && (!flags.calib.empty() || !flags.camera.empty())) throw std::invalid_argument("an EuRoC folder brings its own calibration: no --camera or --calib");
  std::optional<vision::StereoRectifier> rectifier = vslam::rectify_calibration(seq);
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
  return rectifier;
}

/// A bag's camera: its CameraInfo's (read_bag_images refused a bag without one unless --calib or
/// --camera is given), or --calib / --camera over it. The bag's image size, stereo baseline (when
/// the file gives none) and depth scale stay: the depth images are made in the bag's units.
void resolve_bag_calibration(io::ImageSequence& seq, const VslamFlags& flags) {
  if (flags.calib.empty() && flags.camera.empty()) return;
  const io::CameraCalibration from_bag = seq.calibration;
  io::CameraCalibration c = !flags.calib.empty() ? io::read_calibration_yaml(flags.calib) : io::tum_calibration_preset(flags.camera);
  if (!(c.baseline_m > 0.0)) c.baseline_m = from_bag.baseline_m;
  if (c.width == 0 || c.height == 0) {
    c.width = from_bag.width;
    c.height = from_bag.height;
  }
  if (seq.kind == io::SequenceKind::kRgbd) {
    c.depth_units_per_m = from_bag.depth_units_per_m;
    if (!(c.virtual_baseline_m > 0.0)) c.virtual_baseline_m = vslam::kRgbdBaselineTimesFxPx / c.fx;
  }
  seq.calibration = c;
}

}  // namespace

VslamInput read_vslam_input(const VslamFlags& flags) {
  VslamInput input;
  if (bag::is_bag(flags.folder)) {
    input.bag = vslam::read_bag_images(flags.folder, bag_options(flags));
    return input;
  }
  if (const std::string flag = bag_flag_given(flags); !flag.empty()) {
    throw UsageError(flag + " goes with a bag input, and " + flags.folder + " is not a bag");
  }
  input.folder = read_sequence(flags.folder);
  return input;
}



/// The camera (above); refused when given twice, or stereo without a baseline. Returns an EuRoC
/// pair's rectifier.
std::optional<vision::StereoRectifier> resolve_calibration(VslamInput& input, const VslamFlags& flags) {
  if (!flags.calib.empty() && !flags.camera.empty()) throw std::invalid_argument("give --camera or --calib, not both");
  io::ImageSequence& seq = input.sequence();
  std::optional<vision::StereoRectifier> rectifier;
  if (input.bag) {
    resolve_bag_calibration(seq, flags);
  } else {
    rectifier = resolve_folder_calibration(seq, flags);
  }
  if (seq.kind == io::SequenceKind::kStereo && !flags.mono && !(seq.calibration.baseline_m > 0.0)) {
    throw std::invalid_argument("stereo images need the baseline between the rectified cameras: baseline_m in " +
                                (flags.calib.empty() ? std::string("the calibration") : flags.calib) + " (or --mono for the left images only)");
  }
  return rectifier;
}

/// Where the calibration came from, for messages and report.json.
std::string calibration_source(const VslamInput& input, const VslamFlags& flags) {
  if (!flags.calib.empty()) return flags.calib;
  if (!flags.camera.empty()) return "preset " + flags.camera;
  if (input.bag) return input.bag->calibration_source;
  return "dataset";
}

/// --ground-truth, else the dataset's (EuRoC's moved from the body to the rectified left camera).
vslam::GroundTruth resolve_ground_truth(const io::ImageSequence& seq, const VslamFlags& flags,
                                        const std::optional<vision::StereoRectifier>& rectifier) {
  if (!flags.ground_truth.empty()) return {io::read_tum(flags.ground_truth), flags.ground_truth};
  if (!seq.ground_truth) return {};
  if (!rectifier) return {*seq.ground_truth, seq.ground_truth_path};
  return {vslam::ground_truth_of_rectified_camera(*seq.ground_truth, *seq.rig, *rectifier), seq.ground_truth_path};
}

/// Refuses an implausible calibration before any work, naming where it came from.
void check_calibration(const VslamInput& input, const VslamFlags& flags) {
  const io::ImageSequence& seq = input.sequence();
  const std::string source = !flags.calib.empty()    ? flags.calib
                             : !flags.camera.empty() ? "--camera " + flags.camera
                             : input.bag             ? seq.folder + " (" + input.bag->calibration_source + ")"
                                                     : seq.layout == "kitti" ? seq.folder + "/calib.txt"
                                                     : seq.folder + " (its calibration)";
  vslam::check_calibration_plausible(seq, seq.kind == io::SequenceKind::kStereo && !flags.mono, source);
}

}  // namespace cairn::cli
