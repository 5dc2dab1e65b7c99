#pragma once
/// \file
/// Image-sequence datasets on disk: which frames there are, where their image files lie, their
/// times, the camera calibration the dataset ships and its ground truth. No image is decoded here
/// (that is cairn::vision, with OpenCV); this is the layout and the text files, checked like every
/// cairn reader (file:line errors, see text_reader.hpp).
///
/// | layout | folder holds | calibration | times | ground truth |
/// |---|---|---|---|---|
/// | KITTI odometry stereo | `image_0/` + `image_1/` (or `image_l/` + `image_r/`), `calib.txt` | `P0:`/`P1:` lines or two unlabelled 12-number lines | `times.txt` if present, else 0.1 s apart (said in `notes`) | `poses.txt` if present (camera 0 in the first camera-0 frame) |
/// | EuRoC MAV (stereo) | `mav0/cam0/`, `mav0/cam1/` (`data.csv`, `data/`, `sensor.yaml`) | each camera's `sensor.yaml` (pinhole, radial-tangential, `T_BS`); the pair is not rectified: `rig` holds both cameras and the images must be rectified (vision::StereoRectifier) | from `data.csv` (ns) | `mav0/state_groundtruth_estimate0/data.csv` (the body, i.e. the IMU; `rig->T_body_cam0` turns it into the left camera's) |
/// | plain folder (`layout` "folder") | images (.png, .jpg) in the folder itself (monocular), or `left/` + `right/` with the same file names (rectified stereo) | not in the folder: give it (cairn vslam --calib; stereo needs `baseline_m`) | `times.txt` if present; else the file names when all are times (16-19 digits: nanoseconds; digits.digits: seconds); else 0.1 s apart (said in `notes`) | none |
/// | TUM RGB-D | `rgb.txt` + `depth.txt` (or `associations.txt`), `rgb/`, `depth/` | not in the dataset: give it (cairn vslam --camera tum-fr1 / --calib) | from the lists | `groundtruth.txt` if present (T_world_rgb-camera) |

#include <optional>
#include <string>
#include <vector>

#include "cairn/core/time.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::io {

/// Pinhole camera with Brown-Conrady distortion (OpenCV's k1, k2, p1, p2, k3 order), the model
/// ORB-SLAM's settings files and TUM's published calibrations use.
struct CameraCalibration {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  int width = 0;   ///< pixels; 0 = take it from the first image
  int height = 0;
  /// Stereo: distance between the two rectified cameras along x, metres (KITTI: -P1[0,3] / fx).
  double baseline_m = 0.0;
  /// RGB-D: metres per depth unit's inverse (TUM: 5000 units per metre).
  double depth_units_per_m = 0.0;
  /// RGB-D: the baseline of the virtual stereo camera a depth map stands for (ORB-SLAM's bf /
  /// fx; TUM1.yaml has bf = 40, i.e. 0.0773 m at fx 517.3); only scales the uncertainty.
  double virtual_baseline_m = 0.0;

  bool has_distortion() const { return k1 != 0.0 || k2 != 0.0 || p1 != 0.0 || p2 != 0.0 || k3 != 0.0; }
  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
  /// Empty when the calibration is plausible for a real camera taking `width` x `height` images,
  /// else every implausibility ("; "-separated): a field of view outside 1-170 degrees on
  /// either axis (fx = 1e7 on a 1241-pixel image is 0.007 degrees: a calibration in other units,
  /// or a typo), a principal point outside the image, and for `stereo` a baseline outside
  /// 1 mm-10 m. A run on such a calibration would track nothing real while reporting `ok`.
  std::string implausibilities(int width, int height, bool stereo) const;
};

enum class SequenceKind { kStereo, kRgbd, kMonocular };
std::string_view to_string(SequenceKind kind);

/// Two cameras that are not rectified (EuRoC): each with its own calibration and its pose in the
/// body frame (EuRoC's T_BS).
struct StereoRig {
  CameraCalibration left, right;
  core::SE3 T_body_left, T_body_right;
};

