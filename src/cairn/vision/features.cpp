#include "cairn/vision/features.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "cairn/core/problems.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vision/image_file.hpp"

namespace cairn::vision {
namespace {

constexpr int kEdgeThreshold = 19;   // ORB-SLAM's EDGE_THRESHOLD: no corner nearer the border
constexpr int kHalfPatchSize = 15;   // the orientation disc (ORB-SLAM's HALF_PATCH_SIZE)

cv::Mat read_image(const std::string& path, ImageMode mode, const char* what, int expected_width, int expected_height) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw io::ParseError(path, 0, std::string("cannot open ") + what + ": no such file");
  cv::Mat image;
  try {
    image = read_image_file(path, mode);
  } catch (const ImageFileError& e) {
    throw io::ParseError(path, 0, std::string("cannot decode ") + what + ": " + e.detail());
  }
  if (expected_width > 0 && (image.cols != expected_width || image.rows != expected_height)) {
    throw io::ParseError(path, 0, std::string(what) + " is " + std::to_string(image.cols) + " x " + std::to_string(image.rows) +
                                      " pixels, expected " + std::to_string(expected_width) + " x " + std::to_string(expected_height) +
                                      " as the sequence's first image");
  }
  return image;
}

// Intensity-centroid orientation (Rosin 1999; ORB-SLAM2 ORBextractor.cc IC_Angle), degrees.
float ic_angle(const cv::Mat& image, cv::Point2f pt, const std::vector<int>& umax) {
  int m_01 = 0, m_10 = 0;
  const uchar* center = &image.at<uchar>(cvRound(pt.y), cvRound(pt.x));
  for (int u = -kHalfPatchSize; u <= kHalfPatchSize; ++u) m_10 += u * center[u];
  const int step = static_cast<int>(image.step1());
  for (int v = 1; v <= kHalfPatchSize; ++v) {
    int v_sum = 0;
    const int d = umax[static_cast<std::size_t>(v)];
    for (int u = -d; u <= d; ++u) {
      const int plus = center[u + v * step], minus = center[u - v * step];
      v_sum += plus - minus;
      m_10 += u * (plus + minus);
    }
    m_01 += v * v_sum;
  }
  return cv::fastAtan2(static_cast<float>(m_01), static_cast<float>(m_10));
}

}  // namespace

cv::Mat read_gray_image(const std::string& path, int expected_width, int expected_height) {
  return read_image(path, ImageMode::kGray8, "image", expected_width, expected_height);
}

cv::Mat read_depth_image(const std::string& path, int expected_width, int expected_height) {
  cv::Mat depth = read_image(path, ImageMode::kUnchanged, "depth image", expected_width, expected_height);
  if (depth.type() != CV_16UC1) {
    throw io::ParseError(path, 0, "expected a 16-bit single-channel depth image, found " + std::to_string(depth.channels()) +
                                      " channel(s) of " + std::to_string(8 * depth.elemSize1()) + "-bit values");
  }
  return depth;
}

bool StereoOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (max_descriptor_distance < 1 || max_descriptor_distance > 256) problems.add("stereo.max_descriptor_distance must be in [1, 256]");
  if (window_half_size < 1 || window_half_size > 50) problems.add("stereo.window_half_size must be in [1, 50]");
  if (search_half_range < 1 || search_half_range > 50) problems.add("stereo.search_half_range must be in [1, 50]");
  if (!(row_band_px >= 0.0 && row_band_px <= 100.0)) problems.add("stereo.row_band_px must be in [0, 100]");
  if (!(min_depth_baselines > 0.0)) problems.add("stereo.min_depth_baselines must be > 0");
  if (!(sad_outlier_factor > 0.0)) problems.add("stereo.sad_outlier_factor must be > 0");
  return problems.report(why);
}

