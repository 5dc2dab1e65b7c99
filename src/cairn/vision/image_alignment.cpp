// Rotation from small blurry images (Klein & Murray, ECCV 2008, Sec. 4), aligned by ECC
// (Evangelidis & Psarakis, PAMI 2008). See image_alignment.hpp.
#include "cairn/vision/image_alignment.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>
#include <vector>

namespace cairn::vision {

SmallBlurryImage make_small_blurry_image(const cv::Mat& gray, const SmallBlurryImageOptions& options) {
  if (gray.empty() || gray.type() != CV_8UC1) throw std::invalid_argument("make_small_blurry_image: needs a non-empty 8-bit grey image");
  if (options.downsample < 1 || !(options.blur_sigma >= 0.0)) throw std::invalid_argument("make_small_blurry_image: downsample >= 1 and blur_sigma >= 0 needed");
  const int w = gray.cols / options.downsample, h = gray.rows / options.downsample;
  if (w < 8 || h < 8) throw std::invalid_argument("make_small_blurry_image: the image is too small for the downsampling");
  SmallBlurryImage out;
  cv::Mat small;
  cv::resize(gray, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  small.convertTo(out.image, CV_32F);
  if (options.blur_sigma > 0.0) cv::GaussianBlur(out.image, out.image, cv::Size(0, 0), options.blur_sigma);
  out.image -= cv::mean(out.image)[0];
  out.scale = 1.0 / options.downsample;
  return out;
}

namespace {

// The small image's pinhole: the full image's intrinsics scaled, with pixel centres kept
// (INTER_AREA averages blocks: small pixel j covers full pixels [j s, (j + 1) s)).
struct SmallPinhole {
  double fx, fy, cx, cy;
  SmallPinhole(const io::CameraCalibration& c, double scale)
      : fx(c.fx * scale), fy(c.fy * scale), cx((c.cx + 0.5) * scale - 0.5), cy((c.cy + 0.5) * scale - 0.5) {}
  Eigen::Vector3d ray(const Eigen::Vector2d& x) const { return Eigen::Vector3d((x.x() - cx) / fx, (x.y() - cy) / fy, 1.0).normalized(); }
  bool pixel(const Eigen::Vector3d& r, Eigen::Vector2d& x) const {
    if (r.z() <= 1e-6) return false;
    x = {fx * r.x() / r.z() + cx, fy * r.y() / r.z() + cy};
    return true;
  }
};

// A 5 x 5 grid over the middle 30 % of the small image: the sample points of both conversions.
// Near the middle because a rigid 2D warp fitted by ECC to a turned view moves the image by
// about the shift at its centre (the shift of a rotation grows towards the edges as 1 / cos^2
// of the angle from the axis); a grid over the whole image read its shift as 10 % less turn
// (measured on a synthetic pure rotation, tests/vision/test_image_alignment.cpp).
std::vector<Eigen::Vector2d> grid_points(int w, int h) {
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) out.emplace_back((0.35 + 0.075 * j) * (w - 1), (0.35 + 0.075 * i) * (h - 1));
  }
  return out;
}

// The 2D rigid warp (2 x 3, CV_32F) closest to the homography K R K^-1 on the grid (2D
// Procrustes: the angle from the centred points' cross and dot sums, then the shift).
// Identity when a grid ray turns behind the camera.
cv::Mat warp_from_rotation(const Eigen::Matrix3d& R, const SmallPinhole& k, int w, int h) {
  const std::vector<Eigen::Vector2d> grid = grid_points(w, h);
  std::vector<Eigen::Vector2d> moved(grid.size());
  Eigen::Vector2d src_mean = Eigen::Vector2d::Zero(), dst_mean = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (!k.pixel(R * k.ray(grid[i]), moved[i])) return cv::Mat::eye(2, 3, CV_32F);
    src_mean += grid[i];
    dst_mean += moved[i];
  }
  src_mean /= static_cast<double>(grid.size());
  dst_mean /= static_cast<double>(grid.size());
  double cross = 0.0, dot = 0.0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const Eigen::Vector2d a = grid[i] - src_mean, b = moved[i] - dst_mean;
    cross += a.x() * b.y() - a.y() * b.x();
    dot += a.dot(b);
  }
  const double theta = std::atan2(cross, dot), c = std::cos(theta), s = std::sin(theta);
  const Eigen::Vector2d t = dst_mean - Eigen::Vector2d(c * src_mean.x() - s * src_mean.y(), s * src_mean.x() + c * src_mean.y());
  cv::Mat warp = (cv::Mat_<float>(2, 3) << static_cast<float>(c), static_cast<float>(-s), static_cast<float>(t.x()), static_cast<float>(s),
                  static_cast<float>(c), static_cast<float>(t.y()));
  return warp;
}

