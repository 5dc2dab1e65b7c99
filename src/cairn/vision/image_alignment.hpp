#pragma once
/// \file
/// The camera's rotation between two frames from whole-image alignment, for a tracker whose
/// motion model has failed (fast turns, motion blur).
///
/// After PTAM's "small blurry images" (Klein & Murray, "Improving the Agility of Keyframe-Based
/// SLAM", ECCV 2008, Sec. 4; PTAM SmallBlurryImage.cc): each frame is reduced to 1/8 of its size
/// (80 x 60 for 640 x 480) and blurred (sigma 2.5 px of the small image), which leaves what a
/// blurred frame and a sharp one share. The two are aligned by a 2D Euclidean warp (rotation in
/// the image plane and a shift), found here by OpenCV's ECC (Evangelidis & Psarakis, "Parametric
/// Image Alignment Using Enhanced Correlation Coefficient Maximization", PAMI 2008) where PTAM
/// uses ESM; ECC is started from the caller's guess, from no motion and from the shift phase
/// correlation finds (large turns), and the best-correlated result kept. The warp is turned into
/// a 3D rotation as PTAM's SE3fromSE2 does: the rotation that best maps a grid of viewing rays of
/// the first image onto the rays the warp sends them to (Kabsch / Wahba's problem, closed form).
///
/// A whole-image warp cannot tell rotation from the shift a translation makes, so the result is a
/// rotation prediction, not a measurement: the caller searches features around it.

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "cairn/io/image_sequence.hpp"

namespace cairn::vision {

struct SmallBlurryImageOptions {
  int downsample = 8;        ///< PTAM: pyramid level 3 (640 x 480 -> 80 x 60)
  double blur_sigma = 2.5;   ///< Gaussian sigma in small-image pixels (PTAM's default)
};

/// A frame reduced and blurred, as 32-bit floats with zero mean.
struct SmallBlurryImage {
  cv::Mat image;       ///< CV_32F, empty when not made
  double scale = 0.0;  ///< small-image pixels per full-image pixel (1 / downsample)
  bool empty() const { return image.empty(); }
};

/// Throws std::invalid_argument for an empty or non-8-bit-grey image, or one smaller than 8
/// small pixels across.
SmallBlurryImage make_small_blurry_image(const cv::Mat& gray, const SmallBlurryImageOptions& options = {});

struct RotationAlignment {
  bool ok = false;
  /// Rotates viewing rays of the previous camera into the current one: b_current = R b_previous
  /// (with camera poses T_world_camera, R = R_world_current^T R_world_previous).
  Eigen::Matrix3d R_current_previous = Eigen::Matrix3d::Identity();
  double correlation = 0.0;  ///< ECC's enhanced correlation coefficient (1 = identical after warping)
  double rotation_deg = 0.0; ///< angle of R_current_previous
};

struct RotationAlignmentOptions {
  /// Below this correlation the alignment is not trusted (ok = false). PTAM accepts its SBI
  /// rotation without a test; ECC's coefficient is normalised (in [-1, 1]), so a fixed bar is
  /// meaningful: two views of one scene with blur differ but stay well correlated at 80 x 60.
  double min_correlation = 0.7;
  int max_iterations = 50;
  double epsilon = 1e-4;
};

/// Aligns `current` to `previous` (both from make_small_blurry_image of one camera) and returns
/// the camera rotation. `R_guess` (same convention) starts one of the searches: the motion
/// model's rotation, or identity.
RotationAlignment align_rotation(const SmallBlurryImage& previous, const SmallBlurryImage& current, const io::CameraCalibration& camera,
                                 const Eigen::Matrix3d& R_guess = Eigen::Matrix3d::Identity(), const RotationAlignmentOptions& options = {});

}  // namespace cairn::vision