bool OrbOptions::is_valid(std::string* why) const {
  core::Problems problems;
  auto add = [&](const std::string& p) { problems.add(p); };
  if (features < 10 || features > 100000) add("features must be in [10, 100000]");
  if (!(scale_factor > 1.0 && scale_factor < 2.0)) add("scale_factor must be in (1, 2)");
  if (levels < 1 || levels > 16) add("levels must be in [1, 16]");
  if (initial_fast_threshold < 1 || min_fast_threshold < 1 || min_fast_threshold > initial_fast_threshold) {
    add("FAST thresholds must satisfy 1 <= min_fast_threshold <= initial_fast_threshold");
  }
  if (cell_px < 10) add("cell_px must be >= 10");
  return problems.report(why);
}

OrbExtractor::OrbExtractor(const OrbOptions& options) : options_(options) {
  if (std::string p; !options.is_valid(&p)) throw std::invalid_argument("ORB options: " + p);
  // Features per level proportional to the level's area (ORB-SLAM2 ORBextractor's constructor).
  const double factor = 1.0 / options.scale_factor;
  double desired = options.features * (1.0 - factor) / (1.0 - std::pow(factor, options.levels));
  int sum = 0;
  for (int level = 0; level + 1 < options.levels; ++level) {
    features_per_level_.push_back(static_cast<int>(std::lround(desired)));
    sum += features_per_level_.back();
    desired *= factor;
  }
  features_per_level_.push_back(std::max(options.features - sum, 0));
  // Rows of the orientation disc, symmetric (ORBextractor's umax).
  umax_.assign(kHalfPatchSize + 2, 0);
  const int vmax = static_cast<int>(std::floor(kHalfPatchSize * std::sqrt(2.0) / 2 + 1));
  const int vmin = static_cast<int>(std::ceil(kHalfPatchSize * std::sqrt(2.0) / 2));
  for (int v = 0; v <= vmax; ++v) umax_[static_cast<std::size_t>(v)] = static_cast<int>(std::lround(std::sqrt(kHalfPatchSize * kHalfPatchSize - v * v)));
  for (int v = kHalfPatchSize, v0 = 0; v >= vmin; --v) {
    while (umax_[static_cast<std::size_t>(v0)] == umax_[static_cast<std::size_t>(v0) + 1]) ++v0;
    umax_[static_cast<std::size_t>(v)] = v0;
    ++v0;
  }
}

