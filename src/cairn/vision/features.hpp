#pragma once
/// \file
/// Images in, features out: reading images with clear errors, ORB features spread over the image
/// as ORB-SLAM spreads them, undistortion of keypoints, and stereo matching along rows with
/// subpixel refinement (ORB-SLAM2's Frame::ComputeStereoMatches).
///
/// ORB (Rublee et al., ICCV 2011) as ORB-SLAM uses it (Mur-Artal & Tardos, T-RO 2017, Sec. III-A;
/// ORB-SLAM2 ORBextractor.cc): an image pyramid of 8 levels, factor 1.2; on each level a share of
/// the features proportional to its area; FAST corners found cell by cell (cells of ~30 px) with
/// threshold 20, and 7 in a cell where 20 finds none; then the corners are spread over the level:
/// ORB-SLAM keeps the strongest corner of each node of a quadtree grown until it has as many nodes
/// as wanted; here the level is divided into cells and the cells are visited in rounds, each round
/// taking every cell's next-strongest corner, which spreads the same way. Orientation by the
/// intensity centroid over a disc of radius 15; the rotated-BRIEF descriptors are OpenCV's
/// (cv::ORB::compute on the given keypoints, 256 bits, on the Gaussian-blurred pyramid).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "cairn/io/image_sequence.hpp"

namespace cairn::vision {

/// Reads an 8-bit grey image (a colour image is converted, as ORB-SLAM does with RGB order set
/// by the caller's dataset: TUM's PNGs are RGB). Throws io::ParseError(path, 0, ...) when the
/// file is missing, not an image, truncated, or (when expected_width > 0) of another size.
cv::Mat read_gray_image(const std::string& path, int expected_width = 0, int expected_height = 0);
/// Reads a 16-bit single-channel depth image (TUM: 5000 units per metre, 0 = no depth).
cv::Mat read_depth_image(const std::string& path, int expected_width = 0, int expected_height = 0);

struct OrbOptions {
  int features = 2000;          ///< wanted over all levels (ORB-SLAM: 2000 for KITTI, 1000 for TUM)
  double scale_factor = 1.2;    ///< between pyramid levels
  int levels = 8;
  int initial_fast_threshold = 20;
  int min_fast_threshold = 7;   ///< where the initial threshold finds no corner in a cell
  int cell_px = 30;             ///< detection cells (ORB-SLAM's W)
  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
};

/// Features of one image. keypoints[i].pt is in level-0 pixels of the (distorted) image,
/// .octave its pyramid level, .angle degrees, .response the FAST score; descriptors row i is its
/// 32-byte descriptor.
struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;           ///< N x 32, CV_8U
  std::vector<cv::Mat> pyramid;  ///< the levels (level 0 = the image), for stereo refinement
  std::vector<double> scales;    ///< scale_factor^level
};

class OrbExtractor {
 public:
  explicit OrbExtractor(const OrbOptions& options = {});
  Features extract(const cv::Mat& gray) const;
  const OrbOptions& options() const { return options_; }

 private:
  OrbOptions options_;
  std::vector<int> features_per_level_;
  std::vector<int> umax_;  ///< half-widths of the orientation disc's rows
};

/// Hamming distance of two 32-byte descriptors.
int descriptor_distance(const unsigned char* a, const unsigned char* b);

/// Undistorted pixel coordinates of every keypoint (cv::undistortPoints with P = K); the input
/// coordinates when the calibration has no distortion.
std::vector<Eigen::Vector2d> undistort_keypoints(const std::vector<cv::KeyPoint>& keypoints, const io::CameraCalibration& camera);

struct StereoOptions {
  int max_descriptor_distance = 75;  ///< ORB-SLAM2: (TH_HIGH + TH_LOW) / 2
  int window_half_size = 5;          ///< SAD window 11 x 11 on the keypoint's level
  int search_half_range = 5;         ///< SAD positions either side of the descriptor match
  double row_band_px = 2.0;          ///< rows considered: +- this x scale of the level
  double min_depth_baselines = 1.0;  ///< nearest depth accepted, in baselines (disparity <= fx)
  double sad_outlier_factor = 2.1;   ///< reject SAD above this x the median (ORB-SLAM2: 1.5 x 1.4)
  /// True when usable; otherwise false with every problem in *why (match_stereo sizes its SAD
  /// table by search_half_range and indexes rows by row_band_px, so both are bounded).
  bool is_valid(std::string* why) const;
};

/// For each left keypoint the right image's x coordinate (u_right) and the depth, or -1 for
/// both when there is no match. ORB-SLAM2 Frame::ComputeStereoMatches: candidates in the right
/// image on the same rows and adjacent levels within the disparity range, the best descriptor
/// match, refined by SAD block matching on the pyramid level with a parabola through the three
/// best positions, rejected when the parabola's vertex leaves +-1 px or the SAD is an outlier.
struct StereoMatches {
  std::vector<double> u_right;
  std::vector<double> depth_m;
  std::size_t matched = 0;
};
StereoMatches match_stereo(const Features& left, const Features& right, const io::CameraCalibration& camera,
                           const StereoOptions& options = {});

/// Depth from a registered depth image at each (distorted) keypoint; u_right = u - fx b / z with
/// the undistorted u and the virtual baseline b (ORB-SLAM2 Frame::ComputeStereoFromRGBD).
StereoMatches depth_from_rgbd(const std::vector<cv::KeyPoint>& keypoints, const std::vector<Eigen::Vector2d>& undistorted,
                              const cv::Mat& depth, const io::CameraCalibration& camera);

/// Rectification of a stereo pair that is not rectified (EuRoC): Bouguet's method
/// (cv::stereoRectify, alpha 0: only valid pixels) and the maps of cv::initUndistortRectifyMap.
/// The rectified pair is a pinhole camera without distortion: fx, fy, cx, cy of the new left
/// projection matrix and the baseline -P_right[0,3] / fx.
class StereoRectifier {
 public:
  StereoRectifier(const io::StereoRig& rig, int width, int height);
  const io::CameraCalibration& rectified() const { return rectified_; }
  /// The rectified left camera in the original left camera's frame (a pure rotation).
  const core::SE3& T_left_rectified() const { return T_left_rectified_; }
  /// Throws std::invalid_argument when the images are not the size given at construction.
  void rectify(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out) const;

 private:
  io::CameraCalibration rectified_;
  core::SE3 T_left_rectified_;
  cv::Mat map_left_x_, map_left_y_, map_right_x_, map_right_y_;
  int width_ = 0, height_ = 0;
};

/// A PNG of the image with its keypoints: green = states[i] 2 (matched to the map), blue = 1
/// (stereo or depth only), red = 0 (unmatched); the caption at the top left.
std::string draw_features_png(const cv::Mat& gray, const std::vector<cv::KeyPoint>& keypoints,
                              const std::vector<signed char>& states, const std::string& caption);

}  // namespace cairn::vision