struct ImageFrame {
  core::Timestamp time;
  std::string image;        ///< left (stereo), colour (RGB-D) or the only image
  std::string right_image;  ///< stereo only
  std::string depth_image;  ///< RGB-D only
};

struct ImageSequence {
  SequenceKind kind = SequenceKind::kStereo;
  std::string layout;  ///< "kitti", "euroc", "tum", "folder"
  std::string folder;
  CameraCalibration calibration;  ///< from the dataset where it ships one (KITTI; EuRoC: the left camera's, unrectified)
  std::optional<StereoRig> rig;   ///< EuRoC: the unrectified pair
  bool calibration_from_dataset = false;
  std::vector<ImageFrame> frames;
  bool times_from_file = false;
  /// Ground truth from the dataset's own file, if any (KITTI: one pose per frame, frame stamps;
  /// TUM: the motion-capture trajectory at its own stamps).
  std::optional<Trajectory> ground_truth;
  std::string ground_truth_path;
  /// What a user should know about how the folder was read (assumed times, skipped lines).
  std::vector<std::string> notes;
};

/// The layout of `folder`: "kitti" (calib.txt and a stereo image pair of folders), "tum"
/// (rgb.txt), "euroc" (mav0/cam0), "folder" (left/ and right/, or images in the folder), or
/// throws ParseError naming what was looked for.
std::string detect_image_layout(const std::string& folder);

/// Reads a plain folder (layout above): images in natural order ("frame_9" before "frame_10"),
/// monocular, or stereo from left/ and right/ (each left image needs its right partner).
ImageSequence read_image_folder(const std::string& folder);

/// Reads a KITTI odometry stereo folder (layout above). Every image listed in image_0 must have
/// its partner in image_1; times.txt and poses.txt, when present, must have one line per frame.
ImageSequence read_kitti_stereo(const std::string& folder);

/// Reads an EuRoC MAV folder (the one holding `mav0/`, or `mav0/` itself). cam0 and cam1 frames
/// are paired by their identical stamps (a stamp in one list only is skipped and counted in
/// `notes`). The ground truth, when present, is the body's (EuRoC's IMU frame).
ImageSequence read_euroc_stereo(const std::string& folder);

/// Reads one EuRoC camera `sensor.yaml`: `intrinsics` [fu, fv, cu, cv], `distortion_model`
/// radial-tangential with `distortion_coefficients` [k1, k2, p1, p2], `resolution` [w, h] and
/// `T_BS` (data: 16 numbers, row-major). Throws ParseError with the line.
CameraCalibration read_euroc_camera(const std::string& path, core::SE3* T_body_camera);

/// Reads `calib.txt` of KITTI odometry: P0 and P1 (labelled or the first two lines), fx, fy,
/// cx, cy from P0 and the baseline from P1's fourth column. Throws ParseError.
CameraCalibration read_kitti_calibration(const std::string& path);

/// Reads a TUM RGB-D folder. With associations.txt its pairs are used as they are; otherwise
/// rgb.txt and depth.txt are associated as TUM's associate.py does (nearest stamp, each used at
/// most once, |dt| < max_difference_s). The calibration is not in the folder (left zero).
ImageSequence read_tum_rgbd(const std::string& folder, double max_difference_s = 0.02);

/// True for the image file extensions cairn reads: .png, .jpg, .jpeg, any case
/// (vision/image_file.hpp decodes PNG and JPEG only).
bool is_image_file_name(const std::string& path);
/// The image files directly in `folder`, in natural order of their names; ParseError when it
/// cannot be listed or holds none (naming the unread format when it holds PGM, BMP or TIFF
/// images instead).
std::vector<std::string> image_files_in(const std::string& folder);

/// Reads a TUM "timestamp filename" list (rgb.txt, depth.txt). Comments (#) are skipped.
std::vector<std::pair<core::Timestamp, std::string>> read_tum_image_list(const std::string& path);

}  // namespace cairn::io