Features OrbExtractor::extract(const cv::Mat& gray) const {
  if (gray.empty() || gray.type() != CV_8UC1) throw std::invalid_argument("OrbExtractor::extract needs an 8-bit grey image");
  Features out;
  out.pyramid.resize(static_cast<std::size_t>(options_.levels));
  out.scales.resize(static_cast<std::size_t>(options_.levels));
  out.pyramid[0] = gray;
  out.scales[0] = 1.0;
  for (int level = 1; level < options_.levels; ++level) {
    const auto l = static_cast<std::size_t>(level);
    out.scales[l] = out.scales[l - 1] * options_.scale_factor;
    const cv::Size size(static_cast<int>(std::lround(gray.cols / out.scales[l])), static_cast<int>(std::lround(gray.rows / out.scales[l])));
    if (size.width < 2 * kEdgeThreshold + 1 || size.height < 2 * kEdgeThreshold + 1) {
      out.pyramid.resize(l);
      out.scales.resize(l);
      break;
    }
    cv::resize(out.pyramid[l - 1], out.pyramid[l], size, 0, 0, cv::INTER_LINEAR);
  }
  std::vector<cv::KeyPoint> all;
  for (std::size_t level = 0; level < out.pyramid.size(); ++level) {
    const cv::Mat& image = out.pyramid[level];
    const int x_min = kEdgeThreshold, x_max = image.cols - kEdgeThreshold;
    const int y_min = kEdgeThreshold, y_max = image.rows - kEdgeThreshold;
    if (x_max <= x_min || y_max <= y_min) continue;
    const int columns = std::max(1, (x_max - x_min) / options_.cell_px), rows = std::max(1, (y_max - y_min) / options_.cell_px);
    const int cell_w = static_cast<int>(std::ceil(static_cast<double>(x_max - x_min) / columns));
    const int cell_h = static_cast<int>(std::ceil(static_cast<double>(y_max - y_min) / rows));
    std::vector<std::vector<cv::KeyPoint>> cells;
    cells.reserve(static_cast<std::size_t>(columns * rows));
    std::vector<cv::KeyPoint> found;
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < columns; ++j) {
        const int x0 = x_min + j * cell_w, y0 = y_min + i * cell_h;
        const int x1 = std::min(x0 + cell_w, x_max), y1 = std::min(y0 + cell_h, y_max);
        if (x1 <= x0 || y1 <= y0) continue;
        // FAST leaves 3 pixels at each side of what it is given: give it 3 more.
        const cv::Rect roi(x0 - 3, y0 - 3, x1 - x0 + 6, y1 - y0 + 6);
        std::vector<cv::KeyPoint> cell;
        for (const int threshold : {options_.initial_fast_threshold, options_.min_fast_threshold}) {
          found.clear();
          cv::FAST(image(roi), found, threshold, true);
          for (cv::KeyPoint& kp : found) {
            kp.pt.x += static_cast<float>(roi.x);
            kp.pt.y += static_cast<float>(roi.y);
            if (kp.pt.x >= static_cast<float>(x0) && kp.pt.x < static_cast<float>(x1) && kp.pt.y >= static_cast<float>(y0) &&
                kp.pt.y < static_cast<float>(y1)) {
              cell.push_back(kp);
            }
          }
          if (!cell.empty() || threshold == options_.min_fast_threshold) break;
        }
        std::sort(cell.begin(), cell.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
        if (!cell.empty()) cells.push_back(std::move(cell));
      }
    }
    // Rounds over the cells: each round offers every cell's next-strongest corner, strongest
    // offers first, until the level has its share.
    const auto wanted = static_cast<std::size_t>(features_per_level_[std::min(level, features_per_level_.size() - 1)]);
    std::vector<cv::KeyPoint> kept, offers;
    for (std::size_t round = 0; kept.size() < wanted; ++round) {
      offers.clear();
      for (const auto& cell : cells) {
        if (round < cell.size()) offers.push_back(cell[round]);
      }
      if (offers.empty()) break;
      std::sort(offers.begin(), offers.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
      for (const cv::KeyPoint& kp : offers) {
        if (kept.size() >= wanted) break;
        kept.push_back(kp);
      }
    }
    const double scale = out.scales[level];
    for (cv::KeyPoint kp : kept) {
      kp.angle = ic_angle(image, kp.pt, umax_);
      kp.octave = static_cast<int>(level);
      kp.size = static_cast<float>(31.0 * scale);
      kp.pt.x = static_cast<float>(static_cast<double>(kp.pt.x) * scale);
      kp.pt.y = static_cast<float>(static_cast<double>(kp.pt.y) * scale);
      kp.class_id = static_cast<int>(all.size());
      all.push_back(kp);
    }
  }
  if (all.empty()) {
    out.descriptors = cv::Mat(0, 32, CV_8U);
    return out;
  }
  // Rotated BRIEF on OpenCV's blurred pyramid of the same factor; it keeps the given angles.
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(options_.features, static_cast<float>(options_.scale_factor),
                                               static_cast<int>(out.pyramid.size()), kEdgeThreshold, 0, 2,
                                               cv::ORB::HARRIS_SCORE, 31, options_.initial_fast_threshold);
  std::vector<cv::KeyPoint> described = all;
  cv::Mat descriptors;
  orb->compute(gray, described, descriptors);
  // OpenCV may drop or reorder keypoints (border filter, sorting by level): follow class_id.
  out.keypoints.reserve(described.size());
  out.descriptors.create(static_cast<int>(described.size()), 32, CV_8U);
  for (std::size_t i = 0; i < described.size(); ++i) {
    cv::KeyPoint kp = all[static_cast<std::size_t>(described[i].class_id)];
    kp.class_id = -1;
    out.keypoints.push_back(kp);
    descriptors.row(static_cast<int>(i)).copyTo(out.descriptors.row(static_cast<int>(i)));
  }
  return out;
}

