#pragma once
/// \file
/// A camera calibration (io::CameraCalibration) from sensor_msgs/CameraInfo, read as ROS's
/// image_geometry::PinholeCameraModel reads it (the message definition's comments, REP 104):
///
/// * raw images: K = [fx 0 cx; 0 fy cy; 0 0 1] and D, for the "plumb_bob" model (k1, k2, t1, t2,
///   k3: OpenCV's k1 k2 p1 p2 k3; "rational_polynomial" with k4 = k5 = k6 = 0 is the same model);
/// * rectified images (a topic named image_rect or image_rect_..., image_proc's names): P's fx'
///   fy' cx' cy', no distortion;
/// * a rectified stereo pair: P of each camera, with the same fx' fy' cx' cy', and the right
///   camera's P[3] = Tx = -fx' * baseline (KITTI's P1 is written the same way). The pair counts
///   as rectified when both topics are image_rect... ones, or when both R are the identity and
///   both D zero (the images were rectified before they were recorded, as KITTI's); anything
///   else is refused: cairn does not rectify a bag's stereo pair (yet).

#include <string>

#include "cairn/bag/sensor_messages.hpp"
#include "cairn/io/image_sequence.hpp"

namespace cairn::vslam {

/// True when `image_topic` holds rectified images by image_proc's naming: its last name is
/// image_rect or image_rect_... (image_rect_color, image_rect_raw), after a /compressed suffix.
bool is_rectified_topic(const std::string& image_topic);

/// The camera of a monocular or RGB-D image topic (`image_topic`: which model, see above), sized
/// as the CameraInfo says. Throws io::ParseError(file, 0, "CameraInfo on <info_topic>: ...") for
/// a focal length that is not positive (an uncalibrated camera publishes zeros) or a distortion
/// model cairn does not undistort (equidistant, rational_polynomial with k4..k6).
io::CameraCalibration camera_from_camera_info(const bag::CameraInfo& info, const std::string& image_topic, const std::string& file,
                                              const std::string& info_topic);

/// The left camera of a rectified stereo pair, with the baseline -(P_right[3] - P_left[3]) / fx'.
/// Throws io::ParseError naming both topics when the pair is not rectified (see above), the P's
/// differ in fx', fy', cx' or cy', or the baseline is not positive.
io::CameraCalibration camera_from_stereo_camera_infos(const bag::CameraInfo& left, const bag::CameraInfo& right,
                                                      const std::string& left_image_topic, const std::string& right_image_topic,
                                                      const std::string& file, const std::string& left_info_topic,
                                                      const std::string& right_info_topic);

}  // namespace cairn::vslam
