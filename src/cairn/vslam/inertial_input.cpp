#include "cairn/vslam/inertial_input.hpp"

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/vision/features.hpp"

namespace cairn::vslam {

VisualInertialInput read_visual_inertial_input(const VisualInertialInputRequest& request, const io::ImageSequence& sequence,
                                               const vision::StereoRectifier* rectifier) {
  VisualInertialInput input;
  input.imu = inertial::read_imu_source(request.imu);
  if (!request.camera_extrinsic.empty()) {
    input.T_body_camera = inertial::read_euroc_T_BS(request.camera_extrinsic);
    input.camera_extrinsic = request.camera_extrinsic.string();
  } else if (sequence.rig) {
    input.T_body_camera = sequence.rig->T_body_left;
    input.camera_extrinsic = "the dataset's left camera (cam0/sensor.yaml T_BS)";
  } else {
    input.camera_extrinsic = "identity";
    input.imu.notes.push_back("no camera extrinsic (--camera-extrinsic, or an EuRoC cam0/sensor.yaml): the camera taken to be at "
                              "the IMU, with its axes (identity)");
  }
  // Rectification turns the left camera: VisualSlam sees the rectified one.
  if (rectifier != nullptr) {
    input.T_body_camera = input.T_body_camera * rectifier->T_left_rectified();
  }
  return input;
}

VisualSlamOptions with_imu(VisualSlamOptions options, const VisualInertialInput& input) {
  options.inertial.enabled = true;
  options.inertial.noise = input.imu.noise;
  options.inertial.T_body_camera = input.T_imu_camera();
  return options;
}

std::size_t feed_imu_until(VisualSlam& slam, const std::vector<inertial::ImuSample>& samples, std::size_t next, core::Timestamp time) {
  while (next < samples.size()) {
    slam.add_imu(samples[next]);
    if (!(samples[next++].stamp < time)) break;
  }
  return next;
}

}  // namespace cairn::vslam