int descriptor_distance(const unsigned char* a, const unsigned char* b) {
  int distance = 0;
  for (int i = 0; i < 32; i += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a + i, 8);
    std::memcpy(&y, b + i, 8);
    distance += std::popcount(x ^ y);
  }
  return distance;
}

std::vector<Eigen::Vector2d> undistort_keypoints(const std::vector<cv::KeyPoint>& keypoints, const io::CameraCalibration& camera) {
  std::vector<Eigen::Vector2d> out(keypoints.size());
  if (!camera.has_distortion()) {
    for (std::size_t i = 0; i < keypoints.size(); ++i) out[i] = {static_cast<double>(keypoints[i].pt.x), static_cast<double>(keypoints[i].pt.y)};
    return out;
  }
  if (keypoints.empty()) return out;
  std::vector<cv::Point2f> in(keypoints.size()), undistorted;
  for (std::size_t i = 0; i < keypoints.size(); ++i) in[i] = keypoints[i].pt;
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const std::vector<double> dist{camera.k1, camera.k2, camera.p1, camera.p2, camera.k3};
  cv::undistortPoints(in, undistorted, K, dist, cv::noArray(), K);
  for (std::size_t i = 0; i < keypoints.size(); ++i) out[i] = {static_cast<double>(undistorted[i].x), static_cast<double>(undistorted[i].y)};
  return out;
}

