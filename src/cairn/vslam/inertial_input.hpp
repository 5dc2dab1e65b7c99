#pragma once
/// \file
/// The IMU of a `cairn vslam --imu` run (issue 40's input): the IMU as the user names it
/// (inertial/imu_source.hpp: samples, noise, time offset), the camera VisualSlam tracks in the
/// IMU's frame, and the readings fed to VisualSlam before each frame.
///
/// Frames: VisualSlam's body is the IMU (VisualInertialOptions::T_body_camera is the camera in the
/// IMU's frame), so T_imu_camera = T_body_imu^-1 T_body_camera from the two sensor.yaml T_BS
/// (EuRoC's: each sensor in one body frame). The camera is the one VisualSlam sees: for an
/// unrectified pair (EuRoC) the rectified left camera, turned from the original by the
/// rectifier's T_left_rectified.

#include <filesystem>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/inertial/imu_source.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::vision {
class StereoRectifier;
}

namespace cairn::vslam {

struct VisualInertialInputRequest {
  inertial::ImuSourceRequest imu;
  /// --camera-extrinsic: a sensor.yaml whose T_BS is the camera (left, or colour; for an
  /// unrectified pair the original left camera) in the body frame. Empty: the dataset's (EuRoC's
  /// cam0 sensor.yaml), else the identity (said in a note).
  std::filesystem::path camera_extrinsic;
};

struct VisualInertialInput {
  inertial::ImuSource imu;
  core::SE3 T_body_camera;      ///< the camera VisualSlam sees (rectified left) in the body frame
  std::string camera_extrinsic; ///< where T_body_camera came from: a file, "the dataset's cam0", or "identity"
  core::SE3 T_imu_camera() const { return imu.T_body_imu.inverse() * T_body_camera; }
};

/// Reads the IMU and the camera's extrinsic. Throws io::ParseError for bad files,
/// std::invalid_argument for a bad request.
VisualInertialInput read_visual_inertial_input(const VisualInertialInputRequest& request, const io::ImageSequence& sequence,
                                               const vision::StereoRectifier* rectifier);

/// `options` with the IMU on: the input's noise and camera extrinsic.
VisualSlamOptions with_imu(VisualSlamOptions options, const VisualInertialInput& input);

/// Feeds `slam` the readings from `next` on up to and including the first at or after `time`
/// (a frame's prediction needs a reading at or after it); returns the index of the first reading
/// not fed.
std::size_t feed_imu_until(VisualSlam& slam, const std::vector<inertial::ImuSample>& samples, std::size_t next, core::Timestamp time);

}  // namespace cairn::vslam
