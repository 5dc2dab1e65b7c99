#include "cairn/vslam/camera_info_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "cairn/io/parse_error.hpp"

namespace cairn::vslam {
namespace {

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

bool all_zero(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return v == 0.0; });
}

bool is_identity(const std::array<double, 9>& R) {
  return R == std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1};
}

/// plumb_bob's k1 k2 t1 t2 k3 (D may stop early: the rest are 0); rational_polynomial's first
/// five when k4..k6 are 0. Returns a problem, or "" when the model is read.
std::string set_distortion(const bag::CameraInfo& info, io::CameraCalibration& c) {
  const std::vector<double>& D = info.D;
  if (all_zero(D)) return "";
  const bool plumb_bob = info.distortion_model == "plumb_bob" && D.size() <= 5;
  const bool rational = info.distortion_model == "rational_polynomial" && D.size() <= 8 &&
                        std::all_of(D.begin() + std::min<std::ptrdiff_t>(5, static_cast<std::ptrdiff_t>(D.size())), D.end(),
                                    [](double v) { return v == 0.0; });
  if (!plumb_bob && !rational) {
    return "distortion model '" + info.distortion_model + "' with " + std::to_string(D.size()) +
           " coefficients is not undistorted by cairn (plumb_bob is, and rational_polynomial with k4 = k5 = k6 = 0)";
  }
  double* coefficients[] = {&c.k1, &c.k2, &c.p1, &c.p2, &c.k3};
  for (std::size_t i = 0; i < std::min<std::size_t>(5, D.size()); ++i) *coefficients[i] = D[i];
  return "";
}

/// P's intrinsics (the rectified camera) or K's.
void set_intrinsics(const bag::CameraInfo& info, bool rectified, io::CameraCalibration& c) {
  c.fx = rectified ? info.P[0] : info.K[0];
  c.fy = rectified ? info.P[5] : info.K[4];
  c.cx = rectified ? info.P[2] : info.K[2];
  c.cy = rectified ? info.P[6] : info.K[5];
  c.width = static_cast<int>(std::min<std::uint32_t>(info.width, 1u << 30));
  c.height = static_cast<int>(std::min<std::uint32_t>(info.height, 1u << 30));
}

void check_focal_lengths(const io::CameraCalibration& c, const std::string& file, const std::string& info_topic, bool rectified) {
  if (!(c.fx > 0.0) || !(c.fy > 0.0) || !std::isfinite(c.fx) || !std::isfinite(c.fy)) {
    throw io::ParseError(file, 0, "CameraInfo on " + info_topic + ": " + (rectified ? "P" : "K") + " has fx " + number(c.fx) + ", fy " +
                                      number(c.fy) + ": not a calibrated camera (give the calibration with --calib FILE)");
  }
}

}  // namespace

bool is_rectified_topic(const std::string& image_topic) {
  std::string topic = image_topic;
  for (const char* suffix : {"/compressed", "/compressedDepth"}) {
    if (topic.ends_with(suffix)) topic.resize(topic.size() - std::string(suffix).size());
  }
  const std::string name = topic.substr(topic.rfind('/') + 1);  // npos + 1 == 0
  return name == "image_rect" || name.starts_with("image_rect_");
}

io::CameraCalibration camera_from_camera_info(const bag::CameraInfo& info, const std::string& image_topic, const std::string& file,
                                              const std::string& info_topic) {
  const bool rectified = is_rectified_topic(image_topic);
  io::CameraCalibration c;
  set_intrinsics(info, rectified, c);
  check_focal_lengths(c, file, info_topic, rectified);
  if (!rectified) {
    if (const std::string problem = set_distortion(info, c); !problem.empty()) {
      throw io::ParseError(file, 0, "CameraInfo on " + info_topic + ": " + problem + " (give an equivalent --calib FILE)");
    }
  }
  return c;
}

io::CameraCalibration camera_from_stereo_camera_infos(const bag::CameraInfo& left, const bag::CameraInfo& right,
                                                      const std::string& left_image_topic, const std::string& right_image_topic,
                                                      const std::string& file, const std::string& left_info_topic,
                                                      const std::string& right_info_topic) {
  const std::string pair = "CameraInfo on " + left_info_topic + " and " + right_info_topic + ": ";
  const bool named_rectified = is_rectified_topic(left_image_topic) && is_rectified_topic(right_image_topic);
  const bool recorded_rectified = is_identity(left.R) && is_identity(right.R) && all_zero(left.D) && all_zero(right.D);
  if (!named_rectified && !recorded_rectified) {
    throw io::ParseError(file, 0, pair + "the images are not rectified (R is not the identity or D is not zero), and cairn does not rectify "
                                         "a bag's stereo pair: record the image_rect topics, or track the left images alone "
                                         "(monocular) with --image-topic " + left_image_topic);
  }
  io::CameraCalibration c;
  set_intrinsics(left, true, c);
  check_focal_lengths(c, file, left_info_topic, true);
  if (right.P[0] != left.P[0] || right.P[5] != left.P[5] || right.P[2] != left.P[2] || right.P[6] != left.P[6]) {
    throw io::ParseError(file, 0, pair + "the two P differ in fx, fy, cx or cy (" + number(left.P[0]) + " " + number(left.P[5]) + " " +
                                      number(left.P[2]) + " " + number(left.P[6]) + " against " + number(right.P[0]) + " " +
                                      number(right.P[5]) + " " + number(right.P[2]) + " " + number(right.P[6]) +
                                      "): not a rectified stereo pair");
  }
  // As io::read_kitti_calibration: P_right[3] = Tx = -fx' * baseline (P_left[3] is 0 for the left camera).
  c.baseline_m = -(right.P[3] - left.P[3]) / c.fx;
  if (!std::isfinite(c.baseline_m) || !(c.baseline_m > 0.0)) {
    throw io::ParseError(file, 0, pair + "the right camera's P[3] = " + number(right.P[3]) + " gives a baseline of " + number(c.baseline_m) +
                                      " m; expected P[3] = -fx * baseline < 0 (the right camera right of the left one)");
  }
  return c;
}

}  // namespace cairn::vslam