StereoMatches match_stereo(const Features& left, const Features& right, const io::CameraCalibration& camera,
                           const StereoOptions& options) {
  const std::size_t n = left.keypoints.size();
  StereoMatches out;
  out.u_right.assign(n, -1.0);
  out.depth_m.assign(n, -1.0);
  if (n == 0 || right.keypoints.empty() || left.pyramid.empty()) return out;
  const int rows = left.pyramid[0].rows;
  std::vector<std::vector<int>> row_index(static_cast<std::size_t>(rows));
  for (std::size_t i = 0; i < right.keypoints.size(); ++i) {
    const cv::KeyPoint& kp = right.keypoints[i];
    const double r = options.row_band_px * right.scales[static_cast<std::size_t>(kp.octave)];
    const int lo = std::max(0, static_cast<int>(std::floor(static_cast<double>(kp.pt.y) - r))), hi = std::min(rows - 1, static_cast<int>(std::ceil(static_cast<double>(kp.pt.y) + r)));
    for (int y = lo; y <= hi; ++y) row_index[static_cast<std::size_t>(y)].push_back(static_cast<int>(i));
  }
  const double bf = camera.fx * camera.baseline_m;
  const double min_disparity = 0.0, max_disparity = bf / (options.min_depth_baselines * camera.baseline_m);
  const int w = options.window_half_size, L = options.search_half_range;
  std::vector<std::pair<double, std::size_t>> sad_of;
  std::vector<float> distances(static_cast<std::size_t>(2 * L + 1));
  for (std::size_t i = 0; i < n; ++i) {
    const cv::KeyPoint& kl = left.keypoints[i];
    const int y = static_cast<int>(std::lround(static_cast<double>(kl.pt.y)));
    if (y < 0 || y >= rows) continue;
    const double ul0 = static_cast<double>(kl.pt.x);
    const double u_min = ul0 - max_disparity, u_max = ul0 - min_disparity;
    if (u_max < 0.0) continue;
    int best = 256, best_j = -1;
    for (const int j : row_index[static_cast<std::size_t>(y)]) {
      const cv::KeyPoint& kr = right.keypoints[static_cast<std::size_t>(j)];
      if (kr.octave < kl.octave - 1 || kr.octave > kl.octave + 1) continue;
      if (static_cast<double>(kr.pt.x) < u_min || static_cast<double>(kr.pt.x) > u_max) continue;
      const int d = descriptor_distance(left.descriptors.ptr(static_cast<int>(i)), right.descriptors.ptr(j));
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (best_j < 0 || best >= options.max_descriptor_distance) continue;
    // SAD block matching on the keypoint's level around the descriptor match.
    const auto level = static_cast<std::size_t>(kl.octave);
    const double inv = 1.0 / left.scales[level];
    const cv::Mat& L_img = left.pyramid[level];
    const cv::Mat& R_img = right.pyramid[level];
    const int ul = static_cast<int>(std::lround(ul0 * inv)), vl = static_cast<int>(std::lround(static_cast<double>(kl.pt.y) * inv));
    const int ur0 = static_cast<int>(std::lround(static_cast<double>(right.keypoints[static_cast<std::size_t>(best_j)].pt.x) * inv));
    if (vl - w < 0 || vl + w >= L_img.rows || ul - w < 0 || ul + w >= L_img.cols) continue;
    if (ur0 - L - w < 0 || ur0 + L + w >= R_img.cols || vl + w >= R_img.rows) continue;
    const int center_l = L_img.at<uchar>(vl, ul);
    float best_sad = std::numeric_limits<float>::max();
    int best_inc = 0;
    for (int inc = -L; inc <= L; ++inc) {
      const int center_r = R_img.at<uchar>(vl, ur0 + inc);
      int sad = 0;
      for (int dy = -w; dy <= w; ++dy) {
        const uchar* pl = L_img.ptr<uchar>(vl + dy) + ul;
        const uchar* pr = R_img.ptr<uchar>(vl + dy) + ur0 + inc;
        for (int dx = -w; dx <= w; ++dx) sad += std::abs((pl[dx] - center_l) - (pr[dx] - center_r));
      }
      distances[static_cast<std::size_t>(inc + L)] = static_cast<float>(sad);
      if (static_cast<float>(sad) < best_sad) {
        best_sad = static_cast<float>(sad);
        best_inc = inc;
      }
    }
    if (best_inc == -L || best_inc == L) continue;
    const double d1 = distances[static_cast<std::size_t>(L + best_inc - 1)], d2 = distances[static_cast<std::size_t>(L + best_inc)],
                 d3 = distances[static_cast<std::size_t>(L + best_inc + 1)];
    const double denominator = 2.0 * (d1 + d3 - 2.0 * d2);
    if (!(denominator > 0.0)) continue;
    const double delta = (d1 - d3) / denominator;
    if (delta < -1.0 || delta > 1.0) continue;
    double u_right = left.scales[level] * (ur0 + best_inc + delta);
    double disparity = ul0 - u_right;
    if (disparity < min_disparity || disparity >= max_disparity) continue;
    if (disparity <= 0.0) {
      disparity = 0.01;
      u_right = ul0 - 0.01;
    }
    out.u_right[i] = u_right;
    out.depth_m[i] = bf / disparity;
    sad_of.emplace_back(best_sad, i);
  }
  if (sad_of.empty()) return out;
  std::sort(sad_of.begin(), sad_of.end());
  const double threshold = options.sad_outlier_factor * sad_of[sad_of.size() / 2].first;
  for (const auto& [sad, i] : sad_of) {
    if (sad > threshold) {
      out.u_right[i] = -1.0;
      out.depth_m[i] = -1.0;
    } else {
      ++out.matched;
    }
  }
  return out;
}

StereoMatches depth_from_rgbd(const std::vector<cv::KeyPoint>& keypoints, const std::vector<Eigen::Vector2d>& undistorted,
                              const cv::Mat& depth, const io::CameraCalibration& camera) {
  StereoMatches out;
  out.u_right.assign(keypoints.size(), -1.0);
  out.depth_m.assign(keypoints.size(), -1.0);
  const double bf = camera.fx * camera.virtual_baseline_m;
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const int u = static_cast<int>(std::lround(static_cast<double>(keypoints[i].pt.x))), v = static_cast<int>(std::lround(static_cast<double>(keypoints[i].pt.y)));
    if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
    const std::uint16_t raw = depth.at<std::uint16_t>(v, u);
    if (raw == 0) continue;
    const double z = raw / camera.depth_units_per_m;
    out.depth_m[i] = z;
    out.u_right[i] = undistorted[i].x() - bf / z;
    ++out.matched;
  }
  return out;
}