// The rotation that best sends the grid's rays to the rays of their warped pixels (PTAM
// SmallBlurryImage::SE3fromSE2, here in closed form: Kabsch's solution of Wahba's problem).
Eigen::Matrix3d rotation_from_warp(const cv::Mat& warp, const SmallPinhole& k, int w, int h) {
  cv::Mat_<double> W;
  warp.convertTo(W, CV_64F);
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector2d& x : grid_points(w, h)) {
    const Eigen::Vector2d y(W(0, 0) * x.x() + W(0, 1) * x.y() + W(0, 2), W(1, 0) * x.x() + W(1, 1) * x.y() + W(1, 2));
    M += k.ray(y) * k.ray(x).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

}  // namespace

RotationAlignment align_rotation(const SmallBlurryImage& previous, const SmallBlurryImage& current, const io::CameraCalibration& camera,
                                 const Eigen::Matrix3d& R_guess, const RotationAlignmentOptions& options) {
  RotationAlignment out;
  if (previous.empty() || current.empty() || previous.image.size() != current.image.size() || previous.scale != current.scale) return out;
  const int w = current.image.cols, h = current.image.rows;
  const SmallPinhole k(camera, current.scale);
  // Starting warps: the guess, no motion, and phase correlation's shift (cv::phaseCorrelate:
  // the peak of the normalised cross-power spectrum; current(x + shift) ~ previous(x)).
  std::vector<cv::Mat> starts{warp_from_rotation(R_guess, k, w, h), cv::Mat::eye(2, 3, CV_32F)};
  cv::Mat window;
  cv::createHanningWindow(window, current.image.size(), CV_32F);
  double response = 0.0;
  const cv::Point2d shift = cv::phaseCorrelate(previous.image, current.image, window, &response);
  if (std::isfinite(shift.x) && std::isfinite(shift.y)) {
    cv::Mat s = cv::Mat::eye(2, 3, CV_32F);
    s.at<float>(0, 2) = static_cast<float>(shift.x);
    s.at<float>(1, 2) = static_cast<float>(shift.y);
    starts.push_back(s);
  }
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, options.max_iterations, options.epsilon);
  cv::Mat best;
  double best_correlation = -2.0;
  for (cv::Mat& warp : starts) {
    double rho = -2.0;
    try {
      // ECC's own pre-blur off (size 1): the images are blurred already.
      rho = cv::findTransformECC(previous.image, current.image, warp, cv::MOTION_EUCLIDEAN, criteria, cv::noArray(), 1);
    } catch (const cv::Exception&) {
      continue;  // diverged (images uncorrelated from this start)
    }
    if (std::isfinite(rho) && rho > best_correlation) {
      best_correlation = rho;
      best = warp;
    }
  }
  if (best.empty()) return out;
  out.correlation = best_correlation;
  out.R_current_previous = rotation_from_warp(best, k, w, h);
  out.rotation_deg = Eigen::AngleAxisd(out.R_current_previous).angle() * 180.0 / M_PI;
  out.ok = best_correlation >= options.min_correlation;
  return out;
}

}  // namespace cairn::vision