StereoRectifier::StereoRectifier(const io::StereoRig& rig, int width, int height) : width_(width), height_(height) {
  auto K = [](const io::CameraCalibration& c) { return cv::Matx33d(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1); };
  auto D = [](const io::CameraCalibration& c) { return std::vector<double>{c.k1, c.k2, c.p1, c.p2, c.k3}; };
  // x_right = R x_left + T.
  const core::SE3 T_right_left = rig.T_body_right.inverse() * rig.T_body_left;
  cv::Matx33d R;
  const Eigen::Matrix3d Re = T_right_left.rotation_matrix();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = Re(r, c);
  }
  const cv::Vec3d T(T_right_left.translation().x(), T_right_left.translation().y(), T_right_left.translation().z());
  cv::Mat R1, R2, P1, P2, Q;
  const cv::Size size(width, height);
  cv::stereoRectify(K(rig.left), D(rig.left), K(rig.right), D(rig.right), size, R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0.0, size);
  cv::initUndistortRectifyMap(K(rig.left), D(rig.left), R1, P1, size, CV_32FC1, map_left_x_, map_left_y_);
  cv::initUndistortRectifyMap(K(rig.right), D(rig.right), R2, P2, size, CV_32FC1, map_right_x_, map_right_y_);
  rectified_.fx = P1.at<double>(0, 0);
  rectified_.fy = P1.at<double>(1, 1);
  rectified_.cx = P1.at<double>(0, 2);
  rectified_.cy = P1.at<double>(1, 2);
  rectified_.width = width;
  rectified_.height = height;
  rectified_.baseline_m = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
  if (!(rectified_.baseline_m > 0.0)) throw std::invalid_argument("stereo rectification: the right camera is not to the right of the left one");
  Eigen::Matrix3d R1e;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R1e(r, c) = R1.at<double>(r, c);
  }
  // x_rectified = R1 x_left: the rectified frame's axes in the left frame are R1^T.
  T_left_rectified_ = core::SE3(core::SO3::from_matrix(R1e.transpose()), Eigen::Vector3d::Zero());
}

void StereoRectifier::rectify(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out) const {
  if (left.cols != width_ || left.rows != height_ || right.cols != width_ || right.rows != height_) {
    throw std::invalid_argument("stereo rectification: images of " + std::to_string(left.cols) + " x " + std::to_string(left.rows) +
                                " pixels, the calibration is for " + std::to_string(width_) + " x " + std::to_string(height_));
  }
  cv::remap(left, left_out, map_left_x_, map_left_y_, cv::INTER_LINEAR);
  cv::remap(right, right_out, map_right_x_, map_right_y_, cv::INTER_LINEAR);
}

std::string draw_features_png(const cv::Mat& gray, const std::vector<cv::KeyPoint>& keypoints,
                              const std::vector<signed char>& states, const std::string& caption) {
  cv::Mat color;
  cv::cvtColor(gray, color, cv::COLOR_GRAY2BGR);
  int counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const int state = i < states.size() ? std::clamp<int>(states[i], 0, 2) : 0;
    ++counts[state];
    const cv::Scalar colour = state == 2 ? cv::Scalar(0, 200, 0) : state == 1 ? cv::Scalar(255, 120, 0) : cv::Scalar(0, 0, 230);
    const cv::Point2f p = keypoints[i].pt;
    const float r = 2.0f + 1.5f * static_cast<float>(keypoints[i].octave);
    cv::rectangle(color, cv::Point2f(p.x - r, p.y - r), cv::Point2f(p.x + r, p.y + r), colour, 1, cv::LINE_AA);
  }
  const std::string text = caption + ": " + std::to_string(counts[2]) + " matched to the map (green), " + std::to_string(counts[1]) +
                           " stereo/depth only (blue), " + std::to_string(counts[0]) + " unmatched (red)";
  // The caption shrinks to fit narrow images (TUM's 640 px).
  double font = 0.5;
  int baseline = 0;
  while (font > 0.25 && cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline).width > color.cols - 16) font -= 0.05;
  cv::putText(color, text, cv::Point(8, 18), cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(color, text, cv::Point(8, 18), cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return encode_png(color);
}

}  // namespace cairn::vision
